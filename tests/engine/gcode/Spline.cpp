// Tests of engine/gcode/Spline.h against closed forms: a degree-1 NURBS is its control
// polygon; a one-span quadratic NURBS with unit weights is the quadratic Bezier of its
// control points; with weights (1, sqrt(2)/2, 1) on a right-angle corner it is an exact
// quarter circle.

#include "engine/gcode/Spline.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

using namespace engage::gcode;
using Eigen::Vector2d;

namespace {

/// Largest distance from the closed-form curve f(t), t in [0,1], to the polyline.
template <class F>
double deviation(const Vector2d& start, const std::vector<Vector2d>& pts, F f) {
  std::vector<Vector2d> poly{start};
  poly.insert(poly.end(), pts.begin(), pts.end());
  double worst = 0.0;
  for (int i = 0; i <= 4000; ++i) {
    const Vector2d q = f(i / 4000.0);
    double best = 1e300;
    for (std::size_t k = 0; k + 1 < poly.size(); ++k) {
      const Vector2d d = poly[k + 1] - poly[k];
      const double len2 = d.squaredNorm();
      const double t = len2 > 0 ? std::clamp((q - poly[k]).dot(d) / len2, 0.0, 1.0) : 0.0;
      best = std::min(best, (poly[k] + t * d - q).norm());
    }
    worst = std::max(worst, best);
  }
  return worst;
}

}  // namespace

TEST_CASE("quadratic Bezier within tolerance", "[gcode]") {
  const Vector2d p0(0, 0), p1(5, 5), p2(10, 0);
  const auto pts = flattenQuadratic(p0, p1, p2, 0.001);
  CHECK((pts.back() - p2).norm() < 1e-12);
  CHECK(deviation(p0, pts, [&](double t) {
          return (1 - t) * (1 - t) * p0 + 2 * (1 - t) * t * p1 + t * t * p2;
        }) <= 0.001 + 1e-12);
}

TEST_CASE("NURBS: degree 1 is the control polygon, one quadratic span is a Bezier", "[gcode]") {
  const std::vector<Vector2d> cp{{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  const auto poly = flattenNurbs(cp, {1, 1, 1, 1}, 2, 0.001);
  // Every control point is on the result and nothing strays from the polygon.
  for (const Vector2d& c : cp) {
    double best = (c - cp.front()).norm();
    for (const Vector2d& p : poly)
      best = std::min(best, (p - c).norm());
    CHECK(best < 1e-9);
  }
  const std::vector<Vector2d> q{{0, 0}, {5, 5}, {10, 0}};
  const auto bez = flattenNurbs(q, {1, 1, 1}, 3, 0.001);
  CHECK(deviation(q[0], bez, [&](double t) {
          return (1 - t) * (1 - t) * q[0] + 2 * (1 - t) * t * q[1] + t * t * q[2];
        }) <= 0.001 + 1e-12);
}

TEST_CASE("rational weights: a quarter circle of radius 10 stays within 0.001 mm", "[gcode]") {
  const std::vector<Vector2d> cp{{10, 0}, {10, 10}, {0, 10}};
  const auto arc = flattenNurbs(cp, {1, std::sqrt(0.5), 1}, 3, 0.001);
  for (const Vector2d& p : arc)
    CHECK(p.norm() == Approx(10.0).margin(1e-9));  // vertices on the circle
  // The sagitta of each chord is the deviation: r (1 - cos(half angle)) <= 0.001.
  Vector2d prev = cp.front();
  for (const Vector2d& p : arc) {
    const double half = std::asin(std::min(1.0, (p - prev).norm() / 20.0));
    CHECK(10.0 * (1.0 - std::cos(half)) <= 0.001 + 1e-12);
    prev = p;
  }
}
