#pragma once
/// \file CubeClip.h
/// Volume of a voxel cut by planes: the voxel is the unit cube [-1/2, 1/2]^3 (coordinates in
/// voxel sizes about its centre) and each half-space keeps {u : n . u <= a}. Exact for planes
/// (one plane in closed form; two by the six tetrahedra of the cube about its diagonal, the
/// last plane in closed form; three or more by clipping the cube as a polyhedron), so one
/// voxel can hold the material between two surfaces (a wall and the cut that crosses it)
/// instead of only a fraction.

#include <Eigen/Core>

namespace engage {

/// {u : n . u <= a}, u in voxel sizes from the voxel's centre. n = 0 with a >= 0 keeps all.
struct HalfSpace {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  double a = 1.0;
  /// The other side: {u : n . u >= a}.
  HalfSpace complement() const { return {-n, -a}; }
};

/// Fraction of the unit cube inside all `count` (at most 9) half-spaces; with `centroid`,
/// also the centroid of that part (the cube's centre, 0, when it is the whole cube or none).
double cubeFraction(const HalfSpace* planes, int count, Eigen::Vector3d* centroid = nullptr);

inline double cubeFraction(const HalfSpace& p) {
  return cubeFraction(&p, 1);
}

/// The plane with outward normal n that leaves `share` of the unit cube inside: the share
/// grows with the offset; regula falsi (Illinois) to 1e-9 of the share.
HalfSpace planeLeaving(const Eigen::Vector3d& n, double share);

/// The mean over the section of the plane {u : n . u = a} (n of unit length) with the unit
/// cube of (u - f)^T K (u - f), f = a n the foot of the cube's centre; 0 where the plane
/// misses the cube. (With K a surface's curvature, half of it is the mean distance from the
/// surface to its tangent plane at f over the voxel.)
double sectionMeanSquare(const HalfSpace& plane, const Eigen::Matrix3d& K);

}  // namespace engage
