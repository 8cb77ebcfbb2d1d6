#pragma once
/// \file DexelSolid.h
/// Where a step's swept cutter meets one ray of the dexel stock (private to stock/): the z
/// intervals of the swept solid along the ray of a column, with the share of the column's
/// cross-section each covers, in closed form for steps that keep their height and for plunges
/// and retracts, by search along ramps and helices. DexelStock.cpp cuts the rays' material
/// with them.

#include "cutters/AptCutter.h"
#include "cutters/Sweep.h"
#include "stock/DexelStock.h"

#include <Eigen/Core>

#include <vector>

namespace engage::dexel {

using Interval = DexelStock::Interval;

/// Does the cutter's radius never shrink upwards (so that a vertical line at distance rho
/// from its axis meets it in one interval from the profile's lowest height at rho up)? For
/// the APT profile: unless its sides lean inward (beta < 0), the rule Sweep uses for convexity.
bool widensUpwards(const AptCutter& c);

/// The swept solid along the ray of column q (spacing h) below `rayTop` of a step that keeps
/// its height, or a plunge or retract (the cutter from its lowest to its highest position), of
/// a cutter that widens upwards, in closed form: appended to `solid`; false where it cannot
/// reach the ray's material.
bool steadySolid(const StepPath& path, const AptCutter& cutter, const Eigen::Vector2d& q, double h,
                 double rayTop, std::vector<Interval>& solid);

/// rampBand, and where it finds nothing (its h/2 margin short of a column's corner that the
/// cutter reaches at the step's end or start), the cutter there as a plunge or retract takes
/// it: a retract after a ramp had taken up to 0.0012 mm^3 from nothing, the corners the ramp
/// left (tests/stock/ReferenceCuts.cpp). (Not the union with the two ends everywhere: their
/// approximate shares would be taken above the band's.)
void rampSolid(const StepPath& path, const AptCutter& cutter, const Eigen::Vector2d& q, double h,
               double rayTop, std::vector<Interval>& solid);

}  // namespace engage::dexel
