// Benchmark (not a test): per-step removed-volume error against closed forms as the voxel (or
// the dexel ray spacing) shrinks, for a full slot and a side cut (stepover 2 mm) of a 6 mm flat
// end mill, 2 mm deep, cut at 30 deg to the grid in steps of 2.5 cells; the time per step and
// the stock's memory, for both stock models. Prints one JSON line per model, case and
// resolution.

#include "cutters/CrossSection.h"
#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

using namespace engage;

int main() {
  constexpr double kPi = 3.14159265358979323846;
  const Eigen::Vector3d dir(std::cos(kPi / 6), std::sin(kPi / 6), 0.0);
  const Eigen::Vector3d side(-std::sin(kPi / 6), std::cos(kPi / 6), 0.0);
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  for (const std::string model : {"voxel", "dexel"})
    for (const char* name : {"slot", "side_cut_s2"}) {
      const bool slot = name[0] == 's' && name[1] == 'l';
      const double area = slot ? 12.0 : exactCrossSection(c, 2.0, 2.0).area;
      for (double ratio : {10.0, 20.0, 40.0, 80.0}) {
        const double h = 6.0 / ratio;
        const double L = 2.5 * h;
        Box3 b;
        b.min = {-30, -30, -6};
        b.max = {30, 30, 0};
        std::unique_ptr<Stock> stock;
        if (model == "voxel")
          stock = std::make_unique<VoxelStock>(VoxelStock::box(b, h));
        else
          stock = std::make_unique<DexelStock>(DexelStock::box(b, h));
        Stock& s = *stock;
        auto line = [](const Eigen::Vector3d& a, const Eigen::Vector3d& e) {
          StepPath p;
          p.start = a;
          p.end = e;
          return p;
        };
        const Eigen::Vector3d a = Eigen::Vector3d(0, 0, -2) - 8.0 * dir;
        // The previous pass reaches well beyond both ends of the measured one (steady state).
        if (!slot)
          for (double t = -8.0; t < 24.0; t += 4.0)
            s.remove(Sweep(c, line(a - 2.0 * side + t * dir, a - 2.0 * side + (t + 4.0) * dir), h));
        s.remove(Sweep(c, line(a, a), h));
        double worst = 0.0, sum = 0.0;
        int n = 0;
        const auto t0 = std::chrono::steady_clock::now();
        for (double t = 0.0; t + L <= 16.0; t += L) {
          const double v = s.remove(Sweep(c, line(a + t * dir, a + (t + L) * dir), h)).volume;
          if (t > 0.0) {
            const double rel = v / (area * L) - 1.0;
            worst = std::max(worst, std::abs(rel));
            sum += rel;
            ++n;
          }
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf(
            "{\"model\": \"%s\", \"case\": \"%s\", \"D_over_h\": %.0f, \"cell_mm\": %.4f, "
            "\"step_mm\": %.4f, \"steps\": %d, \"worst_step_error\": %.5f, "
            "\"mean_step_error\": %.5f, \"ms_per_step\": %.3f, \"memory_mb\": %.1f}\n",
            model.c_str(), name, ratio, h, L, n, worst, sum / n, 1000.0 * seconds / (n + 1),
            static_cast<double>(s.memoryBytes()) / 1e6);
      }
    }
  return 0;
}
