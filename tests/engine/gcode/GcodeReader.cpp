// Tests of engine/gcode/GcodeReader.h: LinuxCNC's interpretation (golden files made with
// LinuxCNC's rs274 by scripts/compare_linuxcnc.py), semantics checked by hand, and errors.

#include "engine/gcode/GcodeReader.h"
#include "cutters/Numbers.h"
#include "engine/gcode/GcodeError.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

using namespace engage;
using Catch::Matchers::Contains;

namespace {

// Hand-computed positions are exact decimal numbers; 1e-9 mm is round-off.
constexpr double kExact = 1e-9;

Toolpath run(const std::string& text, const ReaderOptions& options = {}) {
  return readProgramText(text, "test.ngc", options);
}

std::vector<Move> moves(const std::string& text) {
  return run(text).moves;
}

void checkPoint(const Eigen::Vector3d& p, double x, double y, double z, double tol = kExact) {
  CHECK(p.x() == Approx(x).margin(tol));
  CHECK(p.y() == Approx(y).margin(tol));
  CHECK(p.z() == Approx(z).margin(tol));
}

/// Message of the GcodeError a program throws ("" when it does not throw).
std::string errorOf(const std::string& text, const ReaderOptions& options = {}) {
  try {
    run(text, options);
  } catch (const GcodeError& e) {
    return e.what();
  }
  return "";
}

struct GoldenMove {
  std::string kind;
  Eigen::Vector3d end{0, 0, 0};
  Eigen::Vector3d center{0, 0, 0};
  int turns = 0;
};

std::vector<GoldenMove> readGolden(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::string line;
  std::getline(in, line);  // header
  std::vector<GoldenMove> out;
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ','))
      c.push_back(cell);
    c.resize(9);
    GoldenMove g;
    g.kind = c[0];
    if (g.kind != "spline") g.end = {std::stod(c[1]), std::stod(c[2]), std::stod(c[3])};
    if (g.kind == "arc") {
      g.center = {std::stod(c[4]), std::stod(c[5]), std::stod(c[6])};
      g.turns = std::stoi(c[8]);
    }
    out.push_back(g);
  }
  return out;
}

/// Moves without zero-length rapids and lines (LinuxCNC's output drops none, ours neither;
/// the comparison script drops them on both sides).
std::vector<Move> withoutZeroLength(const std::vector<Move>& in) {
  std::vector<Move> out;
  Eigen::Vector3d pos(0, 0, 0);
  for (const Move& m : in) {
    if ((m.kind == MoveKind::Rapid || m.kind == MoveKind::Line) &&
        (m.end - pos).cwiseAbs().maxCoeff() < 1e-9)
      continue;
    out.push_back(m);
    pos = m.end;
  }
  return out;
}

}  // namespace

TEST_CASE("programs in the dialects users bring interpret as LinuxCNC's rs274 does", "[gcode]") {
  // Goldens: LinuxCNC 2.9 rs274 output (4 decimals of the program unit), converted to mm in
  // machine coordinates. Tolerance 0.002 mm: the issue's bound, above rs274's rounding
  // (0.00005 in = 0.00127 mm).
  const std::string data = ENGAGE_SOURCE_DIR "/data/gcode/";
  const std::string golden = ENGAGE_SOURCE_DIR "/tests/data/linuxcnc-golden/";
  ReaderOptions options;
  options.toolTable = data + "linuxcnc/tools.tbl";
  options.toolTableInch = true;  // rs274 without an INI file reads tool tables in inches
  // fanuc_subprogram: a Haas-style program with an M98 P L subprogram after its M30.
  // compensation/: cutter radius compensation (G41/G42, G41.1/G42.1, G40) on both sides,
  // outside and inside corners of lines and arcs, an arc entry, G91, the XZ plane.
  for (const char* path :
       {"dialects/fusion360_pocket.nc", "dialects/freecad_profile.ngc",
        "dialects/grbl_engrave.gcode", "dialects/inch_helix.ngc", "dialects/linuxcnc_features.ngc",
        "dialects/linuxcnc_probe_tap.ngc", "dialects/lathe_diameter_thread.ngc",
        "dialects/lathe_turning_cycles.ngc", "dialects/fanuc_subprogram.nc",
        "compensation/profile_mm.ngc", "compensation/entry_xz_mm.ngc"}) {
    INFO(path);
    const std::string name = std::string(path).substr(std::string(path).find('/') + 1);
    const std::string stem = name.substr(0, name.find('.'));
    const auto expected = readGolden(golden + stem + ".csv");
    const auto got = withoutZeroLength(readProgram(data + path, options).moves);
    REQUIRE(got.size() == expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      INFO("move " << i + 1 << " (line " << got[i].line << ")");
      CHECK(std::string(moveKindName(got[i].kind)) == expected[i].kind);
      if (expected[i].kind == "spline") continue;  // rs274 prints no spline end point
      CHECK((got[i].end - expected[i].end).cwiseAbs().maxCoeff() <= 0.002);
      if (expected[i].kind == "arc") {
        CHECK((got[i].center - expected[i].center).cwiseAbs().maxCoeff() <= 0.002);
        CHECK(got[i].turns == expected[i].turns);
      }
    }
  }
}

TEST_CASE("a lathe cycle reads its profile as LinuxCNC does", "[gcode][lathe]") {
  // LinuxCNC runs the profile subroutine's control lines and assignments and tracks the
  // profile's points in #<_x>, #<_z> (#5420-#5422) while it reads them.
  const auto m = moves(
      "G18 G21 F100\nG0 X20 Z5\no10 sub\nG1 X5 Z0\no11 repeat [2]\n"
      "G1 X[#<_x> + 1] Z[#<_z> - 3]\no11 endrepeat\nG1 X12 Z-15\no10 endsub\n"
      "G71 Q10 X14 Z2 D0 I1 R0.3\nX30\nM2\n");
  checkPoint(m[0].end, 20, 0, 5);
  checkPoint(m[1].end, 14, 0, 2);  // the rapid to the cycle's start point comes first
  // By hand, the profile is (X5 Z0) (X6 Z-3) (X7 Z-6) (X12 Z-15): a pass at X ends on the last
  // segment at Z = -6 - 1.8 (X - 7), or at Z-15 where X is above the profile.
  std::map<int, double> passEnd;
  for (std::size_t i = 1; i < m.size(); ++i)
    if (m[i].kind == MoveKind::Line && m[i].line == 10 &&
        std::abs(m[i].end.x() - m[i - 1].end.x()) < kExact)
      passEnd.emplace(static_cast<int>(std::lround(m[i].end.x())), m[i].end.z());
  REQUIRE(passEnd.size() >= 6);
  CHECK(passEnd.at(14) == Approx(-15).margin(kExact));
  CHECK(passEnd.at(12) == Approx(-15).margin(kExact));
  CHECK(passEnd.at(11) == Approx(-6 - 1.8 * 4).margin(kExact));
  CHECK(passEnd.at(9) == Approx(-6 - 1.8 * 2).margin(kExact));
  // Afterwards the last cycle move's mode (G1) is in effect, at the cycle line's feed.
  CHECK(m.back().kind == MoveKind::Line);
  checkPoint(m.back().end, 30, 0, -15);
  CHECK(m.back().feed == Approx(100));
}

TEST_CASE("lathe cycles in diameter mode: X words are diameters, I stays a radius",
          "[gcode][lathe]") {
  const auto m = moves(
      "G18 G21 G7 F100\no1 sub\nG1 X10 Z0\nZ-10\nX20\no1 endsub\n"
      "G71 Q1 X24 Z2 D0 I1 R0.5\nM2\n");
  // By hand: radius 12 down to the profile at radius 5, passes 1 apart (radius), each to Z-10.
  std::vector<double> passes;
  for (std::size_t i = 1; i < m.size(); ++i)
    if (m[i].kind == MoveKind::Line && std::abs(m[i].end.z() + 10) < kExact &&
        std::abs(m[i].end.x() - m[i - 1].end.x()) < kExact)
      passes.push_back(m[i].end.x());
  CHECK(passes == std::vector<double>{12, 11, 10, 9, 8, 7, 6, 5});
}

