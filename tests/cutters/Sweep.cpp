// Tests of cutters/Sweep.h: distances to swept solids against hand values.

#include "cutters/Sweep.h"
#include "cutters/Numbers.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;

namespace {

/// The XY arc of radius 10 about the origin from (10, 0) to (0, 10), counter-clockwise.
StepPath quarterArc() {
  StepPath p;
  p.kind = StepPath::Kind::ArcXY;
  p.center = {0, 0, 0};
  p.start = {10, 0, 0};
  p.end = {0, 10, 0};
  p.sweepRad = kPi / 2;
  return p;
}
}  // namespace

TEST_CASE("a horizontal line sweeps a stadium of the profile", "[cutters]") {
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  StepPath p;
  p.start = {0, 0, 0};
  p.end = {10, 0, 0};
  const Sweep s(c, p, 0.1);
  CHECK(s.signedDistance({5, 4, 1}) == Approx(1.0));   // beside the middle: 4 - r
  CHECK(s.signedDistance({13, 0, 1}) == Approx(0.0));  // on the end cap
  CHECK(s.signedDistance({14, 3, 1}) == Approx(2.0));  // |(14,3)-(10,0)| - 3
  CHECK(s.signedDistance({5, 0, 1}) == Approx(-1.0));  // inside: 1 above the bottom
  CHECK(s.signedDistance({5, 0, -2}) == Approx(2.0));  // below the bottom
  CHECK(s.bounds().min.x() == Approx(-3.0));
  CHECK(s.bounds().max.x() == Approx(13.0));
}

TEST_CASE("a horizontal arc sweeps a torus-like band", "[cutters]") {
  const AptCutter c = AptCutter::flat(2.0, 10.0);
  const Sweep s(c, quarterArc(), 0.1);
  const double a = kPi / 4;
  CHECK(s.signedDistance({12 * std::cos(a), 12 * std::sin(a), 1}) == Approx(1.0));  // 2 out - r
  CHECK(s.signedDistance({8 * std::cos(a), 8 * std::sin(a), 1}) == Approx(1.0));
  CHECK(s.signedDistance({10, -3, 1}) == Approx(2.0));  // past the start: 3 from (10,0) - r
  CHECK(s.bounds().max.y() == Approx(11.0));
}

TEST_CASE("a plunge and a ramp take the closest tool position", "[cutters]") {
  const AptCutter c = AptCutter::flat(2.0, 10.0);
  StepPath p;
  p.start = {0, 0, 0};
  p.end = {0, 0, -5};
  const Sweep plunge(c, p, 0.1);
  CHECK(plunge.signedDistance({3, 0, -2}) == Approx(2.0).margin(1e-6));
  CHECK(plunge.signedDistance({0, 0, -6}) == Approx(1.0).margin(1e-6));
  // Ramp: the tip follows z = -x/2. Below the path the swept bottom is the plane traced by
  // the leading edge, z = -(x + r)/2; the point (4, 0, -3) is 0.5 below it at x = 4, so
  // 0.5 / sqrt(1.25) from the plane.
  p.end = {10, 0, -5};
  const Sweep ramp(c, p, 0.1);
  // Golden-section search to 0.8 % of the step: the distance is found within 1e-4 mm.
  CHECK(ramp.signedDistance({4, 0, -3}) == Approx(0.5 / std::sqrt(1.25)).margin(1e-4));
}

