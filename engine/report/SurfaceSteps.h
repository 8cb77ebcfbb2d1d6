#pragma once
/// \file SurfaceSteps.h
/// Which step of a run last cut the stock's final surface at each point: the latest step
/// that removed material and whose swept solid's surface passes within a tolerance of the
/// point (its signed distance, cutters/Sweep.h). The report colours its 3D view by it (the
/// MRR, force, tool or step that made the surface there).

#include "engine/gcode/Toolpath.h"
#include "engine/sim/Simulation.h"

#include <array>
#include <vector>

namespace engage {

/// Per point, the index of the last step (of `steps`, swept with `cutters` along `path` at
/// sampling `resolution`, mm) that removed more than `minRemoved` mm^3 and whose swept
/// surface lies within `tolerance` mm of it (with `orInside`, or whose swept solid holds it);
/// -1 where none does (faces never cut). The same whatever the thread count (the largest
/// index wins).
std::vector<int> lastCuttingSteps(const std::vector<std::array<float, 3>>& points,
                                  const Toolpath& path, const std::vector<StepRecord>& steps,
                                  const CutterSet& cutters, double resolution, double tolerance,
                                  double minRemoved, bool orInside = false);

}  // namespace engage
