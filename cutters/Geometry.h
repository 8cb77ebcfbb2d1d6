#pragma once
/// \file Geometry.h
/// Small plane-geometry helpers shared by the cutter, sweep and spline code (mm).

#include <Eigen/Core>

#include <algorithm>

namespace engage {

/// Distance from p to the segment [a, b] (a point when a == b).
inline double distanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                                const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

}  // namespace engage