TEST_CASE("probing, spindle-synchronised motion and lathe diameter mode", "[gcode]") {
  SECTION("G38.x runs to the target and backs off 0.254 mm; #5061-#5063 hold the target") {
    // rs274 (LinuxCNC's stand-alone interpreter) without a part: the probe reaches its
    // target, #5070 = 0 (no contact), and it stops 0.254 mm (0.010 in) back towards the start.
    const auto m = moves(
        "G21 F50\nG0 X3 Y4 Z10\nG38.2 Z0\nG1 X#5061 Y[#5062 + #5070] Z#5063\n"
        "G20\nG38.3 X[#5420 + 1] F2\nM2\n");
    REQUIRE(m.size() == 6);
    checkPoint(m[1].end, 3, 4, 0);
    checkPoint(m[2].end, 3, 4, 0.254);
    CHECK(m[1].feedSource == FeedSource::Probe);
    CHECK(m[1].feed == Approx(50.0));
    checkPoint(m[3].end, 3, 4, 0);  // the parameters: the target, no contact
    checkPoint(m[4].end, 3 + 25.4, 4, 0);
    checkPoint(m[5].end, 3 + 25.4 - 0.254, 4, 0);  // 0.010 in back
  }
  SECTION("G33 feeds at K x S; G33.1 taps in and back out") {
    const auto m = moves("G21 S400 M3\nG0 X1 Y1 Z2\nG33 Z-10 K1.5\nG33.1 Z-20 K1\nM2\n");
    REQUIRE(m.size() == 4);
    CHECK(m[1].feed == Approx(600.0));  // 1.5 mm/rev x 400 rpm
    CHECK(m[1].feedSource == FeedSource::Spindle);
    checkPoint(m[2].end, 1, 1, -20);
    checkPoint(m[3].end, 1, 1, -10);  // back where the tap started
    CHECK(m[3].feed == Approx(400.0));
  }
  SECTION("G7 reads X words as diameters (arc centres stay radii); G8 as radii") {
    const auto m = moves(
        "G18 G21 G7 F100\nG0 X40 Z0\nG1 X20\nG91 G1 X-4\nG90 G2 X4 Z-4 I-3 K-2\n"
        "G8 G1 X20\nG7 G92 X10\nG1 X20\nM2\n");
    checkPoint(m[0].end, 20, 0, 0);
    checkPoint(m[1].end, 10, 0, 0);
    checkPoint(m[2].end, 8, 0, 0);  // an increment of 4 on the diameter
    checkPoint(m[3].end, 2, 0, -4);
    checkPoint(m[3].center, 5, 0, -2);
    checkPoint(m[4].end, 20, 0, -4);  // G8 on the line itself: a radius
    // G92 X10 under G7 at radius 20: program radius 5, offset 15; X20 -> radius 10 + 15.
    checkPoint(m[5].end, 25, 0, -4);
  }
}

TEST_CASE("an arc's end off its circle: within LinuxCNC's 0.005 mm (0.0005 in), or refused",
          "[gcode]") {
  // About I5 J0 from the origin: to end (10, y) the radius is sqrt(25 + y^2), 0.004 mm more
  // than 5 for y = 0.2, 0.00624 mm more for y = 0.25.
  CHECK(errorOf("G21 G17 G90\nG2 X10 Y0.2 I5 J0 F100\n").empty());
  CHECK_THAT(errorOf("G21 G17 G90\nG2 X10 Y0.25 I5 J0 F100\n"),
             Contains("expected the arc's end on its circle"));
  // In inches the same in tenths: 0.0004 in more for Y0.02 about I0.5, 0.000624 for Y0.025.
  CHECK(errorOf("G20 G17 G90\nG2 X1 Y0.02 I0.5 J0 F10\n").empty());
  CHECK_THAT(errorOf("G20 G17 G90\nG2 X1 Y0.025 I0.5 J0 F10\n"),
             Contains("expected the arc's end on its circle"));
}

TEST_CASE("units, distance modes and feeds", "[gcode]") {
  SECTION("G20 converts lengths and feeds to mm where they are read") {
    const auto m = moves("G20 G90\nG1 X1 Y-0.5 F10\nM2\n");
    checkPoint(m[0].end, 25.4, -12.7, 0.0);
    CHECK(m[0].feed == Approx(254.0).epsilon(1e-12));
  }
  SECTION("G91 adds to the current position") {
    const auto m = moves("G21 G0 X10 Y10\nG91 G0 X5 Y-2 Z1\nX1\nM2\n");
    checkPoint(m[1].end, 15, 8, 1);
    checkPoint(m[2].end, 16, 8, 1);
  }
  SECTION("G93 inverse time: feed = length x F; G95: F x S") {
    const auto m = moves("G21 G93 G1 X10 F2\nG94 G1 X20 F300\nS1000 M3 G95 G1 X30 F0.1\nM2\n");
    CHECK(m[0].feed == Approx(20.0).epsilon(1e-12));  // 10 mm in 1/2 min
    CHECK(m[1].feed == Approx(300.0).epsilon(1e-12));
    CHECK(m[2].feed == Approx(100.0).epsilon(1e-12));  // 0.1 mm/rev x 1000 rpm
    CHECK(m[2].spindleRpm == Approx(1000.0));
  }
  SECTION("a line's parameter reads see the values before its assignments") {
    const auto m = moves("#1=1\n#1=5 #2=#1\nG0 X#2 Y#1\nM2\n");
    checkPoint(m[0].end, 1, 5, 0);
  }
  SECTION("expressions, functions and operator precedence") {
    // 2 + 3 * 4**2 = 50; -7 MOD 3 = 2 (LinuxCNC's modulus is non-negative); ATAN[1]/[1] = 45
    // degrees; ROUND[2.5] = 3; FIX[-2.5] = -3; FUP[2.1] = 3; [1 EQ 1.00001] is true (0.0001
    // tolerance); SIN[30] = 0.5.
    const auto m = moves(
        "G0 X[2+3*4**2] Y[-7 MOD 3] Z[ATAN[1]/[1]]\n"
        "G0 X[ROUND[2.5]] Y[FIX[-2.5]] Z[FUP[2.1]]\n"
        "G0 X[1 EQ 1.00001] Y[SIN[30]] Z[EXISTS[#<nope>]]\nM2\n");
    checkPoint(m[0].end, 50, 2, 45);
    checkPoint(m[1].end, 3, -3, 3);
    checkPoint(m[2].end, 1, 0.5, 0, 1e-12);
  }
  SECTION("comments, N words, block delete, %, spaces inside numbers") {
    const auto m = moves("%\nN10 G0 X1 (move) ; tail\n/G0 X5\nG 0 X 1 2 . 5\n%\nG0 X99\n");
    REQUIRE(m.size() == 3);
    checkPoint(m[1].end, 5, 0, 0);  // block delete is off by default, as in LinuxCNC
    checkPoint(m[2].end, 12.5, 0, 0);
    ReaderOptions skip;
    skip.blockDelete = true;
    CHECK(run("G0 X1\n/G0 X5\nM2\n", skip).moves.size() == 1);
  }
}

TEST_CASE("arcs: R form, centres, helices, planes", "[gcode]") {
  SECTION("G3 with positive R takes the short way: centre left of the chord") {
    // (0,0) -> (10,0), R 10: centre (5, sqrt(75)), sweep +60 deg.
    const auto m = moves("G0 X0 Y0\nG3 X10 Y0 R10 F100\nM2\n");
    checkPoint(m[1].center, 5, std::sqrt(75.0), 0);
    CHECK(arcSweep(m[1]) == Approx(kPi / 3).epsilon(1e-12));
  }
  SECTION("negative R takes the long way") {
    const auto m = moves("G0 X0 Y0\nG3 X10 Y0 R-10 F100\nM2\n");
    checkPoint(m[1].center, 5, -std::sqrt(75.0), 0);
    CHECK(arcSweep(m[1]) == Approx(2 * kPi - kPi / 3).epsilon(1e-12));
  }
  SECTION("helix with P turns: two full turns and 3 mm down") {
    const auto m = moves("G0 X10 Y0 Z0\nG3 X10 Y0 Z-3 I-10 J0 P2 F100\nM2\n");
    CHECK(m[1].turns == 2);
    CHECK(arcSweep(m[1]) == Approx(4 * kPi).epsilon(1e-12));
    CHECK(moveLength(m[1]) == Approx(std::hypot(40 * kPi, 3.0)).epsilon(1e-12));
  }
  SECTION("G90.1 absolute centres; G2 clockwise is negative") {
    const auto m = moves("G0 X10 Y0\nG90.1 G2 X0 Y-10 I0 J0 F100\nM2\n");
    checkPoint(m[1].center, 0, 0, 0);
    CHECK(m[1].turns == -1);
    CHECK(arcSweep(m[1]) == Approx(-kPi / 2).epsilon(1e-12));
  }
  SECTION("G18 arcs turn about +Y: G3 from (0,0,0) around (5,0,0) passes z = +5") {
    const auto m = moves("G0 X0 Y0 Z0\nG18 G3 X10 Z0 I5 K0 F100\nM2\n");
    checkPoint(pointAt(m[1], 0.5), 5, 0, 5);
  }
}

