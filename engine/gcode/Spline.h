#pragma once
/// \file Spline.h
/// Flattening of the parametric tool paths of G5 (cubic Bezier), G5.1 (quadratic) and
/// G5.2/G5.3 (NURBS) into line pieces within a chord tolerance.

#include <Eigen/Core>

#include <vector>

namespace engage::gcode {

/// Points after the start (the last one is the curve's end) of a polyline that stays within
/// `tolerance` (mm) of the curve: every piece is bisected until the curve points at 1/4, 1/2
/// and 3/4 of its parameter span lie within the tolerance of its chord. Throws Error when a
/// curve needs more than 100000 pieces (coordinates too large for the tolerance).
std::vector<Eigen::Vector2d> flattenCubic(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                          const Eigen::Vector2d& p2, const Eigen::Vector2d& p3,
                                          double tolerance);
std::vector<Eigen::Vector2d> flattenQuadratic(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                              const Eigen::Vector2d& p2, double tolerance);
/// Rational B-spline of the given order (degree + 1) with a clamped uniform knot vector,
/// as LinuxCNC's G5.2/G5.3. Needs at least `order` control points and positive weights.
std::vector<Eigen::Vector2d> flattenNurbs(const std::vector<Eigen::Vector2d>& controlPoints,
                                          const std::vector<double>& weights, int order,
                                          double tolerance);

}  // namespace engage::gcode
