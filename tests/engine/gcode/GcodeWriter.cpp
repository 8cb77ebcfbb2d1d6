// Tests of engine/gcode/GcodeWriter.h: unchanged programs come back byte for byte; re-fed
// programs read back to the same geometry within 1e-6 mm with the planned feeds.

#include "engine/gcode/GcodeWriter.h"
#include "engine/gcode/GcodeReader.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

using namespace engage;
using Catch::Matchers::Contains;

namespace {

Toolpath read(const std::string& text) {
  return readProgramText(text, "w.ngc");
}

/// Largest distance between the two paths sampled at the same arc lengths (every move,
/// rapids included), mm; the paths must have the same length within 1e-6 mm.
double pathDistance(const Toolpath& a, const Toolpath& b) {
  auto total = [](const Toolpath& t) {
    double s = 0.0;
    for (const Move& m : t.moves)
      s += moveLength(m);
    return s;
  };
  const double la = total(a);
  REQUIRE(std::abs(la - total(b)) < 1e-6);
  auto at = [](const Toolpath& t, double s) {
    for (const Move& m : t.moves) {
      const double l = moveLength(m);
      if (s <= l) return pointAt(m, l > 0 ? s / l : 1.0);
      s -= l;
    }
    return t.moves.back().end;
  };
  double worst = 0.0;
  for (int i = 0; i <= 5000; ++i)
    worst = std::max(worst, (at(a, la * i / 5000.0) - at(b, la * i / 5000.0)).norm());
  return worst;
}

FeedPlan unchanged(const Toolpath& t) {
  return FeedPlan(t.moves.size());
}

}  // namespace

TEST_CASE("an unchanged plan gives the program back byte for byte", "[gcode]") {
  for (const char* name : {"fusion360_pocket.nc", "linuxcnc_features.ngc", "inch_helix.ngc",
                           "lathe_turning_cycles.ngc"}) {
    std::ifstream in(std::string(ENGAGE_SOURCE_DIR "/data/gcode/dialects/") + name);
    std::stringstream s;
    s << in.rdbuf();
    const Toolpath t = readProgramText(s.str(), name);
    CHECK(writeProgram(s.str(), t, unchanged(t)) == s.str());
  }
}

TEST_CASE("a new feed on one line, and the original F restored on the next", "[gcode]") {
  const std::string src = "G21 G90\nG0 X0 Y0\nG1 X10 F500 (a)\nG1 X20\nG1 X30\nM2\n";
  const Toolpath t = read(src);
  FeedPlan plan = unchanged(t);
  plan[1] = {{1.0, 250.0}};  // G1 X10 at 250 mm/min
  const std::string out = writeProgram(src, t, plan);
  CHECK(out == "G21 G90\nG0 X0 Y0\nG1 X10 F250 (a)\nG1 X20 F500\nG1 X30\nM2\n");
  const Toolpath back = read(out);
  CHECK(back.moves[1].feed == 250.0);
  CHECK(back.moves[2].feed == 500.0);
  CHECK(back.moves[3].feed == 500.0);
  CHECK(pathDistance(t, back) < 1e-6);
}

