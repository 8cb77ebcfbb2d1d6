#pragma once
/// \file SteadyCut.h
/// The measured counterpart of the analytic model's steady state (paper Fig 8): a cutter on
/// a straight or circular path at stepover s and depth d, after a previous pass one
/// stepover away, simulated in the voxel stock; the MRR is measured over the middle of the
/// pass, away from its entry and exit.

#include "cutters/AptCutter.h"
#include "engine/model/EngagementModel.h"

namespace engage {

/// What was measured.
struct SteadyCut {
  double mrr = 0.0;       ///< measured MRR over the middle of the pass, mm^3/min
  std::size_t steps = 0;  ///< steps measured
};

/// Simulate the two passes and measure the second. `path.radius` is the tool-centre radius
/// of the measured pass (concave: the previous pass ran one stepover inside it; convex: one
/// stepover outside; straight: one stepover to the side). Feed mm/min, lengths mm; `voxel`
/// 0 means the cutter diameter / 40. Throws ParameterError for a path tighter than the
/// model allows (EngagementModel::centroidSpeedRatio) or a non-positive size.
SteadyCut measureSteadyCut(const AptCutter& cutter, double stepover, double depth,
                           const PathShape& path, double feed, double voxel = 0.0);

}  // namespace engage