TEST_CASE("a ball end mill's ramp is a thickened parallelogram", "[cutters]") {
  // Ball D 6 (r 3), flute 18, from (0,0,0) down to (10,0,-1): the ball centre runs from
  // (0,0,3) to (10,0,2). Hand values: beside the middle at the centre's height, 4 away: 1.
  const AptCutter c = AptCutter::ball(6.0, 18.0);
  StepPath p;
  p.start = {0, 0, 0};
  p.end = {10, 0, -1};
  const Sweep s(c, p, 0.1);
  CHECK(s.signedDistance({5, 4, 2.5}) == Approx(1.0).margin(1e-12));
  // Below and behind the start: the distance to the centre's line (it projects just inside
  // the segment), |v x a| / |a| - r with v = (-0.3, 0, -4), a = (10, 0, -1): 40.3/sqrt(101) - 3.
  CHECK(s.signedDistance({-0.3, 0, -1}) == Approx(40.3 / std::sqrt(101.0) - 3.0).margin(1e-12));
  // Outside: the same as the nearest of many tool positions (independent brute force).
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(3, 3.5, 1), Eigen::Vector3d(13, 1, 0),
                                   Eigen::Vector3d(7, -2, -2.5), Eigen::Vector3d(-2, 3, 4)}) {
    double brute = 1e300;
    for (int k = 0; k <= 20000; ++k)
      brute = std::min(brute, c.signedDistance(q - p.at(k / 20000.0)));
    INFO(q.transpose());
    REQUIRE(brute > 0.0);
    CHECK(s.signedDistance(q) == Approx(brute).margin(1e-6));  // sampling: < 1e-7 mm
  }
  // Inside: at least as deep as under the deepest single position (the union's surface is
  // no nearer than any one tool's).
  const Eigen::Vector3d inside(5, 0.5, 1.5);
  double deepest = 1e300;
  for (int k = 0; k <= 2000; ++k)
    deepest = std::min(deepest, c.signedDistance(inside - p.at(k / 2000.0)));
  CHECK(s.signedDistance(inside) <= deepest + 1e-9);
  // The gradient points away from the solid, unit length.
  Eigen::Vector3d g;
  s.signedDistance({5, 4, 2.5}, &g);
  CHECK(g.y() == Approx(1.0).margin(1e-9));
  CHECK(g.norm() == Approx(1.0));
}

TEST_CASE("near a flat bottom's rim the swept solid is two faces", "[cutters]") {
  // A flat end mill (r = 3) along +X at z = 0: the slot's side at y = 3 and its floor at
  // z = 0 meet at the rim. Beside the rim: the floor's face (normal -z, distance -z) and the
  // side's (normal +y, distance y - 3), exactly (both faces are planes here).
  const AptCutter flat = AptCutter::flat(6.0, 18.0);
  REQUIRE(flat.corners().size() == 2);  // the bottom rim and the top rim
  CHECK(flat.corners()[0].at.isApprox(Eigen::Vector2d(3.0, 0.0)));
  CHECK(AptCutter::ball(6.0, 18.0).corners().size() == 1);  // only the top rim
  StepPath p;
  p.start = {0, 0, 0};
  p.end = {10, 0, 0};
  const Sweep s(flat, p, 0.1);
  Eigen::Vector3d n[2];
  double d[2];
  int count = 0;
  s.localFaces({5.0, 3.05, -0.02}, 0.2, n, d, count);
  REQUIRE(count == 2);
  CHECK((n[0] - Eigen::Vector3d(0, 0, -1)).norm() < 1e-12);
  CHECK(d[0] == Approx(0.02).margin(1e-12));
  CHECK((n[1] - Eigen::Vector3d(0, 1, 0)).norm() < 1e-12);
  CHECK(d[1] == Approx(0.05).margin(1e-12));
  // Away from the rim: one face, the tangent plane of the distance (the floor here).
  s.localFaces({5.0, 1.0, -0.05}, 0.2, n, d, count);
  REQUIRE(count == 1);
  CHECK((n[0] - Eigen::Vector3d(0, 0, -1)).norm() < 1e-9);
  CHECK(d[0] == Approx(0.05).margin(1e-9));
  // A plunge keeps its lowest rim: the same two faces at the bottom of its cylinder.
  StepPath plunge;
  plunge.start = {0, 0, 5};
  plunge.end = {0, 0, 0};
  const Sweep down(flat, plunge, 0.1);
  down.localFaces({3.05, 0.0, -0.02}, 0.2, n, d, count);
  REQUIRE(count == 2);
  CHECK((n[1] - Eigen::Vector3d(1, 0, 0)).norm() < 1e-12);
  CHECK(d[1] == Approx(0.05).margin(1e-12));
}

