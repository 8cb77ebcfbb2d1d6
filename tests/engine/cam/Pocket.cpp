// Tests of engine/cam/Pocket.h: offsets of shapes whose rings are known by hand, coverage of
// the pocket floor, arcs kept, the program read back, and bad input.

#include "engine/cam/Pocket.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/gcode/GcodeReader.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;

namespace {

Loop rectangle(double x0, double y0, double x1, double y1) {
  return polygonLoop({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
}

Loop circle(double cx, double cy, double radius) {
  // Two counter-clockwise half circles.
  Element a;
  a.arc = true;
  a.ccw = true;
  a.center = {cx, cy};
  a.start = {cx + radius, cy};
  a.end = {cx - radius, cy};
  Element b = a;
  std::swap(b.start, b.end);
  return {a, b};
}

PocketOptions options(double r, double s) {
  PocketOptions o;
  o.toolRadius = r;
  o.stepover = s;
  o.depth = 2.0;
  o.safeZ = 5.0;
  o.feed = 600.0;
  o.plungeFeed = 200.0;
  return o;
}

double distanceTo(const Element& e, const Eigen::Vector2d& p) {
  if (!e.arc) {
    const Eigen::Vector2d d = e.end - e.start;
    const double t = std::clamp((p - e.start).dot(d) / d.squaredNorm(), 0.0, 1.0);
    return (e.start + t * d - p).norm();
  }
  // Inside the arc's sweep: |distance to the centre - radius|; else the nearer end.
  const double radius = (e.start - e.center).norm();
  auto angle = [&](const Eigen::Vector2d& q) {
    return std::atan2(q.y() - e.center.y(), q.x() - e.center.x());
  };
  auto ccwFrom = [](double a, double b) {  // counter-clockwise angle from a to b in [0, 2pi)
    double x = std::fmod(b - a, 2 * kPi);
    return x < 0 ? x + 2 * kPi : x;
  };
  const double a0 = angle(e.start), a1 = angle(e.end), ap = angle(p);
  const bool within =
      e.ccw ? ccwFrom(a0, ap) <= ccwFrom(a0, a1) : ccwFrom(a1, ap) <= ccwFrom(a1, a0);
  if (within) return std::abs((p - e.center).norm() - radius);
  return std::min((p - e.start).norm(), (p - e.end).norm());
}

double distanceToRings(const std::vector<Ring>& rings, const Eigen::Vector2d& p) {
  double best = 1e300;
  for (const Ring& r : rings)
    for (const Element& e : r.elements)
      best = std::min(best, distanceTo(e, p));
  return best;
}

double signedArea(const Ring& r) {
  // The shoelace formula over the ring with its arcs flattened into 32 chords each.
  std::vector<Eigen::Vector2d> p;
  for (const Element& e : r.elements) {
    p.push_back(e.start);
    if (!e.arc) continue;
    const Eigen::Vector2d a = e.start - e.center, b = e.end - e.center;
    double sweep = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    if (e.ccw && sweep < 0) sweep += 2 * kPi;
    if (!e.ccw && sweep > 0) sweep -= 2 * kPi;
    const double a0 = std::atan2(a.y(), a.x());
    for (int k = 1; k < 32; ++k)
      p.push_back(e.center + a.norm() * Eigen::Vector2d(std::cos(a0 + sweep * k / 32),
                                                        std::sin(a0 + sweep * k / 32)));
  }
  double area = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& u = p[i];
    const Eigen::Vector2d& v = p[(i + 1) % p.size()];
    area += u.x() * v.y() - v.x() * u.y();
  }
  return 0.5 * area;
}

}  // namespace

TEST_CASE("pocket: a rectangle gives rectangles at r, r + s, ... cut inside out", "[cam]") {
  // 50 x 30 mm, r = 5, s = 4: rings at 5, 9, 13 from the walls (40 x 20, 32 x 12, 24 x 4);
  // at 17 nothing is left (half the height is 15).
  const std::vector<Ring> rings = pocketRings({rectangle(0, 0, 50, 30)}, options(5, 4));
  REQUIRE(rings.size() == 3);
  const double expected[] = {13, 9, 5};
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(rings[i].offset == Approx(expected[i]));
    REQUIRE(rings[i].elements.size() == 4);
    const double e = expected[i];
    for (const Element& el : rings[i].elements) {
      CHECK_FALSE(el.arc);
      // Every corner is a corner of the offset rectangle, to Clipper's 0.1 um grid.
      CHECK((std::abs(el.start.x() - e) < 1e-4 || std::abs(el.start.x() - (50 - e)) < 1e-4));
      CHECK((std::abs(el.start.y() - e) < 1e-4 || std::abs(el.start.y() - (30 - e)) < 1e-4));
    }
    // Climb milling with an M3 spindle: the walls on the right (G41 side), counter-clockwise.
    CHECK(signedArea(rings[i]) > 0);
  }
  CHECK(rings[1].linked);  // 4 mm to the next ring, inside the pocket
}

