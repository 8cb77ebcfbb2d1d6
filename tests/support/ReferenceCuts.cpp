#include "tests/support/ReferenceCuts.h"

#include "cutters/Numbers.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/sim/Simulation.h"
#include "tests/support/ExactSweep.h"

#include <map>
#include <mutex>

namespace engage::test {

std::vector<ReferenceCase> referenceCases(const std::string& sourceDir) {
  constexpr double kDeg = kPi / 180.0;
  const std::string dir = sourceDir + "/data/gcode/thin/";
  Box3 box;
  box.min = {0.0, 0.0, 0.0};
  box.max = {60.0, 40.0, 10.0};
  const AptCutter flat = AptCutter::flat(6.0, 20.0);
  return {
      {"floor_recut flat", dir + "floor_recut.ngc", flat, box},
      {"skims_ramps flat", dir + "skims_ramps.ngc", flat, box},
      {"pecks_grazes flat", dir + "pecks_grazes.ngc", flat, box},
      {"ball_steps ball", dir + "ball_steps.ngc", AptCutter::ball(6.0, 20.0), box},
      {"bull_taper bull", dir + "bull_taper.ngc", AptCutter::bull(6.0, 1.0, 20.0), box},
      {"bull_taper taper", dir + "bull_taper.ngc", AptCutter::taper(4.0, 10.0 * kDeg, 20.0), box},
  };
}

Toolpath casePath(const ReferenceCase& c) {
  return readProgram(c.program);
}

const std::vector<double>& exactPerMove(const ReferenceCase& c) {
  static std::mutex mutex;
  static std::map<std::string, std::vector<double>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(c.name);
  if (it == cache.end()) {
    const Toolpath path = casePath(c);
    const std::vector<AptCutter> cutters(path.moves.size(), c.cutter);
    it = cache.emplace(c.name, exactRemovals(path, cutters, c.stock)).first;
  }
  return it->second;
}

std::vector<double> measuredPerMove(const ReferenceCase& c, const Toolpath& path, Stock& stock) {
  const SimulationResult r = simulate(path, c.cutter, stock, SimulationOptions{});
  std::vector<double> perMove(path.moves.size(), 0.0);
  for (const StepRecord& s : r.steps)
    perMove.at(s.move) += s.removed;
  return perMove;
}

}  // namespace engage::test
