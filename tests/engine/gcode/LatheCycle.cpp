// Tests of engine/gcode/LatheCycle.h: the moves of G70/G71/G72 on profiles whose passes are
// worked out by hand below, the symmetries of the cycles, and the refusals. (The comparison
// with LinuxCNC's own interpreter is in GcodeReader.cpp's golden test.)

#include "engine/gcode/LatheCycle.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

using namespace engage::gcode;
using Catch::Matchers::Contains;

namespace {

// Hand-computed positions are exact decimals or thirds; 1e-9 is round-off.
constexpr double kExact = 1e-9;

LathePoint zx(double z, double x) {
  return {z, x};
}

LatheSegment line(LathePoint a, LathePoint b) {
  LatheSegment s;
  s.start = a;
  s.end = b;
  return s;
}

/// A profile through points (z, x), starting at the cycle's start.
std::vector<LatheSegment> polyline(const std::vector<LathePoint>& points) {
  std::vector<LatheSegment> out;
  for (std::size_t i = 1; i < points.size(); ++i)
    out.push_back(line(points[i - 1], points[i]));
  return out;
}

/// The moves without zero-length rapids and lines (the reader leaves those out too).
std::vector<LatheMove> moving(const std::vector<LatheMove>& in, LathePoint from) {
  std::vector<LatheMove> out;
  for (const LatheMove& m : in) {
    if (m.kind != LatheMoveKind::Arc && std::abs(m.end - from) < kExact) continue;
    out.push_back(m);
    from = m.end;
  }
  return out;
}

void checkMove(const LatheMove& m, LatheMoveKind kind, double z, double x) {
  CHECK(m.kind == kind);
  CHECK(m.end.real() == Approx(z).margin(kExact));
  CHECK(m.end.imag() == Approx(x).margin(kExact));
}

// A shoulder: start X10 Z2, the profile X5 Z0, Z-10, X10 (radius mode, program units).
const LathePoint kStart = zx(2, 10);
const std::vector<LatheSegment> kShoulder = polyline({kStart, zx(0, 5), zx(-10, 5), zx(-10, 10)});

}  // namespace

TEST_CASE("G71 roughs a shoulder in passes I apart, each retracting by R at 45 degrees",
          "[gcode][lathe]") {
  LatheCycle c;
  c.code = 71;
  c.start = kStart;
  c.d = 0.0;
  c.depth = 1.0;
  c.retract = 0.3;
  const auto m = moving(latheCycleMoves(kShoulder, c), kStart);
  // By hand: passes at X10, 9, 8, 7, 6 start on the approach line from (Z2, X10) to (Z0, X5),
  // Z = 2 - 0.4 (10 - X), and end on the shoulder face Z-10; each leaves by (+0.3, +0.3),
  // rapids back at X + 0.3 to 0.3 short of its start and down to it; the next pass's start
  // is a rapid down the approach line. The last pass is the profile itself.
  REQUIRE(m.size() == 4 * 5 + 4 + 3);
  std::size_t i = 0;
  for (int k = 0; k < 5; ++k) {
    const double x = 10 - k;
    const double z0 = 2 - 0.4 * k;
    if (k > 0) checkMove(m[i++], LatheMoveKind::Rapid, z0, x);
    checkMove(m[i++], LatheMoveKind::Line, -10, x);
    checkMove(m[i++], LatheMoveKind::Rapid, -9.7, x + 0.3);
    checkMove(m[i++], LatheMoveKind::Rapid, z0 - 0.3, x + 0.3);
    checkMove(m[i++], LatheMoveKind::Rapid, z0, x);
  }
  checkMove(m[i++], LatheMoveKind::Rapid, 0, 5);  // down the approach to the profile
  checkMove(m[i++], LatheMoveKind::Line, -10, 5);
  checkMove(m[i++], LatheMoveKind::Line, -10, 10);
}