TEST_CASE("pocket: conventional milling runs the other way", "[cam]") {
  PocketOptions o = options(5, 4);
  o.climb = false;
  for (const Ring& r : pocketRings({rectangle(0, 0, 50, 30)}, o))
    CHECK(signedArea(r) < 0);
}

TEST_CASE("pocket: a circle gives concentric arcs, and the program reads back", "[cam]") {
  // R 20, r 3, s 5: rings of radius 17 - 5k: 2, 7, 12, 17 (cut in that order).
  const std::vector<Ring> rings = pocketRings({circle(0, 0, 20)}, options(3, 5));
  REQUIRE(rings.size() == 4);
  for (std::size_t i = 0; i < 4; ++i) {
    const double radius = 2.0 + 5.0 * static_cast<double>(i);
    CHECK(rings[i].elements.size() == 2);  // a full circle is two half circles
    for (const Element& e : rings[i].elements) {
      REQUIRE(e.arc);
      // Exact offsets: the centre exactly, the radius to the end points' rounding to
      // Clipper's 0.1 um grid.
      CHECK(e.center.norm() < 1e-9);
      CHECK((e.start - e.center).norm() == Approx(radius).margin(1e-4));
    }
  }
  const PocketOptions o = options(3, 5);
  const Toolpath path = readProgramText(writePocketProgram(rings, o, {"test"}), "circle.ngc");
  int arcs = 0;
  for (const Move& m : path.moves) {
    if (m.kind != MoveKind::Arc) continue;
    ++arcs;
    CHECK(m.start.z() == Approx(-2.0));
    const double radius = arcRadius(m);
    CHECK(std::abs(radius - std::round((radius - 2.0) / 5.0) * 5.0 - 2.0) < 1e-4);
  }
  std::size_t elements = 0;
  for (const Ring& r : rings)
    elements += r.elements.size();
  CHECK(static_cast<std::size_t>(arcs) == elements);
}

TEST_CASE("pocket: every point of the floor is within r of the path", "[cam]") {
  SECTION("leftover in the middle needs a clean-up ring") {
    // 50 x 21, r 3, s 4: rings at 3 and 7 leave a 36 x 7 mm strip whose middle is 3.5 mm
    // from the ring at 7, more than r: a clean-up ring on the middle line must cover it.
    // (s <= r sqrt 2, so that the rings' sharp corners leave nothing between them.)
    const std::vector<Ring> rings = pocketRings({rectangle(0, 0, 50, 21)}, options(3, 4));
    CHECK(rings.size() == 3);
    for (double x = 3; x <= 47; x += 0.25)
      for (double y = 3; y <= 18; y += 0.25)
        REQUIRE(distanceToRings(rings, {x, y}) <= 3.0 + 0.01);
  }
  SECTION("an island: rings around it, clockwise when climbing (the island on the right)") {
    const std::vector<Ring> rings =
        pocketRings({rectangle(-30, -30, 30, 30), circle(0, 0, 7)}, options(3, 4));
    int islands = 0;
    for (const Ring& r : rings)
      if (r.island) {
        ++islands;
        CHECK(signedArea(r) < 0);
        for (const Element& e : r.elements)
          CHECK(e.arc);
      }
    // Around the R 7 island the rings run at 10, 14 and 18 from its centre, inside the
    // square's rings (half sides 27, 23, 19); at the next offset the disc of 22 covers the
    // square of half side 15 (corner 21.2) and nothing is left.
    CHECK(islands == 3);
    for (double x = -27; x <= 27; x += 0.5)
      for (double y = -27; y <= 27; y += 0.5) {
        const Eigen::Vector2d p(x, y);
        if (p.norm() < 7 + 3) continue;  // the island and the tool's radius around it
        REQUIRE(distanceToRings(rings, p) <= 3.0 + 0.01);
      }
  }
}

