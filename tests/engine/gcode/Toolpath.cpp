// Tests of engine/gcode/Toolpath.h helpers against hand values.

#include "engine/gcode/Toolpath.h"
#include "cutters/Numbers.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;

namespace {
Move arc(Eigen::Vector3d s, Eigen::Vector3d e, Eigen::Vector3d c, int turns,
         Plane plane = Plane::XY) {
  Move m;
  m.kind = MoveKind::Arc;
  m.start = s;
  m.end = e;
  m.center = c;
  m.turns = turns;
  m.plane = plane;
  return m;
}
}  // namespace

TEST_CASE("arc sweep, length and points", "[gcode]") {
  // Quarter circle radius 10 counter-clockwise from (10,0) to (0,10): length 5 pi.
  const Move q = arc({10, 0, 0}, {0, 10, 0}, {0, 0, 0}, 1);
  CHECK(arcRadius(q) == Approx(10.0));
  CHECK(arcSweep(q) == Approx(kPi / 2));
  CHECK(moveLength(q) == Approx(5 * kPi));
  const Eigen::Vector3d mid = pointAt(q, 0.5);
  CHECK(mid.x() == Approx(10 * std::cos(kPi / 4)));
  CHECK(mid.y() == Approx(10 * std::sin(kPi / 4)));
  // The same end points clockwise: three quarters, negative.
  const Move cw = arc({10, 0, 0}, {0, 10, 0}, {0, 0, 0}, -1);
  CHECK(arcSweep(cw) == Approx(-3 * kPi / 2));
  // A closed circle is a full turn; P2 makes two.
  CHECK(arcSweep(arc({10, 0, 0}, {10, 0, 0}, {0, 0, 0}, 2)) == Approx(4 * kPi));
  // G19 (YZ) arcs turn about +X: from (0,10,0) CCW a quarter about the origin reaches z = 10.
  const Move yz = arc({0, 10, 0}, {0, 0, 10}, {0, 0, 0}, 1, Plane::YZ);
  CHECK(arcSweep(yz) == Approx(kPi / 2));
}

TEST_CASE("lines and splines: length and interpolation", "[gcode]") {
  Move l;
  l.start = {0, 0, 0};
  l.end = {3, 4, 0};
  CHECK(moveLength(l) == Approx(5.0));
  CHECK(pointAt(l, 0.2).x() == Approx(0.6));
  Move s;
  s.kind = MoveKind::Spline;
  s.start = {0, 0, 0};
  s.points = {{1, 0, 0}, {1, 1, 0}};
  s.end = s.points.back();
  CHECK(moveLength(s) == Approx(2.0));
  CHECK(pointAt(s, 0.75).y() == Approx(0.5));
}