TEST_CASE("the swept surface's curvature at the point nearest", "[cutters]") {
  // Closed forms: a wall beside a straight pass is flat; a ball's tip a sphere of its
  // radius; a flat end mill's side on an XY arc of radius R a cylinder of R + r outside and
  // R - r inside (negative: the solid is outside it); a ball's straight ramp a cylinder of r
  // about the path of its centre below it, flat beside. Second differences at a quarter resolution
  // (0.025 mm) of the closed-form profile distance: 1e-6 relative; the golden-section search of a
  // plunge: 1e-3 relative.
  Eigen::Vector3d g;
  Eigen::Matrix3d K;
  auto trace = [&](const Sweep& s, const Eigen::Vector3d& p) {
    s.signedDistance(p, &g, &K);
    return K.trace();
  };
  const AptCutter flat = AptCutter::flat(6.0, 18.0), ball = AptCutter::ball(6.0, 18.0);
  StepPath line;
  line.start = {0, 0, 0};
  line.end = {10, 0, 0};
  CHECK(trace(Sweep(flat, line, 0.1), {5.0, 3.02, 1.0}) == Approx(0.0).margin(1e-9));
  // Beside the end: the tool's own cylinder, across the wall only.
  CHECK(trace(Sweep(flat, line, 0.1), {13.02, 0.0, 1.0}) == Approx(1.0 / 3.0).epsilon(1e-6));
  CHECK(K(2, 2) == Approx(0.0).margin(1e-9));
  // Where the tangent plane misses the cube of side `resolution` about the point (0.2 from
  // the surface here), it is not wanted: zero.
  CHECK(trace(Sweep(flat, line, 0.1), {13.2, 0.0, 1.0}) == 0.0);
  StepPath plunge;
  plunge.start = {0, 0, 5};
  plunge.end = {0, 0, 0};
  // Below the tip: the sphere, curvature 1/3 both ways (trace 2/3).
  CHECK(trace(Sweep(ball, plunge, 0.1), {0.3, 0.2, -0.02}) == Approx(2.0 / 3.0).epsilon(1e-3));
  const double a = kPi / 4;
  const Sweep band(flat, quarterArc(), 0.1);
  CHECK(trace(band, {13.02 * std::cos(a), 13.02 * std::sin(a), 1.0}) ==
        Approx(1.0 / 13.0).epsilon(1e-6));
  CHECK(trace(band, {6.98 * std::cos(a), 6.98 * std::sin(a), 1.0}) ==
        Approx(-1.0 / 7.0).epsilon(1e-6));
  StepPath ramp;
  ramp.start = {0, 0, 0};
  ramp.end = {10, 0, -2};
  const Sweep capsule(ball, ramp, 0.1);
  // 3.02 below the ball centre at x = 5, (5, 0, 2), normal to the path: r + 0.02 from it.
  const Eigen::Vector3d across = Eigen::Vector3d(2.0, 0.0, 10.0).normalized();
  CHECK(trace(capsule, Eigen::Vector3d(5.0, 0.0, 2.0) - 3.02 * across) ==
        Approx(1.0 / 3.0).epsilon(1e-9));
  CHECK(trace(capsule, {5.0, 3.02, 2.5}) == 0.0);  // beside: the side swept flat
}

