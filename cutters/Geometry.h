#pragma once
/// \file Geometry.h
/// Small geometry helpers shared by the cutter, sweep and spline code (mm).

#include <Eigen/Core>

#include <algorithm>

namespace engage {

/// The point of the segment [a, b] closest to p (a when a == b), in 2D or 3D.
template <typename Vector>
Vector closestOnSegment(const Vector& p, const Vector& a, const Vector& b) {
  const Vector d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return a + t * d;
}

/// Distance from p to the segment [a, b] (a point when a == b).
inline double distanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                                const Eigen::Vector2d& b) {
  return (closestOnSegment(p, a, b) - p).norm();
}

}  // namespace engage