TEST_CASE("pocket: levels and the program's entries", "[cam]") {
  PocketOptions o = options(5, 4);
  o.depth = 2.5;
  o.stepDown = 1.0;
  CHECK(levelZ(o, 0) == Approx(-1.0));
  CHECK(levelZ(o, 1) == Approx(-2.0));
  CHECK(levelZ(o, 2) == Approx(-2.5));
  const std::vector<Ring> rings = pocketRings({rectangle(0, 0, 50, 30)}, o);
  REQUIRE(rings.size() == 9);
  // A step-down of 1e-6 mm would make 2.5 million levels: refused up front.
  PocketOptions thin = o;
  thin.stepDown = 1e-6;
  CHECK_THROWS_WITH(pocketRings({rectangle(0, 0, 50, 30)}, thin),
                    Catch::Matchers::Contains("more than 10000 levels"));
  CHECK(rings[3].level == 1);
  CHECK_FALSE(rings[3].linked);
  const Toolpath path = readProgramText(writePocketProgram(rings, o, {}), "levels.ngc");
  // Every plunge is a feed move at the plunge feed; no feed move runs above the stock into
  // air deeper than the level it cuts.
  double lowest = 0.0;
  for (const Move& m : path.moves) {
    lowest = std::min(lowest, m.end.z());
    if (m.kind == MoveKind::Line && m.start.head<2>() == m.end.head<2>())
      CHECK(m.feed == Approx(200.0));
  }
  CHECK(lowest == Approx(-2.5));
}

TEST_CASE("pocket: bad input", "[cam]") {
  CHECK_THROWS_AS(pocketRings({rectangle(0, 0, 50, 30)}, options(5, 11)), ParameterError);
  CHECK_THROWS_AS(pocketRings({rectangle(0, 0, 50, 30)}, options(0, 1)), ParameterError);
  CHECK_THROWS_WITH(pocketRings({rectangle(0, 0, 8, 8)}, options(5, 4)),
                    Catch::Contains("does not fit"));
  const Toolpath open = readProgramText("G21 G90\nG0 X0 Y0\nG1 X10 F100\nG1 Y10\nM2\n", "open.ngc");
  CHECK_THROWS_WITH(boundaryLoops(open),
                    Catch::Contains("open.ngc:4") && Catch::Contains("does not close"));
  const Toolpath none = readProgramText("G21 G90\nG0 X0 Y0\nM2\n", "none.ngc");
  CHECK_THROWS_WITH(boundaryLoops(none), Catch::Contains("no closed boundary loop"));
}

TEST_CASE("pocket: the paper's free-form pocket keeps its arcs, concentric with the boundary",
          "[cam]") {
  // data/paper/fig10_boundary.ngc: lobes of R 2.5 in about (0, 0) and R 2 in about (5, 0),
  // necks of R 1.5 in about (2.875, +-2.781074) in (a hand computation in the file's terms).
  // With r = s = 0.5 in every ring is made of arcs about those four centres: radius
  // R_lobe - offset on the lobes, R_neck + offset on the necks.
  const Toolpath b = readProgram(ENGAGE_SOURCE_DIR "/data/paper/fig10_boundary.ngc");
  PocketOptions o = options(12.7, 12.7);
  const std::vector<Ring> rings = pocketRings(boundaryLoops(b), o);
  const double in = 25.4;
  struct Circle {
    Eigen::Vector2d c;
    double radius;
    double sign;  // -1: the ring is inside the boundary circle (lobes), +1 outside (necks)
  };
  const Circle circles[] = {{{0, 0}, 2.5 * in, -1},
                            {{5 * in, 0}, 2.0 * in, -1},
                            {{2.875 * in, 2.781074 * in}, 1.5 * in, 1},
                            {{2.875 * in, -2.781074 * in}, 1.5 * in, 1}};
  REQUIRE(rings.size() == 5);
  for (const Ring& r : rings)
    for (const Element& e : r.elements) {
      REQUIRE(e.arc);
      bool matched = false;
      for (const Circle& c : circles)
        if ((e.center - c.c).norm() < 1e-4)  // the file's 6 decimals of an inch
          matched = std::abs((e.start - e.center).norm() - (c.radius + c.sign * r.offset)) < 1e-3;
      CHECK(matched);
    }
}