TEST_CASE("the support function of a straight step's swept solid", "[cutters]") {
  // The swept solid of a straight step is the hull of the cutter at its two ends, so its
  // support in a direction n is the larger of the two copies'. Hand-computed for a 6 mm flat
  // end mill (flute length 20: its profile's corners at rho 3, z 0 and 20) and a 6 mm ball
  // (centre 3 above the tip: in a direction at theta from straight down, 3 - 3 cos theta).
  StepPath p;
  p.start = {1.0, 2.0, 5.0};
  p.end = {11.0, 2.0, 4.0};  // a ramp down along +X
  const Sweep flat(AptCutter::flat(6.0, 20.0), p, 0.3);
  CHECK(flat.convexLine());
  CHECK(flat.support({0.0, 0.0, -1.0}) == Approx(-4.0));  // the end's flat bottom
  CHECK(flat.support({0.0, 0.0, 1.0}) == Approx(25.0));   // the start's top
  CHECK(flat.support({1.0, 0.0, 0.0}) == Approx(14.0));   // the end's side
  CHECK(flat.support({0.0, -1.0, 0.0}) == Approx(1.0));   // a side of both
  const double c = std::cos(0.3), s = std::sin(0.3);
  // Down and back (-X): the rim point facing -X of whichever copy reaches further, 3 s out.
  CHECK(flat.support({-s, 0.0, -c}) ==
        Approx(std::max(-s * 1.0 - c * 5.0, -s * 11.0 - c * 4.0) + 3.0 * s));
  const Sweep ball(AptCutter::ball(6.0, 20.0), p, 0.3);
  const Eigen::Vector3d n(s, 0.0, -c);
  CHECK(ball.support(n) == Approx(3.0 - 3.0 * c + std::max(n.dot(p.start), n.dot(p.end))));
}

namespace {
/// A straight step from tip `from` to `to` of a tool lying along +Y.
StepPath lyingAlongY(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  StepPath p;
  p.start = from;
  p.end = to;
  p.axisStart = p.axisEnd = {0, 1, 0};
  return p;
}
}  // namespace

TEST_CASE("a tilted tool that keeps its axis sweeps the upright solid turned", "[cutters]") {
  // A flat end mill lying along +Y (a 90 deg tilt), its end face at y = 5, its axis at z = -1,
  // moving along X from 0 to 20: a box of x -3..23 (rounded ends), y 5..35, z -4..2. Hand
  // values: outside, the distance to the nearest face; inside, the depth below the nearest
  // instance's surface. 1e-9 mm is round-off.
  const Sweep s(AptCutter::flat(6.0, 30.0), lyingAlongY({0, 5, -1}, {20, 5, -1}), 0.1);
  CHECK(s.signedDistance({10, 4, -1}) == Approx(1.0).margin(1e-9));    // before the end face
  CHECK(s.signedDistance({10, 20, 3}) == Approx(1.0).margin(1e-9));    // above the side
  CHECK(s.signedDistance({10, 20, -1}) == Approx(-3.0).margin(1e-9));  // on the axis
  CHECK(s.signedDistance({25, 20, -1}) == Approx(2.0).margin(1e-9));   // beyond the end's rim
  CHECK(s.signedDistance({10, 36, -1}) == Approx(1.0).margin(1e-9));   // beyond the shank's end
  Eigen::Vector3d g;
  s.signedDistance({10, 20, 2.5}, &g);
  CHECK((g - Eigen::Vector3d(0, 0, 1)).norm() < 1e-6);  // (central differences)
  // The bounds hold the turned cylinder at both ends, no more.
  CHECK(s.bounds().min.x() == Approx(-3.0).margin(1e-9));
  CHECK(s.bounds().max.x() == Approx(23.0).margin(1e-9));
  CHECK(s.bounds().min.y() == Approx(5.0).margin(1e-9));
  CHECK(s.bounds().max.y() == Approx(35.0).margin(1e-9));
  CHECK(s.bounds().min.z() == Approx(-4.0).margin(1e-9));
  CHECK(s.bounds().max.z() == Approx(2.0).margin(1e-9));
  // The support plane along +Z touches the top of the lying cylinder, exactly.
  CHECK(s.support({0, 0, 1}) == Approx(2.0).margin(1e-9));
}

