#pragma once
/// \file ProbeContact.h
/// Where a probing move (G38.2, G38.3) first touches a box of stock: the probe is the tool in
/// the spindle, a cylinder of its radius standing on its tip (the controlled point), so it
/// touches where the tip is at or below the box's top and within a radius of the box's
/// outline in XY. Both sets are intervals of the move's parameter (the tip moves on a line, the
/// outline grown by the radius is convex), so the first touch is where both have begun.

#include "cutters/AptCutter.h"

#include <Eigen/Core>

namespace engage {

/// The fraction t in [0, 1] of the move from `from` to `to` (mm) at which a probe of `radius`
/// (mm) first touches `box`; a value above 1 when it touches nowhere on the move. Exact to
/// 1e-12 of the move.
double probeContact(const Box3& box, double radius, const Eigen::Vector3d& from,
                    const Eigen::Vector3d& to);

}  // namespace engage