TEST_CASE("offsets and coordinate systems", "[gcode]") {
  SECTION("G10 L2 and G55: machine = program + offset") {
    const auto m = moves("G10 L2 P2 X100 Y50 Z-5\nG55 G0 X1 Y2 Z3\nG54 G0 X1\nM2\n");
    checkPoint(m[0].end, 101, 52, -2);
    checkPoint(m[1].end, 1, 52, -2);
  }
  SECTION("G92 makes the current point the given one; G92.1 cancels") {
    const auto m = moves("G0 X10 Y10\nG92 X0 Y0\nG0 X5 Y5\nG92.1\nG0 X5\nM2\n");
    checkPoint(m[1].end, 15, 15, 0);
    checkPoint(m[2].end, 5, 15, 0);
  }
  SECTION("G53 and G28 position the spindle; the tip is one tool length lower") {
    // Tool 1: 10 mm. G43 at Z 20 lowers the tip to 10 without motion; G53 Z0 puts the tip at -10.
    ReaderOptions o;
    o.toolTable = ENGAGE_SOURCE_DIR "/tests/data/tools_mm.tbl";
    const auto m = run("G0 Z20\nT1 M6\nG43 H1\nG0 X1\nG53 G0 Z0\nG28\nM2\n", o).moves;
    checkPoint(m[1].end, 1, 0, 10);
    checkPoint(m[2].end, 1, 0, -10);
    checkPoint(m[3].end, 0, 0, -10);
  }
}

TEST_CASE("canned cycles as LinuxCNC expands them", "[gcode]") {
  // G98 G81 from Z 5, R 1, Z -3: over the hole at 5, down to R, feed to -3, back to 5.
  // G99 G83 with Q 3: pecks at -2, -5, -8, each followed by a rapid to R and a rapid back to
  // 0.254 mm above the last depth; last feed to -10; retract to R.
  const auto m = moves("G0 X0 Y0 Z5\nG98 G81 X10 Y10 Z-3 R1 F100\nG99 G83 X20 Z-10 R1 Q3\nM2\n");
  const std::vector<std::tuple<MoveKind, double, double, double>> expected = {
      {MoveKind::Rapid, 0, 0, 5},        {MoveKind::Rapid, 10, 10, 5},
      {MoveKind::Rapid, 10, 10, 1},      {MoveKind::Line, 10, 10, -3},
      {MoveKind::Rapid, 10, 10, 5},      {MoveKind::Rapid, 20, 10, 5},
      {MoveKind::Rapid, 20, 10, 1},      {MoveKind::Line, 20, 10, -2},
      {MoveKind::Rapid, 20, 10, 1},      {MoveKind::Rapid, 20, 10, -1.746},
      {MoveKind::Line, 20, 10, -5},      {MoveKind::Rapid, 20, 10, 1},
      {MoveKind::Rapid, 20, 10, -4.746}, {MoveKind::Line, 20, 10, -8},
      {MoveKind::Rapid, 20, 10, 1},      {MoveKind::Rapid, 20, 10, -7.746},
      {MoveKind::Line, 20, 10, -10},     {MoveKind::Rapid, 20, 10, 1}};
  REQUIRE(m.size() == expected.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    INFO("move " << i);
    CHECK(m[i].kind == std::get<0>(expected[i]));
    checkPoint(m[i].end, std::get<1>(expected[i]), std::get<2>(expected[i]),
               std::get<3>(expected[i]));
  }
}

TEST_CASE("subroutines, loops and conditionals", "[gcode]") {
  const auto m = moves(
      "o<go> sub\n G0 X#1 Y#2\n o<go> return [#1 + #2]\no<go> endsub\n"
      "o<go> call [1] [2]\nG0 Z#<_value>\n"                                 // Z 3
      "#1 = 0\no1 while [#1 LT 3]\n #1 = [#1 + 1]\n G0 X#1\no1 endwhile\n"  // X 1, 2, 3
      "o2 repeat [2]\n G91 G0 Y1\n G90\no2 endrepeat\n"                     // Y 3, 4
      "o3 if [#1 EQ 3]\n G0 Z10\no3 elseif [1]\n G0 Z20\no3 else\n G0 Z30\no3 endif\n"
      "#2 = 0\no4 do\n #2 = [#2 + 1]\n o5 if [#2 EQ 2]\n  o4 continue\n o5 endif\n"
      " o6 if [#2 EQ 4]\n  o4 break\n o6 endif\n G0 X[#2 * 10]\no4 while [#2 LT 9]\nM2\n");
  REQUIRE(m.size() == 10);
  checkPoint(m[0].end, 1, 2, 0);
  checkPoint(m[1].end, 1, 2, 3);
  CHECK(m[2].end.x() == 1.0);
  CHECK(m[4].end.x() == 3.0);
  CHECK(m[6].end.y() == Approx(4.0));
  CHECK(m[7].end.z() == 10.0);
  CHECK(m[8].end.x() == 10.0);  // #2 = 1; 2 continues; 3 prints 30; 4 breaks
  CHECK(m[9].end.x() == 30.0);
}

TEST_CASE("rotary and UVW words stay out of the XYZ path, marked on the move", "[gcode]") {
  const auto m = moves("G0 X1 A90\nG1 X2 F100\nG0 B45\nM2\n");
  REQUIRE(m.size() == 3);
  checkPoint(m[0].end, 1, 0, 0);
  CHECK(m[0].otherAxes);
  CHECK_FALSE(m[1].otherAxes);
  CHECK(m[2].otherAxes);
  checkPoint(m[2].end, 2, 0, 0);  // an A/B-only move keeps X, Y, Z
  // A word that does not move its axis (posts write A0 on 3-axis programs) marks nothing; in
  // G91 a zero increment neither.
  const auto still = moves("G0 X1 A0\nG1 X2 A0 F100\nG1 X3 A5\nG91 G1 X1 A0\nM2\n");
  REQUIRE(still.size() == 4);
  CHECK_FALSE(still[0].otherAxes);
  CHECK_FALSE(still[1].otherAxes);
  CHECK(still[2].otherAxes);
  CHECK_FALSE(still[3].otherAxes);
}

TEST_CASE("rotary positions ride on each move, and a machine refuses the axes it lacks",
          "[gcode]") {
  const auto m = moves("G0 X1 A90\nG1 X2 F100\nG91 G1 A-30 C15\nG90 G93 G1 X3 B10 F4\nM2\n");
  REQUIRE(m.size() == 4);
  checkPoint(m[0].rotaryStart, 0, 0, 0);
  checkPoint(m[0].rotaryEnd, 90, 0, 0);
  checkPoint(m[1].rotaryStart, 90, 0, 0);  // held
  checkPoint(m[1].rotaryEnd, 90, 0, 0);
  checkPoint(m[2].rotaryEnd, 60, 0, 15);  // incremental
  checkPoint(m[3].rotaryEnd, 60, 10, 15);
  CHECK(m[3].minutes == Approx(0.25));  // inverse time: 1 / F
  CHECK(m[1].minutes == 0.0);
  // On a table-A machine a B word that moves is an error at its column.
  ReaderOptions o;
  MachineSetup machine;
  machine.name = "fourth.json";
  machine.kinematics.type = Kinematics::Type::TableA;
  o.machine = machine;
  CHECK_THROWS_WITH(readProgramText("G0 X1 A90\nG0 X2 B5\nM2\n", "b.ngc", o),
                    Catch::Matchers::Contains("b.ngc:2:7: expected the rotary axes of this machine "
                                              "only, A (table-a in fourth.json), found B"));
  CHECK(readProgramText("G0 X1 A90 B0\nM2\n", "b0.ngc", o).kinematics.type ==
        Kinematics::Type::TableA);  // (a B word that stays put is no motion)
}

TEST_CASE("headers as Fanuc and Haas posts write them", "[gcode]") {
  // A program number after the '%', and G80 beside a motion code on one line.
  const Toolpath p = run("%\nO1001 (PART)\nG00 G17 G21 G40 G49 G80 G90\nX5 Y5\nG1 X10 F100\n%\n");
  REQUIRE(p.moves.size() == 2);
  CHECK(p.moves[0].kind == MoveKind::Rapid);  // G0 is the mode, G80 cancelled the cycle
  checkPoint(p.moves[0].end, 5, 5, 0);
  CHECK(p.latheLine == 0);
  // An O-word with a keyword missing is still an error.
  CHECK_THAT(errorOf("o100 cal\n"), Contains("expected an O-word label and keyword"));
}

TEST_CASE("a lathe program says so", "[gcode]") {
  const Toolpath p = run("G18 G21 G90\nG7\nG0 X20 Z2\nG1 Z-10 F100\nM2\n");
  CHECK(p.latheLine == 2);
  CHECK(p.lathe == "G7, lathe diameter mode");
}