TEST_CASE("a tilted plunge's faces near the rim are the turned solid's", "[cutters]") {
  // The same flat end mill lying along +Y, plunging along its axis from its end face at y = 5
  // to y = 3 (axis at x 10, z -1). Beside the rim the swept solid is the cylinder's side and
  // end face: at (10, 2.9, -1 + 3.05) the side is 0.05 mm and the end face 0.1 mm away
  // (outside both: the corner's distance is their hypotenuse), and localFaces gives the two
  // faces turned to the part (normals +Z and -Y) with the distance signedDistance gives.
  const Sweep s(AptCutter::flat(6.0, 30.0), lyingAlongY({10, 5, -1}, {10, 3, -1}), 0.1);
  const Eigen::Vector3d q(10, 2.9, 2.05);
  Eigen::Vector3d normals[2];
  double distances[2];
  int count = 0;
  const double d = s.localFaces(q, 0.3, normals, distances, count);
  CHECK(d == Approx(std::hypot(0.05, 0.1)).margin(1e-9));
  CHECK(d == Approx(s.signedDistance(q)).margin(1e-9));
  REQUIRE(count == 2);
  const bool sideFirst = std::abs(normals[0].z()) > 0.5;
  const Eigen::Vector3d side = normals[sideFirst ? 0 : 1], end = normals[sideFirst ? 1 : 0];
  CHECK((side - Eigen::Vector3d(0, 0, 1)).norm() < 1e-9);
  CHECK((end - Eigen::Vector3d(0, -1, 0)).norm() < 1e-9);
  CHECK(distances[sideFirst ? 0 : 1] == Approx(0.05).margin(1e-9));
  CHECK(distances[sideFirst ? 1 : 0] == Approx(0.1).margin(1e-9));
}

TEST_CASE("a ball end mill turned about its centre sweeps the ball", "[cutters]") {
  // The axis turns 30 deg from +Z towards +X about the ball's centre c (the tip on the ball,
  // at even steps of the turn): below and beside the centre the swept solid is the ball.
  // Points within the resolution of the surface (beyond it only the sign is kept); the
  // instances are sampled every half resolution of travel and refined by golden section:
  // 1e-6 mm covers the refinement.
  const double r = 3.0;
  const AptCutter c = AptCutter::ball(2.0 * r, 18.0);
  const Eigen::Vector3d centre(10, 10, 2);
  StepPath p;
  p.kind = StepPath::Kind::Polyline;
  p.axisStart = {0, 0, 1};
  p.axisEnd = {std::sin(kPi / 6), 0, std::cos(kPi / 6)};
  for (int i = 0; i <= 8; ++i)
    p.points.push_back(centre - r * p.axisAt(i / 8.0));
  p.start = p.points.front();
  p.end = p.points.back();
  const Sweep s(c, p, 0.1);
  CHECK(s.signedDistance(centre - Eigen::Vector3d(0, 0, r + 0.05)) == Approx(0.05).margin(1e-6));
  CHECK(s.signedDistance(centre + Eigen::Vector3d(0, -(r + 0.02), 0)) == Approx(0.02).margin(1e-6));
  const Eigen::Vector3d down(-std::sin(kPi / 12), 0, -std::cos(kPi / 12));  // mid-turn's tip side
  CHECK(s.signedDistance(centre + (r + 0.03) * down) == Approx(0.03).margin(1e-6));
  CHECK(s.signedDistance(centre + (r - 0.04) * down) == Approx(-0.04).margin(1e-6));
  CHECK(s.signedDistance(centre - Eigen::Vector3d(0, 0, r + 2.0)) > 0.0);  // far: the sign
  CHECK(s.signedDistance(centre) == Approx(-r).margin(1e-6));
  // Above the equator on +X, 0.45 mm outside the ball, the shank turned towards +X covers it.
  const Eigen::Vector3d side = centre + Eigen::Vector3d(r + 0.3, 0, 1.0);
  CHECK(s.signedDistance(side) < 0.0);
}