TEST_CASE("G70 finishes in P passes from D to E away from the profile", "[gcode][lathe]") {
  LatheCycle c;
  c.code = 70;
  c.start = kStart;
  c.d = 1.0;
  c.e = 0.0;
  c.passes = 2;
  const auto m = moving(latheCycleMoves(kShoulder, c), kStart);
  // By hand: pass 1 at (2 - 1) (1 - 0) / 2 = 0.5 from the profile, on the start's side (X up,
  // Z towards the start): X5.5 along Z, the face at Z-9.5; pass 2 on the profile.
  REQUIRE(m.size() == 3 + 4);
  checkMove(m[0], LatheMoveKind::Rapid, 0, 5.5);
  checkMove(m[1], LatheMoveKind::Line, -9.5, 5.5);
  checkMove(m[2], LatheMoveKind::Line, -9.5, 10);
  checkMove(m[3], LatheMoveKind::Rapid, 2, 10);
  checkMove(m[4], LatheMoveKind::Rapid, 0, 5);
  checkMove(m[5], LatheMoveKind::Line, -10, 5);
  checkMove(m[6], LatheMoveKind::Line, -10, 10);
}

TEST_CASE("G71 cuts a pocket after the main passes, G71.1 leaves it", "[gcode][lathe]") {
  // A groove between Z-4 and Z-10 down to X3, walls sloping 3 in X over 2 in Z.
  const auto profile = polyline(
      {kStart, zx(0, 6), zx(-4, 6), zx(-6, 3), zx(-8, 3), zx(-10, 6), zx(-14, 6), zx(-14, 10)});
  LatheCycle c;
  c.code = 71;
  c.start = kStart;
  c.depth = 1.0;
  c.retract = 0.3;

  c.variant = 1;
  const auto skipping = moving(latheCycleMoves(profile, c), kStart);
  for (const LatheMove& m : skipping) {
    INFO("G71.1 move to Z" << m.end.real() << " X" << m.end.imag());
    const bool inGroove = m.end.real() < -4 - kExact && m.end.real() > -10 + kExact;
    CHECK((!inGroove || m.end.imag() >= 6 - kExact));
  }
  // By hand: it ends along X6 over the groove and up the last face.
  REQUIRE(skipping.size() >= 3);
  checkMove(skipping[skipping.size() - 3], LatheMoveKind::Line, -10, 6);
  checkMove(skipping[skipping.size() - 2], LatheMoveKind::Line, -14, 6);
  checkMove(skipping[skipping.size() - 1], LatheMoveKind::Line, -14, 10);

  c.variant = 0;
  const auto full = moving(latheCycleMoves(profile, c), kStart);
  // By hand, the groove's passes: at X6 from Z-4 to Z-10, at X5 from Z-4 2/3 to Z-9 1/3, at X4
  // from Z-5 1/3 to Z-8 2/3 (the walls' crossings), then along its floor and out.
  std::vector<std::pair<double, double>> passes;  // (Z start, Z end) of feed lines along X5, X4
  for (std::size_t i = 1; i < full.size(); ++i) {
    const LatheMove& m = full[i];
    if (m.kind == LatheMoveKind::Line && std::abs(m.end.imag() - full[i - 1].end.imag()) < kExact &&
        (std::abs(m.end.imag() - 5) < kExact || std::abs(m.end.imag() - 4) < kExact))
      passes.emplace_back(full[i - 1].end.real(), m.end.real());
  }
  REQUIRE(passes.size() == 2);
  CHECK(passes[0].first == Approx(-4 - 2.0 / 3).margin(kExact));
  CHECK(passes[0].second == Approx(-9 - 1.0 / 3).margin(kExact));
  CHECK(passes[1].first == Approx(-5 - 1.0 / 3).margin(kExact));
  CHECK(passes[1].second == Approx(-8 - 2.0 / 3).margin(kExact));
  REQUIRE(full.size() >= 4);
  checkMove(full[full.size() - 4], LatheMoveKind::Line, -8, 3);
  checkMove(full[full.size() - 3], LatheMoveKind::Line, -10, 6);
  checkMove(full[full.size() - 2], LatheMoveKind::Line, -14, 6);
  checkMove(full[full.size() - 1], LatheMoveKind::Line, -14, 10);
}