TEST_CASE("splines are flattened within 0.001 mm", "[gcode]") {
  const auto m = moves("G0 X0 Y0\nG1 F100\nG5 X10 Y0 I2 J5 P-2 Q5\nM2\n");
  REQUIRE(m[1].kind == MoveKind::Spline);
  // Closed-form cubic Bezier: P0 (0,0), P1 (2,5), P2 (8,5), P3 (10,0). Every curve point lies
  // within 0.001 mm (+ round-off) of the polyline.
  auto bezier = [](double t) {
    const double u = 1 - t;
    return Eigen::Vector2d(3 * u * u * t * 2 + 3 * u * t * t * 8 + t * t * t * 10,
                           3 * u * u * t * 5 + 3 * u * t * t * 5);
  };
  std::vector<Eigen::Vector2d> poly{{0, 0}};
  for (const auto& p : m[1].points)
    poly.emplace_back(p.x(), p.y());
  double worst = 0.0;
  for (int i = 0; i <= 2000; ++i) {
    const Eigen::Vector2d q = bezier(i / 2000.0);
    double best = 1e9;
    for (std::size_t k = 0; k + 1 < poly.size(); ++k) {
      const Eigen::Vector2d d = poly[k + 1] - poly[k];
      const double t = std::clamp((q - poly[k]).dot(d) / d.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (poly[k] + t * d - q).norm());
    }
    worst = std::max(worst, best);
  }
  CHECK(worst <= 0.001 + 1e-9);
  checkPoint(m[1].end, 10, 0, 0);
}

TEST_CASE("cutter radius compensation: the tool a radius to the side, corners as LinuxCNC",
          "[gcode][comp]") {
  // Hand-computed: a 10 mm tool (G41.1 D10, r = 5) from the origin along +X to X20, then up.
  {
    INFO("left: the entry, then an inside corner");
    const auto m = moves(
        "G21 G17 F100\nG0 X0 Y0\nG41.1 D10 G1 X20 Y0\nG1 X20 Y20\n"
        "G40 G1 X30 Y30\nM2\n");
    REQUIRE(m.size() == 4);
    // The entry ends a radius left of X20 Y0, moved back to where the two offset lines meet.
    checkPoint(m[1].end, 15, 5, 0);
    checkPoint(m[2].start, 15, 5, 0);
    checkPoint(m[2].end, 15, 20, 0);
    // After G40 the next move goes from the offset point to its programmed end.
    checkPoint(m[3].start, 15, 20, 0);
    checkPoint(m[3].end, 30, 30, 0);
  }
  {
    INFO("right: an outside corner gets an arc about the programmed corner");
    const auto m =
        moves("G21 G17 F100\nG0 X0 Y0\nG42.1 D10 G1 X20 Y0\nG1 X20 Y20\nG40 G1 X30 Y30\n");
    REQUIRE(m.size() == 5);
    checkPoint(m[1].end, 20, -5, 0);
    REQUIRE(m[2].kind == MoveKind::Arc);
    checkPoint(m[2].start, 20, -5, 0);
    checkPoint(m[2].end, 25, 0, 0);
    checkPoint(m[2].center, 20, 0, 0);
    CHECK(m[2].turns == 1);  // counter-clockwise around the corner
    CHECK(m[2].line == 4);   // the corner belongs to the move that turns it
    checkPoint(m[3].end, 25, 20, 0);
  }
  {
    INFO("an inside arc: its radius less the tool's; a tool too big for it is refused");
    // Left of a ccw arc of radius 20 about (20, 20) from (20, 0) to (40, 20): the tool on
    // the inside, on a radius of 15.
    const auto m = moves(
        "G21 G17 F100\nG0 X0 Y0\nG41.1 D10 G1 X20 Y0\nG3 X40 Y20 I0 J20\n"
        "G40 G1 X50 Y0\n");
    REQUIRE(m.size() == 4);
    checkPoint(m[1].end, 20, 5, 0);
    REQUIRE(m[2].kind == MoveKind::Arc);
    checkPoint(m[2].end, 35, 20, 0);
    checkPoint(m[2].center, 20, 20, 0);
    CHECK_THAT(errorOf("G21 G17 F100\nG0 X0 Y0\nG41.1 D10 G1 X20 Y0\nG3 X24 Y4 R4\n"),
               Contains("test.ngc:4:1: tool radius not less than arc radius"));
  }
  // LinuxCNC's refusals, each at its line.
  CHECK_THAT(errorOf("G21 F100\nG0 X0 Y0\nG41.1 D10 G1 X4 Y0\n"),
             Contains("test.ngc:3:11: length of cutter compensation entry move is not greater "
                      "than the tool radius"));
  CHECK_THAT(errorOf("G21 F100\nG0 X0 Y0\nG41.1 D10 G1 X20 Y0\nG1 X20 Y2\nG1 X0 Y2\n"),
             Contains("test.ngc:5:1: straight feed in concave corner cannot be reached by the "
                      "tool without gouging"));
  CHECK_THAT(errorOf("G21 F100\nG0 X0 Y0\nG41.1 D10 G1 X20 Y0\nG40 G2 X30 Y10 R10\n"),
             Contains("test.ngc:4:5: expected a straight move just after G40"));
  CHECK_THAT(errorOf("G21 F100\nG41.1 D10\nG42.1 D10\n"),
             Contains("test.ngc:3:1: cannot turn cutter radius compensation on when it is on"));
  // The plane is set before compensation on one line (a common header), not after it.
  CHECK(errorOf("G21 F100\nG0 X0 Y0\nG17 G41.1 D10 G1 X20 Y0\nG40 G1 X30\n").empty());
  CHECK_THAT(errorOf("G21 F100\nG0 X0 Y0\nG41.1 D10 G1 X20 Y0\nG18\n"),
             Contains("test.ngc:4:1: expected G40 before changing the plane"));
  CHECK_THAT(errorOf("G21 F100\nG19 G41.1 D10\n"),
             Contains("expected G17 or G18 (the XY or XZ plane) for cutter radius compensation"));
  CHECK_THAT(errorOf("G21 F100\nG41.1 D10 G1 X20\nT2 M6\n"),
             Contains("test.ngc:3:4: expected G40 before a tool change (M6)"));
  CHECK_THAT(errorOf("G21 F100\nG41 D3 G1 X20\n"),
             Contains("expected a tool of the tool table in D") && Contains("found D3"));
  CHECK_THAT(errorOf("G21 F100\nG41.1 G1 X20\n"),
             Contains("expected a D word (the tool's diameter) with G41.1"));
  CHECK_THAT(errorOf("G21 F100\nG41.1 D10 G1 X20\nG81 X30 Y0 Z-1 R1\n"),
             Contains("expected G0, G1, G2 or G3 with cutter radius compensation on, found G81"));
}

TEST_CASE("cutter compensation: lead arcs larger than the tool, and LinuxCNC's sweep tolerance",
          "[gcode][comp]") {
  {
    INFO("a pocket entered and left on arcs of 0.3 in with a 0.5 in tool (a Haas/Fusion lead)");
    // Hand-computed: the tool inside each lead arc, 0.3 - 0.25 = 0.05 in from its centre; the
    // lead-out arc's end lies exactly on the G40 move's line (an end a rounding past the
    // programmed sweep was refused before).
    const auto m = moves(
        "G20 G17 F30\nG0 X0.7 Y1\nG41.1 D0.5 G1 X0.7 Y0.3\nG3 X1 Y0 I0.3 J0\nG1 X2\nG1 Y2\n"
        "G1 X0\nG1 Y0\nG1 X1\nG3 X1.3 Y0.3 I0 J0.3\nG1 G40 X1.3 Y1\nM2\n");
    REQUIRE(m.size() == 10);
    REQUIRE(m[2].kind == MoveKind::Arc);
    checkPoint(m[2].end, 1.0 * 25.4, 0.25 * 25.4, 0);
    checkPoint(m[2].center, 1.0 * 25.4, 0.3 * 25.4, 0);
    REQUIRE(m[8].kind == MoveKind::Arc);
    checkPoint(m[8].start, 1.0 * 25.4, 0.25 * 25.4, 0);
    checkPoint(m[8].end, 1.05 * 25.4, 0.3 * 25.4, 0);
    checkPoint(m[9].end, 1.3 * 25.4, 1.0 * 25.4, 0);
  }
  // An inside arc of radius 2.2 entered phi off tangent from a line, with a 4 mm tool: the tool's
  // arc (radius 0.2) starts where the line's offset ends, which puts its start about 10 phi
  // behind the programmed start; a corner right after it (G40) keeps the whole offset arc, which
  // then sweeps that much more than the programmed one. LinuxCNC 2.9's rs274 (Debian 12) allows
  // 0.001 rad in an inch program and 0.0254 rad in a mm one; measured by bisection on this very
  // program (0.0200 rad runs and 0.0270 is refused in mm, 0.0008 runs and 0.0012 is refused in
  // inches), and engage agrees on each.
  const auto offTangent = [](const char* units, double phi) {
    const double R = 2.2, cx = 20.0 - R * std::sin(phi), cy = R * std::cos(phi);
    const double a1 = std::atan2(-cy, 20.0 - cx) + 1.0;
    const double ex = cx + R * std::cos(a1), ey = cy + R * std::sin(a1);
    char text[400];
    std::snprintf(text, sizeof text,
                  "%s G17 F100\nG0 X0 Y-5\nG41.1 D4 G1 X0 Y0\nG1 X20 Y0\n"
                  "G3 X%.9f Y%.9f I%.9f J%.9f\nG40 G1 X%.9f Y%.9f\nM2\n",
                  units, ex, ey, cx - 20.0, cy, ex - 5.0 * std::sin(a1) + 3.0,
                  ey + 5.0 * std::cos(a1));
    return errorOf(text);
  };
  CHECK(offTangent("G21", -0.002).empty());
  CHECK_THAT(offTangent("G21", -0.0027),
             Contains("test.ngc:6:1: arc move in concave corner cannot be reached by the tool "
                      "without gouging"));
  CHECK(offTangent("G20", -0.00008).empty());
  CHECK_THAT(offTangent("G20", -0.00012), Contains("arc move in concave corner"));
}

