// Tests of engine/report/SurfaceSteps.h: which step last cut each place of the final surface,
// against the closed form of flat end mill slots (the swept solid's floor is the stadium of
// the tool's radius about the step's segment).

#include "engine/report/SurfaceSteps.h"

#include "engine/gcode/GcodeReader.h"
#include "stock/VoxelStock.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;

namespace {

/// Distance in XY from p to the segment a-b.
double segmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                       const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t =
      ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

}  // namespace

TEST_CASE("the last step to cut a place names it, and rapids and faces never cut name none",
          "[report]") {
  // Two overlapping slots 1 mm deep with a 6 mm flat end mill: along y = 0, then y = 4.
  const Toolpath path = readProgramText(
      "G21 G90 G17\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10 F600\nG0 Z5\nG0 X0 Y4\nG1 Z-1 F100\n"
      "G1 X10 F600\nG0 Z5\nM2\n",
      "slots.ngc");
  const AptCutter cutter = AptCutter::flat(6.0, 18.0);
  Box3 box;
  box.min = {-5.0, -5.0, -3.0};
  box.max = {15.0, 10.0, 0.0};
  VoxelStock stock = VoxelStock::box(box, 0.25);
  const SimulationResult sim = simulate(path, cutter, stock, SimulationOptions{});
  CutterSet cutters;
  cutters.fallback = cutter;
  constexpr double kTolerance = 0.05;  // mm
  const std::vector<std::array<float, 3>> points = {
      {5.0f, -2.0f, -1.0f},  // floor of the first slot only
      {5.0f, 2.0f, -1.0f},   // floor of both: the second cut it last
      {5.0f, 9.0f, 0.0f},    // top face, 2 mm beyond the second slot's wall
      {5.0f, 2.0f, 5.0f},    // on the bottom of the rapid G0 X0 Y4 at Z5, which cuts nothing
  };
  const std::vector<int> last =
      lastCuttingSteps(points, path, sim.steps, cutters, stock.resolution(), kTolerance,
                       0.01 * std::pow(stock.resolution(), 3));
  REQUIRE(last.size() == points.size());
  // The expected steps: on a floor at z = -1, the last cutting step (at z = -1) whose
  // stadium of radius 3 (+ the tolerance: the floor's edge) holds the point.
  auto expected = [&](const std::array<float, 3>& q) {
    int best = -1;
    for (std::size_t i = 0; i < sim.steps.size(); ++i) {
      const StepRecord& s = sim.steps[i];
      const Move& m = path.moves[s.move];
      if (!(s.removed > 0.01 * std::pow(stock.resolution(), 3)) || m.kind != MoveKind::Line)
        continue;
      const StepPath sp = stepPath(m, s.t0, s.t1);
      if (std::abs(sp.start.z() + 1.0) > 1e-9 || std::abs(sp.end.z() + 1.0) > 1e-9) continue;
      if (segmentDistance({q[0], q[1]}, sp.start.head<2>(), sp.end.head<2>()) <= 3.0 + kTolerance)
        best = static_cast<int>(i);
    }
    return best;
  };
  CHECK(last[0] == expected(points[0]));
  CHECK(sim.steps[static_cast<std::size_t>(last[0])].line == 4);
  CHECK(last[1] == expected(points[1]));
  CHECK(sim.steps[static_cast<std::size_t>(last[1])].line == 8);
  CHECK(last[2] == -1);
  CHECK(last[3] == -1);
}