TEST_CASE("the cycles are symmetric: mirrored profiles give mirrored moves, G72 is a turned G71",
          "[gcode][lathe]") {
  // A profile with a convex and a concave arc (radius 2), a finishing allowance and retract.
  std::vector<LatheSegment> profile = polyline({kStart, zx(0, 4), zx(-3, 4)});
  LatheSegment convex;  // G3 from (Z-3, X4) to (Z-5, X6) about (Z-5, X4)
  convex.arc = true;
  convex.ccw = true;
  convex.start = zx(-3, 4);
  convex.end = zx(-5, 6);
  convex.centre = zx(-5, 4);
  LatheSegment concave;  // G2 from (Z-5, X6) to (Z-7, X8) about (Z-5, X8)
  concave.arc = true;
  concave.start = zx(-5, 6);
  concave.end = zx(-7, 8);
  concave.centre = zx(-5, 8);
  profile.push_back(convex);
  profile.push_back(concave);
  profile.push_back(line(zx(-7, 8), zx(-12, 8)));
  profile.push_back(line(zx(-12, 8), zx(-12, 10)));
  LatheCycle c;
  c.code = 71;
  c.start = kStart;
  c.d = 0.4;
  c.depth = 0.7;
  c.retract = 0.5;

  const auto transformed = [&](auto map, bool mirror) {
    std::vector<LatheSegment> out = profile;
    for (LatheSegment& s : out) {
      s.start = map(s.start);
      s.end = map(s.end);
      s.centre = map(s.centre);
      if (s.arc && mirror) s.ccw = !s.ccw;
    }
    return out;
  };
  const auto same = [](const std::vector<LatheMove>& a, const std::vector<LatheMove>& b, auto map,
                       bool mirror) {
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      INFO("move " << i);
      CHECK(a[i].kind == b[i].kind);
      CHECK(std::abs(map(a[i].end) - b[i].end) < kExact);
      if (a[i].kind == LatheMoveKind::Arc) {
        CHECK(std::abs(map(a[i].centre) - b[i].centre) < kExact);
        CHECK(a[i].ccw == (b[i].ccw != mirror));
      }
    }
  };
  const auto base = latheCycleMoves(profile, c);
  REQUIRE(base.size() > 20);

  SECTION("a bore: X mirrored") {
    const auto flip = [](LathePoint p) { return std::conj(p); };
    LatheCycle m = c;
    m.start = flip(c.start);
    same(base, latheCycleMoves(transformed(flip, true), m), flip, true);
  }
  SECTION("cutting towards +Z: Z mirrored") {
    const auto flip = [](LathePoint p) { return -std::conj(p); };
    LatheCycle m = c;
    m.start = flip(c.start);
    same(base, latheCycleMoves(transformed(flip, true), m), flip, true);
  }
  SECTION("G72 on the profile turned by a quarter turn") {
    // turn(Z + iX) = i (Z + iX): G72 turns it back by -i and roughs it as G71 does.
    const auto turn = [](LathePoint p) { return LathePoint(0, 1) * p; };
    LatheCycle m = c;
    m.code = 72;
    m.start = turn(c.start);
    same(base, latheCycleMoves(transformed(turn, false), m), turn, false);
  }
}

TEST_CASE("lathe cycles refuse what LinuxCNC refuses, and what would never end", "[gcode][lathe]") {
  LatheCycle c;
  c.code = 71;
  c.start = kStart;
  SECTION("a depth of cut of zero") {
    c.depth = 0.0;
    CHECK_THROWS_WITH(latheCycleMoves(kShoulder, c),
                      Contains("expected a depth of cut I greater than zero, found I0"));
  }
  SECTION("an undercut: the profile turns back along Z") {
    const auto undercut = polyline({kStart, zx(0, 5), zx(-10, 5), zx(-8, 8), zx(-12, 10)});
    CHECK_THROWS_WITH(latheCycleMoves(undercut, c),
                      Contains("expected a profile that runs one way along the cut"));
  }
  SECTION("two consecutive profile lines on one line") {
    const auto straight = polyline({kStart, zx(0, 5), zx(-5, 5), zx(-10, 5), zx(-10, 10)});
    c.d = 0.5;
    CHECK_THROWS_WITH(latheCycleMoves(straight, c), Contains("two parallel lines"));
  }
  SECTION("undefined numbers") {
    c.d = std::nan("");
    CHECK_THROWS_WITH(latheCycleMoves(kShoulder, c), Contains("expected finite cycle words"));
  }
  SECTION("no profile: no moves, as LinuxCNC") {
    CHECK(latheCycleMoves(polyline({kStart, zx(0, 5)}), c).empty());
  }
}