TEST_CASE("compensation by wear, D0, and the run's one tool", "[gcode][comp]") {
  // An outside corner of a tool-centre path (CAM wear compensation), entered 0.01 in long.
  const std::string program =
      "G20 G17 F30\nG0 X0.25 Y-0.3\nG41 D1 G1 Y-0.29\nG1 Y1\nG1 X1\nG40 G1 X1.2\nM2\n";
  {
    INFO("wear: the D register holds the wear alone, the path is the tool centre's as written");
    ReaderOptions o;
    o.wearCompensation = true;
    o.toolDiameters = {{1, 12.7}};  // the tool's 0.5 in: not what a wear register offsets by
    const Toolpath p = run(program, o);
    REQUIRE(p.moves.size() == 5);
    checkPoint(p.moves[1].end, 0.25 * 25.4, -0.29 * 25.4, 0);
    checkPoint(p.moves[2].end, 0.25 * 25.4, 1.0 * 25.4, 0);
    checkPoint(p.moves[3].end, 1.0 * 25.4, 1.0 * 25.4, 0);
    CHECK(p.unoffsetCompensation.empty());
  }
  {
    INFO("control: the same program offset by the tool's radius cannot enter, and says why");
    ReaderOptions o;
    o.toolDiameters = {{1, 12.7}};
    CHECK_THAT(errorOf(program, o), Contains("test.ngc:3:8: length of cutter compensation entry "
                                             "move is not greater than the tool radius") &&
                                        Contains("give --cutter-comp wear"));
  }
  {
    INFO("D0 offsets by nothing (LinuxCNC's rs274 agrees) and is named");
    const Toolpath p =
        run("G21 G17 F100\nG0 X-10 Y-10\nG41 D0 G1 X0 Y0\nG1 X20\nG40 G1 X30 Y-10\nM2\n");
    REQUIRE(p.moves.size() == 4);
    checkPoint(p.moves[2].end, 20, 0, 0);
    REQUIRE(p.unoffsetCompensation.size() == 1);
    CHECK(p.unoffsetCompensation[0].line == 3);
  }
  {
    INFO("no table: G41 without D, and with any D, takes the run's one tool (6 mm)");
    ReaderOptions o;
    o.soleToolDiameter = 6.0;
    for (const char* d : {"", " D1"}) {
      const Toolpath p = run(std::string("G21 G17 F100\nT1 M6\nG0 X-10 Y-10\nG41") + d +
                                 " G1 X0 Y0\nG1 X20\nG40 G1 X30 Y-10\nM2\n",
                             o);
      // The entry, an arc round the outside corner, then along +X a radius to its left.
      REQUIRE(p.moves.size() == 5);
      CHECK(p.moves[2].kind == MoveKind::Arc);
      checkPoint(p.moves[3].end, 20, 3, 0);
      CHECK(p.unoffsetCompensation.empty());
    }
  }
}

TEST_CASE("M98/M99 subprograms, Fanuc's repeat digits and grbl's off-plane word", "[gcode]") {
  // rs274 2.9 on the same text: X10 after one call; X10, X20, X30 after L3; M99 in the main
  // program ends it.
  const std::string sub = "O2000\nG91 G1 X10 F100\nG90\nM99\n";
  {
    const auto m = moves("G21 G90\nG0 X0 Y0 Z5\nM98 P2000 L3\nG0 X50\nM99\n" + sub);
    REQUIRE(m.size() == 5);
    checkPoint(m[1].end, 10, 0, 5);
    checkPoint(m[3].end, 30, 0, 5);
    CHECK(m[3].line == 7);  // the subprogram's line
    checkPoint(m[4].end, 50, 0, 5);
    // Fanuc and Haas also number programs with ':' (ISO code): ":1000" names the main
    // program, ":2000" the subprogram M98 calls; the same moves.
    const auto c = moves(":1000 (PART)\nG21 G90\nG0 X0 Y0 Z5\nM98 P2000 L3\nG0 X50\nM99\n:2000\n" +
                         sub.substr(sub.find('\n') + 1));
    REQUIRE(c.size() == 5);
    checkPoint(c[3].end, 30, 0, 5);
    checkPoint(c[4].end, 50, 0, 5);
  }
  {
    // P32000: O2000 three times with --dialect fanuc (the digits above four are the count);
    // program 32000 for LinuxCNC.
    ReaderOptions fanuc;
    fanuc.dialect = Dialect::Fanuc;
    const auto m = run("G21 G90\nG0 X0 Y0 Z5\nM98 P32000\nM30\n" + sub, fanuc).moves;
    REQUIRE(m.size() == 4);
    checkPoint(m[3].end, 30, 0, 5);
    CHECK_THAT(errorOf("G21\nM98 P32000\nM30\n" + sub),
               Contains("test.ngc:2:5: expected a subprogram O32000"));
  }
  CHECK_THAT(errorOf("G21\nM98\n"), Contains("test.ngc:2:1: expected a P word"));
  CHECK_THAT(errorOf("G21\nM98 P7\nM30\nO7\nG0 X1\n"),
             Contains("expected M99 closing the subprogram, found the end of the file"));
  // grbl ignores the off-plane centre word (FreeCAD's grbl post writes K0 in G17).
  const std::string arc = "G21 G17 G90\nG0 X0 Y0\nG2 X10 Y0 I5 J0 K0 F100\n";
  CHECK_THAT(errorOf(arc),
             Contains("test.ngc:3:17: expected I/J centre words") && Contains("--dialect grbl"));
  ReaderOptions grbl;
  grbl.dialect = Dialect::Grbl;
  const auto g = run(arc, grbl).moves;
  REQUIRE(g.size() == 2);
  checkPoint(g[1].center, 5, 0, 0);
}

TEST_CASE("a machine: G53, G28 and G30 where it puts them, its start, its travel", "[gcode]") {
  // G54's origin at machine (-250, -200, -180); the moves come out in G54's frame, where the
  // machine's zero is (250, 200, 180).
  ReaderOptions o;
  MachineSetup m;
  m.name = "vmc.json";
  m.workOffset = {-250, -200, -180};
  m.g30 = {-10, -10, 0};
  m.start = {0, 0, 0};
  o.machine = m;
  const auto moves = run("G21 G90\nG0 X10 Y10\nG1 Z-2 F100\nG53 G0 Z0\nG30\nG28\nM30\n", o).moves;
  REQUIRE(moves.size() == 5);
  checkPoint(moves[0].start, 250, 200, 180);  // the tool starts at the machine's home
  checkPoint(moves[0].end, 10, 10, 180);
  checkPoint(moves[2].end, 10, 10, 180);  // G53 Z0: the top of the machine, not the stock's
  checkPoint(moves[3].end, 240, 190, 180);
  checkPoint(moves[4].end, 250, 200, 180);
  m.limited = true;
  m.travelMin = {-510, -410, -300};
  m.travelMax = {0, 0, 0};
  o.machine = m;
  try {
    run("G21 G90\nG0 X10 Y10\nG0 X300\n", o);
    FAIL("a move beyond the travel was accepted");
  } catch (const GcodeError& e) {
    CHECK_THAT(e.what(), Contains("test.ngc:3:1: expected moves within the travel of the machine "
                                  "(vmc.json: X -510 mm to 0 mm, machine coordinates), found one "
                                  "to X 50 mm"));
  }
}