TEST_CASE("a lathe cycle takes one new feed on its line", "[gcode][lathe]") {
  const std::string src =
      "G18 G21 F100\no1 sub\nG1 X5 Z0\nZ-10\nX10\no1 endsub\n"
      "G71 Q1 X10 Z2 I1 R0.3\nG1 X12\nM2\n";
  const Toolpath t = read(src);
  FeedPlan plan = unchanged(t);
  std::size_t cycleFeeds = 0;
  for (std::size_t i = 0; i < t.moves.size(); ++i)
    if (t.moves[i].line == 7 && t.moves[i].kind != MoveKind::Rapid) {
      plan[i] = {{1.0, 80.0}};
      ++cycleFeeds;
    }
  REQUIRE(cycleFeeds > 5);
  const std::string out = writeProgram(src, t, plan);
  CHECK(out ==
        "G18 G21 F100\no1 sub\nG1 X5 Z0\nZ-10\nX10\no1 endsub\n"
        "G71 Q1 X10 Z2 I1 R0.3 F80\nG1 X12 F100\nM2\n");
  const Toolpath back = read(out);
  REQUIRE(back.moves.size() == t.moves.size());
  for (std::size_t i = 0; i < back.moves.size(); ++i)
    if (back.moves[i].kind != MoveKind::Rapid)
      CHECK(back.moves[i].feed == (back.moves[i].line == 7 ? 80.0 : 100.0));
  CHECK(pathDistance(t, back) < 1e-6);
  // A plan that changes the feed within the cycle cannot be written on its one line.
  for (std::size_t i = 0; i < t.moves.size(); ++i)
    if (t.moves[i].line == 7 && t.moves[i].kind == MoveKind::Line) {
      plan[i] = {{1.0, 60.0}};
      break;
    }
  CHECK_THROWS_WITH(writeProgram(src, t, plan),
                    Contains("a canned cycle or spline line takes one feed"));
}

TEST_CASE("splitting lines and helices where the feed changes", "[gcode]") {
  const std::string src =
      "G21 G17 G90\nG0 X10 Y0 Z1\nG1 Z0 F300\n"
      "G3 X10 Y0 Z-3 I-10 J0 P3 F600 M8 (helix)\nG1 X25 Y7\nG2 X35 Y7 R5\nM2\n";
  const Toolpath t = read(src);
  FeedPlan plan = unchanged(t);
  plan[2] = {{0.1, 200.0}, {0.55, 400.0}, {1.0, 600.0}};  // the helix in three pieces
  plan[3] = {{0.5, 300.0}, {1.0, 450.0}};                 // the line in two
  plan[4] = {{0.25, 100.0}, {1.0, 600.0}};                // the R arc as two I/J arcs
  const std::string out = writeProgram(src, t, plan);
  INFO(out);
  const Toolpath back = read(out);
  REQUIRE(back.moves.size() == t.moves.size() + 2 + 1 + 1);
  CHECK(pathDistance(t, back) < 1e-6);
  // Feeds piece by piece; M8 and the comment stay on the helix's first line.
  CHECK(back.moves[2].feed == 200.0);
  CHECK(back.moves[3].feed == 400.0);
  CHECK(back.moves[4].feed == 600.0);
  CHECK(back.moves[5].feed == 300.0);
  CHECK(back.moves[6].feed == 450.0);
  CHECK(back.moves[7].feed == 100.0);
  CHECK(back.moves[8].feed == 600.0);
  CHECK_THAT(out, Contains("M8 (helix)"));
  // The first helix piece is 0.3 of three turns: less than one turn, no P; the second, 1.35 turns:
  // P2.
  CHECK(back.moves[2].turns == 1);
  CHECK(back.moves[3].turns == 2);
}

TEST_CASE("incremental inch programs split in their own units and modes", "[gcode]") {
  const std::string src = "G20 G91 G17\nG1 X1 Y1 F20\nG2 X1 Y-1 I1 J0\nG1 X-2\nM2\n";
  const Toolpath t = read(src);
  FeedPlan plan = unchanged(t);
  plan[0] = {{0.5, 10.0 * 25.4}, {1.0, 30.0 * 25.4}};
  plan[1] = {{0.5, 5.0 * 25.4}, {1.0, 20.0 * 25.4}};
  const std::string out = writeProgram(src, t, plan);
  INFO(out);
  const Toolpath back = read(out);
  CHECK(pathDistance(t, back) < 1e-6);
  CHECK(back.moves[0].feed == Approx(254.0));
  CHECK(back.moves[1].feed == Approx(762.0));
  CHECK(back.moves[2].feed == Approx(127.0));
  CHECK(back.moves[4].feed == Approx(508.0));  // restored F20
  CHECK_THAT(out, Contains("G1 X0.5 Y0.5 F10"));
}

