// Benchmark (not a test): simulate a program and print the speed figures as JSON, with the
// time per step binned by the number of voxels the step changes.
//   build/tests/bench/bench_simulate PROGRAM TOOL_DIAMETER_MM VOXEL_MM X0 Y0 Z0 X1 Y1 Z1
// e.g. on one core:
//   taskset -c 0 build/tests/bench/bench_simulate data/gcode/bench/finishing_raster.ngc 1 0.2
//       0 0 -10 65 65 0

#include "engine/gcode/GcodeReader.h"
#include "engine/sim/Simulation.h"
#include "stock/VoxelStock.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>

using namespace engage;

int main(int argc, char** argv) {
  if (argc != 10) {
    std::fprintf(stderr, "usage: bench_simulate PROGRAM DIAMETER VOXEL X0 Y0 Z0 X1 Y1 Z1\n");
    return 2;
  }
  const Toolpath path = readProgram(argv[1]);
  const double d = std::atof(argv[2]);
  const double voxel = std::atof(argv[3]);
  Box3 b;
  b.min = {std::atof(argv[4]), std::atof(argv[5]), std::atof(argv[6])};
  b.max = {std::atof(argv[7]), std::atof(argv[8]), std::atof(argv[9])};
  const AptCutter cutter = AptCutter::ball(d, 3 * d);
  VoxelStock stock = VoxelStock::box(b, voxel);
  SimulationOptions o;
  o.timeSteps = true;
  const SimulationResult r = simulate(path, cutter, stock, o);
  // Bins of voxels changed: 0, 1-9, 10-99, 100-999, ...
  std::map<int, std::pair<double, long>> bins;
  for (std::size_t i = 0; i < r.steps.size(); ++i) {
    const long n = r.steps[i].voxelsChanged;
    int bin = 0;
    for (long v = n; v > 0; v /= 10)
      ++bin;
    bins[bin].first += r.stepSeconds[i];
    ++bins[bin].second;
  }
  std::printf(
      "{\"moves\": %zu, \"steps\": %zu, \"seconds\": %.3f, \"steps_per_second\": %.0f, "
      "\"voxels_changed\": %ld, \"voxels_changed_per_second\": %.0f, \"memory_mb\": %.1f, "
      "\"us_per_step_by_voxels_changed\": {",
      path.moves.size(), r.steps.size(), r.seconds, static_cast<double>(r.steps.size()) / r.seconds,
      r.voxelsChanged, static_cast<double>(r.voxelsChanged) / r.seconds,
      static_cast<double>(stock.memoryBytes()) / 1e6);
  bool first = true;
  for (const auto& [bin, v] : bins) {
    const long lo = bin == 0 ? 0 : static_cast<long>(std::pow(10, bin - 1));
    std::printf("%s\"%ld+\": {\"steps\": %ld, \"us\": %.1f}", first ? "" : ", ", lo, v.second,
                1e6 * v.first / static_cast<double>(v.second));
    first = false;
  }
  std::printf("}}\n");
  return 0;
}