TEST_CASE("what cannot be interpreted is reported with file:line:col", "[gcode]") {
  CHECK_THAT(errorOf("G12 X1\n"), Contains("test.ngc:1:1: expected a known G code, found G12"));
  CHECK_THAT(errorOf("M97 P100\n"),
             Contains("test.ngc:1:1: expected --dialect haas for M97 (a Haas local subprogram "
                      "call), found the LinuxCNC dialect"));
  CHECK_THAT(errorOf("M96 P100 Q1\n"),
             Contains("test.ngc:1:1: expected an M code engage interprets, found M96 (Haas: a "
                      "jump on an input"));
  CHECK_THAT(
      errorOf("G1 G2 X1 F1\n"),
      Contains("1:4: expected at most one G code of modal group 1 per line, found G1 and G2"));
  CHECK_THAT(errorOf("G0 X0 Y0\nG2 X10 Y1 I5 J0 F100\n"),
             Contains("2:1: expected the arc's end on its circle"));
  CHECK_THAT(
      errorOf("G0 X0 Y0\nG2 X10 Y0 R4 F100\n"),
      Contains(
          "2:11: expected an arc radius that reaches the end point (at least 5 mm), found R4"));
  CHECK_THAT(errorOf("G0 X0 Y0\nG2 X0 Y0 R4 F100\n"),
             Contains("expected an R-form arc to end elsewhere"));
  CHECK_THAT(errorOf("G0 X0 Y0\nG2 X10 Y0 I5 K0 F100\n"),
             Contains("2:14: expected I/J centre words for an arc in the XY plane, found K"));
  CHECK_THAT(errorOf("G1 X10\n"),
             Contains("1:1: expected a positive F word before the first feed move, found feed 0"));
  CHECK_THAT(errorOf("G1 X10 F100 (open comment\n"),
             Contains("1:13: expected ')' closing this comment"));
  CHECK_THAT(errorOf("G1 X10 $\n"),
             Contains("1:8: expected a word letter (G, M, X, F, ...), found '$'"));
  CHECK_THAT(errorOf("X10\n"), Contains("expected a motion mode"));
  CHECK_THAT(errorOf("o<nowhere> call\n"), Contains("expected a subroutine o<nowhere>"));
  CHECK_THAT(errorOf("G0 X[1/0]\n"),
             Contains("1:7: expected a non-zero divisor, found division by zero"));
  CHECK_THAT(errorOf("G0 X#<unset>\n"),
             Contains("1:5: expected a parameter that has a value, found #<unset> unset"));
  CHECK_THAT(errorOf("G0 X[SQRT[-1]]\n"), Contains("expected a non-negative SQRT argument"));
  CHECK_THAT(errorOf("#6000=1\n"), Contains("expected a parameter number in 1..5602, found #6000"));
  // Numbers as LinuxCNC reads them: no E word (X1e308 read as X1 before), no infinite or NaN
  // values, no literal beyond a double's range (read as 0 before).
  CHECK_THAT(errorOf("G0 X1e308\n"),
             Contains("1:6: expected an E word only with G70") && Contains("found E308"));
  CHECK_THAT(errorOf("G0 X[10**400]\n"),
             Contains("1:5: expected a finite value of X, found an infinite one"));
  CHECK_THAT(errorOf("#<x>=[10**400]\nG0 X#<x>\n"),
             Contains("1:6: expected a finite value, found an infinite one"));
  CHECK_THAT(errorOf("G0 X" + std::string(400, '9') + "\n"),
             Contains("1:5: expected a number within the range of a double"));
  // Found by the fuzzer (UBSan): a parameter number beyond int, a bad coordinate system.
  CHECK_THAT(errorOf("G0 X#[1111111111111]\n"), Contains("expected a parameter number in 1..5602"));
  CHECK_THAT(errorOf("#5220=12\nG0 X1\n"),
             Contains("expected a coordinate system 1..9 in #5220, found 12"));
  CHECK_THAT(errorOf("G0 X1 X2\n"),
             Contains("1:7: expected one X word per line, found a second X"));
  CHECK_THAT(errorOf("G81 X1 Z-1 F10\n"), Contains("expected an R word"));
  CHECK_THAT(errorOf("G0 Z1\nG38.2 Z1 F10\n"),
             Contains("2:1: expected a probe target away from the start point"));
  CHECK_THAT(errorOf("G93 G38.2 Z-1 F10\n"),
             Contains("expected units-per-minute feed (G94) for G38.2, found inverse time"));
  CHECK_THAT(errorOf("S100 M3\nG33 Z-1\n"),
             Contains("2:1: expected a K word (distance per spindle revolution) with G33"));
  CHECK_THAT(errorOf("G33.1 Z-1 K1\n"), Contains("expected a spindle speed S > 0 for G33.1"));
  // Lathe cycles: the words they need, and a profile LinuxCNC cannot cut.
  CHECK_THAT(errorOf("G18 G71 X10 Z2 D1\n"),
             Contains("1:5: expected a Q word (the profile's subroutine number) with G71"));
  CHECK_THAT(errorOf("G18 G70 Q100 X15 Z4 D1 P1\n"), Contains("1:9: expected a subroutine o100"));
  CHECK_THAT(errorOf("G71 Q1 X10 Z2\n"), Contains("1:1: expected the XZ plane (G18) for G71"));
  CHECK_THAT(errorOf("G18 G91 G72.1 Q1 X10 Z2\n"),
             Contains("1:9: expected absolute distance mode (G90) for G72.1, found G91"));
  const std::string profile = "o1 sub\nG1 X5 Z0\nZ-10\nX8 Z-8\nX10 Z-12\no1 endsub\n";
  CHECK_THAT(errorOf("G18 F100\n" + profile + "G71 Q1 X10 Z2 I1\n"),
             Contains("8:1: expected a profile that runs one way along the cut (no undercut)"));
  CHECK_THAT(errorOf("G18 F100\n" + profile + "G71 Q1 X10 Z2 I0\n"),
             Contains("8:1: expected a depth of cut I greater than zero, found I0"));
  // Found by the fuzzer: a G72 where LinuxCNC's rs274 repeats one rapid forever.
  CHECK_THAT(errorOf("G18 G21 F400\no101 sub\nG0 X-1 Z22\nG1 X-1 Z20\nG1 X5 Z20\nG1 X5 Z15\n"
                     "G2 I5 K0 X10 Z10\nG1 X14 Z10\nG0 X14 Z8\no101 endsub\n"
                     "G72 Q101 X0 Z6 D0.5 I1 R0.3\n"),
             Contains("11:1: expected a cycle that ends, found one repeating a move of no length"));
  CHECK_THAT(errorOf("%\nG18 F100\no1 sub\nG1 X5 Z0\n%\nZ-10\no1 endsub\nG71 Q1 X10 Z2\n%\n"),
             Contains("5:1: expected O-endsub closing the profile subroutine o1, found the end"));
  CHECK_THAT(errorOf("G18 F100\no1 sub\nG1 X5 Z0\nG2 X7 Z-2 R2 K1\no1 endsub\nG71 Q1 X9 Z2\n"),
             Contains("4:11: expected either R or I/K for an arc, found both"));
  ReaderOptions limited;
  limited.maxExecutedLines = 1000;
  CHECK_THROWS_WITH(run("o1 while [1]\no1 endwhile\n", limited),
                    Contains("more than 1000 executed lines"));
  ReaderOptions few;
  few.maxMoves = 3;
  CHECK_THROWS_WITH(run("G0 X1\nX2\nX3\nX4\n", few),
                    Contains("4:1: expected at most 3 moves in a program, found more"));
  CHECK_THROWS_WITH(readProgram("no/such/program.ngc"),
                    Contains("cannot read program 'no/such/program.ngc'"));
  // A folder is not a program (an ifstream opens it and reads nothing); a device without end
  // is read up to 1 GiB and refused, never until the memory is full.
  CHECK_THROWS_WITH(readProgram(ENGAGE_SOURCE_DIR "/data"), Contains("it is a folder"));
}

TEST_CASE("a program without end is refused at 1 GiB", "[gcode]") {
  CHECK_THROWS_WITH(readProgram("/dev/zero"), Contains("larger than 1 GiB"));
}

TEST_CASE("M codes that move nothing are kept out of the path and named", "[gcode]") {
  // Haas M31/M33 (chip auger), LinuxCNC's user M123 (a script on the machine): no move, no
  // error; each with its line, in order. G92 with a rotary word alone offsets an axis engage
  // does not move (LinuxCNC takes "G92 A0"): nothing changes in XYZ.
  const Toolpath p = run("G21 G90\nG0 X0 Y0 Z5\nM31\nG1 X10 F100 M123\nG92 A0\nM33\nG1 X20\nM2\n");
  REQUIRE(p.moves.size() == 3);
  CHECK(p.moves[2].end.isApprox(Eigen::Vector3d(20, 0, 5)));
  REQUIRE(p.inert.size() == 3);
  CHECK(p.inert[0].code == 31);
  CHECK(p.inert[0].line == 3);
  CHECK(p.inert[1].code == 123);
  CHECK(p.inert[1].line == 4);
  CHECK(p.inert[2].code == 33);
  CHECK(p.inert[2].line == 6);
}