TEST_CASE("inverse-time programs get an F per piece", "[gcode]") {
  const std::string src = "G21 G90 G93\nG1 X10 F60\nG1 X20 F30\nM2\n";
  const Toolpath t = read(src);
  FeedPlan plan = unchanged(t);
  plan[0] = {{0.5, 300.0}, {1.0, 1200.0}};  // 5 mm at 300 mm/min: F60; 5 mm at 1200: F240
  const std::string out = writeProgram(src, t, plan);
  CHECK(out == "G21 G90 G93\nG1 X5 F60\nG1 X10 F240\nG1 X20 F30\nM2\n");
}

TEST_CASE("moves that turn rotary axes: A/B/C at the split points, F scaled", "[gcode]") {
  // Hand values: a piece of fraction f at scale s runs f x (the move's minutes) / s.
  SECTION("units per minute: the F word times the scale, the axes on the move's line") {
    const std::string src = "G21 G90 G94\nG0 X0 Y0 Z5 A0 B0\nG1 X10 A30 B-15 F200\nM2\n";
    const Toolpath t = read(src);
    FeedPlan plan = unchanged(t);
    plan[1] = {{0.25, 1.0, 0.5}, {0.6, 1.0, 1.5}, {1.0, 1.0, 0.8}};
    const std::string out = writeProgram(src, t, plan);
    INFO(out);
    CHECK_THAT(out, Contains("G1 X2.5 A7.5 B-3.75 F100\nG1 X6 A18 B-9 F300\nG1 X10 A30 B-15 F160"));
    const Toolpath back = read(out);
    REQUIRE(back.moves.size() == 4);
    for (std::size_t k = 1; k < 4; ++k) {
      const double t1 = back.moves[k].end.x() / 10.0;  // X and the axes interpolate together
      CHECK(back.moves[k].rotaryEnd.x() == Approx(30.0 * t1).margin(1e-9));
      CHECK(back.moves[k].rotaryEnd.y() == Approx(-15.0 * t1).margin(1e-9));
    }
  }
  SECTION("inverse time: each piece's F is 1 / its duration") {
    // 10 mm at F2 (0.5 min): pieces 0.4 at scale 2 (0.1 min: F10), 0.6 at 0.5 (0.6 min:
    // F1.666667); then A alone turning 90 deg at F4 (0.25 min), halved at scale 4 and 1
    // (0.03125 and 0.125 min: F32 and F8).
    const std::string src = "G21 G90 G93\nG1 X10 A20 F2\nG1 A110 F4\nM2\n";
    const Toolpath t = read(src);
    FeedPlan plan = unchanged(t);
    plan[0] = {{0.4, 1.0, 2.0}, {1.0, 1.0, 0.5}};
    plan[1] = {{0.5, 1.0, 4.0}, {1.0, 1.0, 1.0}};
    const std::string out = writeProgram(src, t, plan);
    CHECK(out == "G21 G90 G93\nG1 X4 A8 F10\nG1 X10 A20 F1.666667\nG1 A65 F32\nG1 A110 F8\nM2\n");
  }
  SECTION("incremental, one piece, and the modal F restored after it") {
    const std::string src = "G21 G91 G94\nG1 X1 C10 F100\nG1 X1\nG93 G1 X1 F5\nG94 G1 X1\nM2\n";
    const Toolpath t = read(src);
    FeedPlan plan = unchanged(t);
    plan[0] = {{1.0, 1.0, 2.0}};  // one piece: the line keeps its words
    plan[2] = {{1.0, 1.0, 0.5}};  // a move that turns nothing takes a feed, not a scale
    CHECK_THROWS_WITH(writeProgram(src, t, plan), Contains("takes scaled pieces"));
    plan[2] = {{1.0, 2.5}};  // 1 mm at 2.5 mm/min: F2.5 in inverse time
    const std::string out = writeProgram(src, t, plan);
    // The edited G93 line's F would leak into the G94 line after it as its modal F: that
    // line gets the feed it was read with back, the G93 F5 taken as 5 mm/min.
    CHECK(out == "G21 G91 G94\nG1 X1 C10 F200\nG1 X1 F100\nG93 G1 X1 F2.5\nG94 G1 X1 F5\nM2\n");
    plan[0] = {{0.3, 1.0, 2.0}, {1.0, 1.0, 1.0}};
    const std::string split = writeProgram(src, t, plan);
    CHECK_THAT(split, Contains("G1 X0.3 C3 F200\nG1 X0.7 C7 F100\nG1 X1 F100"));
  }
}