TEST_CASE("a program that sets neither G20 nor G21 is read in the machine's start-up units",
          "[gcode]") {
  // Two Haas posts and Estlcam write no G20 for machines that start up in inches.
  const std::string text = "G90\nG0 X1 Y0 Z0.2\nG1 Z-0.05 F10\nG1 X2\nM2\n";
  const Toolpath mm = run(text);
  CHECK_FALSE(mm.unitsSet);
  CHECK_FALSE(mm.inch);
  CHECK(mm.moves.back().end.isApprox(Eigen::Vector3d(2, 0, -0.05)));
  ReaderOptions o;
  o.startInch = true;
  const Toolpath in = run(text, o);
  CHECK(in.inch);
  CHECK(in.moves.back().end.isApprox(Eigen::Vector3d(50.8, 0, -1.27)));  // 2 in, -0.05 in
  CHECK(in.moves.back().feed == Approx(254.0));                          // F10 in/min
  // A G21 in the program wins over the start-up units, and says the units are set.
  const Toolpath set = run("G21\n" + text, o);
  CHECK(set.unitsSet);
  CHECK(set.moves.back().end.isApprox(Eigen::Vector3d(2, 0, -0.05)));
}

TEST_CASE("Fanuc and Haas corner words round or chamfer the corner to the next G1", "[gcode]") {
  // A 90 deg left turn at (20, 0): ",R5" puts the tangent points R tan(45 deg) = 5 mm from the
  // corner on each move, the arc's centre at (15, 5), counter-clockwise; ",C4" cuts 4 mm from
  // the corner along each (Fanuc operator's manual, chamfering and corner R).
  const auto r = moves("G21 G90 G17\nG0 X0 Y0 Z-1\nG1 X20 ,R5 F100\nG1 Y20\nM2\n");
  REQUIRE(r.size() == 4);
  checkPoint(r[1].end, 15, 0, -1);
  CHECK(r[2].kind == MoveKind::Arc);
  checkPoint(r[2].start, 15, 0, -1);
  checkPoint(r[2].end, 20, 5, -1);
  checkPoint(r[2].center, 15, 5, -1);
  CHECK(r[2].turns == 1);
  CHECK(r[2].line == 3);
  checkPoint(r[3].start, 20, 5, -1);
  checkPoint(r[3].end, 20, 20, -1);
  // A right turn: clockwise, the centre to the right; in inches, ",R0.2" is 5.08 mm.
  const auto in = moves("G20 G90 G17\nG0 X0 Y0 Z0\nG1 X1 ,R0.2 F10\nG1 Y-1\nM2\n");
  REQUIRE(in.size() == 4);
  CHECK(in[2].turns == -1);
  checkPoint(in[2].center, 25.4 - 5.08, -5.08, 0);
  const auto c = moves("G21 G90 G17\nG0 X0 Y0 Z-1\nG1 X20 , C 4 F100\nG1 Y20\nM2\n");
  REQUIRE(c.size() == 4);
  CHECK(c[2].kind == MoveKind::Line);
  checkPoint(c[2].start, 16, 0, -1);
  checkPoint(c[2].end, 20, 4, -1);
  // What cannot be done is refused at the corner word.
  CHECK_THAT(errorOf("G21 G90\nG0 X0 Y0\nG1 X20 ,R30 F100\nG1 Y20\n"),
             Contains("test.ngc:3:8: expected a corner ,R that fits both moves (it takes 30 mm "
                      "of each), found moves of 20 mm and 20 mm"));
  CHECK_THAT(errorOf("G21 G90\nG0 X0 Y0\nG1 X20 ,R5 F100\nG0 Y20\n"),
             Contains("test.ngc:3:8: expected a G1 in the XY plane (G17) after the corner ,R") &&
                 Contains("found G0"));
  CHECK_THAT(errorOf("G21 G90\nG0 X0 Y0\nG1 X20 ,R5 F100\nM2\n"),
             Contains("found the end of the program"));
  CHECK_THAT(errorOf("G21 G90\nG0 X0 Y0\nG1 X20 ,R5 F100\nT2 M6\nG1 Y20\n"),
             Contains("test.ngc:3:8: expected a G1") && Contains("found a tool change"));
  CHECK_THAT(errorOf("G21 G90\nG1 X20 ,X5 F100\n"), Contains("expected R or C after ','"));
}

TEST_CASE("a G41 restated while it is on: a no-op for Fanuc and Haas, refused by LinuxCNC",
          "[gcode]") {
  ReaderOptions o;
  o.toolDiameters = {{1, 6.0}};
  const std::string head = "G21 G90 G17\nT1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nG1 X20\n";
  const std::string tail = "G1 X0\nG40 G1 X-10 Y-10\nM2\n";
  try {
    run(head + "G41 Y20\n" + tail, o);
    FAIL("LinuxCNC's reading took a restated G41");
  } catch (const GcodeError& e) {
    CHECK_THAT(e.what(),
               Contains("test.ngc:6:1: cannot turn cutter radius compensation on when it is on"));
  }
  o.dialect = Dialect::Fanuc;
  const auto restated = run(head + "G41 Y20\n" + tail, o).moves;
  const auto plain = run(head + "G1 Y20\n" + tail, o).moves;
  REQUIRE(restated.size() == plain.size());
  for (std::size_t i = 0; i < plain.size(); ++i) {
    checkPoint(restated[i].start, plain[i].start.x(), plain[i].start.y(), plain[i].start.z());
    checkPoint(restated[i].end, plain[i].end.x(), plain[i].end.y(), plain[i].end.z());
  }
  // The offset path: the 20 x 20 square's left side, 3 mm inside it: (3, 17) after X20.
  checkPoint(plain[3].end, 17, 3, 0);
}

namespace {

Toolpath runAs(Dialect dialect, const std::string& text) {
  ReaderOptions o;
  o.dialect = dialect;
  return run(text, o);
}

std::string errorAs(Dialect dialect, const std::string& text) {
  ReaderOptions o;
  o.dialect = dialect;
  return errorOf(text, o);
}

}  // namespace

TEST_CASE("Fanuc and Haas custom macro B: G65 with arguments, IF, WHILE, GOTO, vacant",
          "[gcode][macro]") {
  {
    INFO("a shop's bolt-circle macro (data/gcode/dialects/haas_macro_b.nc), holes by hand");
    ReaderOptions o;
    o.dialect = Dialect::Haas;
    const Toolpath p = readProgram(ENGAGE_SOURCE_DIR "/data/gcode/dialects/haas_macro_b.nc", o);
    // Each hole: a rapid over it, down to R, the plunge to Z, back to R. The plunges only:
    std::vector<Eigen::Vector3d> plunges;
    for (const Move& m : p.moves)
      if (m.kind == MoveKind::Line) plunges.push_back(m.end);
    REQUIRE(plunges.size() == 10);
    // Six on r 20 about (40, 30) from 0 deg, 3 mm deep (A and R not given: 0 deg, R 2);
    for (int i = 0; i < 6; ++i) {
      const double a = i * kPi / 3.0;
      checkPoint(plunges[static_cast<std::size_t>(i)], 40 + 20 * std::cos(a), 30 + 20 * std::sin(a),
                 -3, 1e-9);
    }
    // four on r 15 about (100, 30) from 45 deg, 2 mm deep, at F150.
    for (int i = 0; i < 4; ++i) {
      const double a = kPi / 4.0 + i * kPi / 2.0;
      checkPoint(plunges[static_cast<std::size_t>(6 + i)], 100 + 15 * std::cos(a),
                 30 + 15 * std::sin(a), -2, 1e-9);
    }
    // The clearance R: 2 mm when not given (the macro's IF [#18 EQ #0] THEN), 5 when given.
    CHECK(p.moves[3].end.z() == Approx(2.0).margin(kExact));
    CHECK(p.moves.back().end.z() == Approx(25.0).margin(kExact));
  }
  const std::string macro = "O9001\n#30=#1+#2\nG1 X#30 Y#24 F100\n#1=99\nM99\n";
  {
    INFO("arguments into #1-#26 by letter; the caller's locals back after M99");
    const auto m =
        runAs(Dialect::Fanuc, "G21 G90\n#1=7\nG65 P9001 A1 B2 X3\nG0 Z#1\nM30\n" + macro).moves;
    REQUIRE(m.size() == 2);
    checkPoint(m[0].end, 3, 3, 0);  // X = A + B, Y = X's argument
    checkPoint(m[1].end, 3, 3, 7);  // #1 is the caller's 7 again, not the macro's 99
  }
  {
    INFO("L repeats: the arguments only on the first time (#1 is 99 from then on)");
    const auto m = runAs(Dialect::Fanuc, "G21 G90\nG65 P9001 L2 A1 B2 X3\nM30\n" + macro).moves;
    REQUIRE(m.size() == 2);
    checkPoint(m[0].end, 3, 3, 0);
    checkPoint(m[1].end, 101, 3, 0);
  }
  {
    INFO("vacant: an argument not given, #0; 0 in arithmetic, a left-out word, EQ only to #0");
    const auto m = runAs(Dialect::Fanuc,
                         "G21 G90\nG0 X1 Y2 Z3\n#2=#0\n#3=#0+4\nG0 X#2 Y#3\n"
                         "IF [#2 EQ 0] THEN #4=1\nIF [#2 EQ #0] THEN #5=1\nG0 Z[#4+10*#5]\nM30\n")
                       .moves;
    REQUIRE(m.size() == 3);
    checkPoint(m[1].end, 1, 4, 3);   // X#2 left out; #3 = 0 + 4
    checkPoint(m[2].end, 1, 4, 10);  // #4 vacant (0 in the sum), #5 = 1
  }
  {
    INFO("WHILE .. DO nested, GOTO within the program it is in");
    const auto m = runAs(Dialect::Fanuc,
                         "G21 G90\n#1=0\nWHILE [#1 LT 2] DO 1\n#2=0\nWHILE [#2 LT 3] DO 2\n"
                         "G0 X#1 Y#2\n#2=#2+1\nEND 2\n#1=#1+1\nEND 1\nGOTO 10\nG0 Z99\n"
                         "N10 M98 P20\nM30\nO20\nGOTO 10\nG0 Z-99\nN10 G0 Z5\nM99\n")
                       .moves;
    REQUIRE(m.size() == 7);
    checkPoint(m[5].end, 1, 2, 0);
    checkPoint(m[6].end, 1, 2, 5);  // O20's own N10, not the main program's
  }
  {
    INFO("Haas: #10000-#10999, legacy numbers aliased; M97 local subprograms");
    const auto m = runAs(Dialect::Haas,
                         "G21 G90\n#10100=5\n#10200=6\nG0 X#100 Y#10200\nM97 P100 L2\nM30\n"
                         "N100 #101=#101+1\nG0 Z#10101\nM99\n")
                       .moves;
    REQUIRE(m.size() == 3);
    checkPoint(m[0].end, 5, 6, 0);
    checkPoint(m[2].end, 5, 6, 2);
  }
  {
    INFO("system variables a program reads, in program units");
    ReaderOptions o;
    o.dialect = Dialect::Fanuc;
    o.toolDiameters = {{3, 6.35}};
    const auto m = run("G20 G90\nT3 M6\nG0 X1 Y2 Z3\n#1=#5041+#5022\nG0 X#1 Y#4006 Z#4120\n"
                       "G0 X#2403 Y#4003 Z#4001\nM30\n",
                       o)
                       .moves;
    REQUIRE(m.size() == 3);
    checkPoint(m[1].end, 3 * 25.4, 20 * 25.4, 3 * 25.4);  // 1 + 2; G20; T3
    checkPoint(m[2].end, 0.125 * 25.4, 90 * 25.4, 0);     // tool 3's radius; G90; G0
  }
  // What needs the machine, what cannot be set, and a program's own alarm: refused at the word.
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nG0 X#3011\n"),
             Contains("test.ngc:2:5: expected a variable a simulation can give, found #3011"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\n#1=#1000\n"), Contains("found #1000 (an input"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\n#5021=1\n"),
             Contains("test.ngc:2:1: expected a variable a program can set, found #5021"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\n#3000=12 (CHECK TOOL)\nG0 X1\n"),
             Contains("test.ngc:2:1: expected the program to go on, found alarm #3000 = 12 "
                      "(CHECK TOOL)"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nG65 P9001 G1 X2\nM30\n" + macro),
             Contains("test.ngc:2:11: expected only G65 and its arguments on a macro call's "
                      "line, found G1"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nG65 P9001 A1 A2\nM30\n" + macro),
             Contains("test.ngc:2:14: expected each argument once in G65"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nG65 P9002\nM30\n"),
             Contains("test.ngc:2:1: expected a macro program O9002"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nWHILE [1] DO 1\nG0 X1\nEND 2\n"),
             Contains("test.ngc:4:1: expected WHILE .. DO 2 or DO 2 opening this END"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nWHILE [0] DO 1\nG0 X1\nM30\n"),
             Contains("test.ngc:2:1: expected END 1 closing this loop, found none"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nGOTO 5\n"),
             Contains("test.ngc:2:1: expected a line N5 in this program to go to, found none"));
  // LinuxCNC and Fanuc (without Haas) refuse what is not theirs, naming the dialect to give.
  CHECK_THAT(errorOf("G21\n#1=1\nIF [#1 GT 0] GOTO 5\nN5 M30\n"),
             Contains("test.ngc:3:1: expected --dialect fanuc or haas"));
  CHECK_THAT(errorOf("G21\nG65 P9001 A1\nM30\n" + macro),
             Contains("test.ngc:2:1: expected --dialect fanuc or haas for G65"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\nM97 P10\nM30\nN10 M99\n"),
             Contains("expected --dialect haas for M97"));
  CHECK_THAT(errorAs(Dialect::Fanuc, "G21\n#10000=1\n"),
             Contains("expected a parameter number in 1..5602, found #10000"));
}

TEST_CASE("a probe stops where the simulated stock says it touches", "[gcode][probe]") {
  // The stock's answer stands in for the box: the probe touches 22.3 of the 30 mm down.
  ReaderOptions o;
  o.probeContact = [](const Eigen::Vector3d& from, const Eigen::Vector3d& to, int) {
    return from.z() > to.z() && to.z() < -2.3 ? (from.z() + 2.3) / (from.z() - to.z()) : 2.0;
  };
  const Toolpath p =
      run("G21 G90\nG0 X10 Y10 Z20\nG38.2 Z-10 F100\nG10 L20 P1 Z0\nG1 Z-1 F200\n"
          "G0 X#5061 Y#5062 Z[#5063+#5070]\nM2\n",
          o);
  REQUIRE(p.moves.size() == 4);
  checkPoint(p.moves[1].end, 10, 10, -2.3);  // the probe stops at the top; no back-off
  checkPoint(p.moves[2].end, 10, 10, -3.3);  // Z0 is the touched top: Z-1 is 1 mm into it
  // #5061-#5063 the touch in the coordinates it was taken in (before G10: Z-2.3), #5070 = 1:
  // Z-1.3 in the new coordinates, whose Z0 is at -2.3, is -3.6.
  checkPoint(p.moves[3].end, 10, 10, -3.6);
  {
    INFO("G38.2 that touches nothing is an error; G38.3 goes to its target, #5070 = 0");
    CHECK_THAT(errorOf("G21 G90\nG0 X10 Y10 Z20\nG38.2 Z0 F100\nM2\n", o),
               Contains("test.ngc:3:1: expected the probe to touch the stock on its way"));
    const Toolpath q = run("G21 G90\nG0 X10 Y10 Z20\nG38.3 Z0 F100\nG0 X#5070\nM2\n", o);
    REQUIRE(q.moves.size() == 3);
    checkPoint(q.moves[1].end, 10, 10, 0);
    checkPoint(q.moves[2].end, 0, 10, 0);
  }
}

TEST_CASE("a Fanuc or Haas canned cycle without R drills from the initial level",
          "[gcode][cycle]") {
  // As Haas student programs write it: "G81 G98 Z-0.45 F85.95" from Z0.1. By hand: down to
  // Z-0.45 at the feed from the initial level, back up to it (G98), in inches.
  const std::string text = "G20 G90\nG0 X0.8 Y1.75 Z0.1\nG81 G98 Z-0.45 F85.95\nG80\nM30\n";
  // (The cycle's rapids to the hole and to R have no length here: left out.)
  const auto m = withoutZeroLength(runAs(Dialect::Haas, text).moves);
  REQUIRE(m.size() == 3);
  CHECK(m[1].kind == MoveKind::Line);
  checkPoint(m[1].end, 0.8 * 25.4, 1.75 * 25.4, -0.45 * 25.4);
  checkPoint(m[2].end, 0.8 * 25.4, 1.75 * 25.4, 0.1 * 25.4);
  CHECK_THAT(errorOf(text), Contains("test.ngc:3:1: expected an R word (retract plane) when a "
                                     "canned cycle starts, found none (--dialect fanuc or haas"));
}