TEST_CASE("under G43.5 the split points carry the tool's axis as I, J, K", "[gcode]") {
  // A head-bc machine (axis (-sin B cos C, -sin B sin C, cos B)). The move turns the tool from
  // +Z to (0, 0.5, sqrt(3)/2): B 0 -> 30, C 0 -> -90 (the nearer of B30 C-90 and B-30 C90, a
  // tie, the first). Half way B15 C-45: (-sin 15 cos 45, sin 15 sin 45, cos 15) =
  // (-0.1830127019, 0.1830127019, 0.9659258263); read back, the nearest angles for that axis
  // are B15 C-45 again.
  ReaderOptions o;
  MachineSetup m;
  m.name = "head.json";
  m.kinematics.type = Kinematics::Type::HeadBC;
  m.kinematics.pivotLength = 150.0;
  o.machine = m;
  const std::string src =
      "G21 G90 G94\nG0 X0 Y0 Z5\nG43.5 H1\nG1 X10 J0.5 K0.866025403784439 F200\nG49\nM2\n";
  const Toolpath t = readProgramText(src, "w5.ngc", o);
  REQUIRE(t.moves.size() == 2);
  FeedPlan plan = unchanged(t);
  plan[1] = {{0.5, 1.0, 0.5}, {1.0, 1.0, 1.5}};
  const std::string out = writeProgram(src, t, plan);
  INFO(out);
  CHECK_THAT(out, Contains("G1 X5 I-0.183012702 J0.183012702 K0.965925826 F100\n"
                           "G1 X10 I0 J0.5 K0.866025404 F300\n"));
  const Toolpath back = readProgramText(out, "w5.ngc", o);
  REQUIRE(back.moves.size() == 3);
  CHECK((back.moves[1].rotaryEnd - Eigen::Vector3d(0.0, 15.0, -45.0)).norm() < 1e-6);
  CHECK((back.moves[2].rotaryEnd - t.moves[1].rotaryEnd).norm() < 1e-6);  // (9 digits written)
}

TEST_CASE("programs that do not run line by line cannot be re-fed in place", "[gcode]") {
  const std::string src = "G21 F100\no1 repeat [2]\nG91 G1 X1\no1 endrepeat\nM2\n";
  const Toolpath t = read(src);
  FeedPlan plan = unchanged(t);
  plan[0] = {{1.0, 50.0}};
  CHECK_THROWS_WITH(writeProgram(src, t, plan), Contains("w.ngc:3: this line runs again"));
  plan = unchanged(t);
  plan.pop_back();
  CHECK_THROWS_WITH(writeProgram(src, t, plan), Contains("feed plan has 1 entries for 2 moves"));
}

TEST_CASE("threading and probing feeds are the controller's and stay as they are", "[gcode]") {
  const std::string src = "G21 S500 M3 F100\nG1 X10\nG33 Z-5 K1\nG38.2 Z-20\nM2\n";
  const Toolpath t = read(src);
  FeedPlan plan = unchanged(t);
  plan[0] = {{1.0, 150.0}};  // the G1 line may change
  CHECK(writeProgram(src, t, plan) ==
        "G21 S500 M3 F100\nG1 X10 F150\nG33 Z-5 K1\n"
        "G38.2 Z-20 F100\nM2\n");
  for (const std::size_t fixed : {std::size_t{1}, std::size_t{2}}) {
    plan = unchanged(t);
    plan[fixed] = {{1.0, 80.0}};
    CHECK_THROWS_WITH(writeProgram(src, t, plan),
                      Contains("is not the F word's; engage cannot change it"));
  }
}
