// Benchmark (not a test): per-step removed-volume error against closed forms as the voxel (or
// the dexel ray spacing) shrinks, for a full slot and a side cut (stepover 2 mm) of a 6 mm flat
// end mill, 2 mm deep, cut at 30 deg to the grid in steps of 2.5 cells, and for a helical bore
// (helix radius 1.2 mm, pitch 1 mm, arc pieces of 2.5 cells; in steady state every step removes
// (1.2 + 3)^2 x 1 x dtheta / 2, see tests/stock/DexelStock.cpp); the time per step and the
// stock's memory, for both stock models. Prints one JSON line per model, case and resolution.

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
    for (const std::string name : {"slot", "side_cut_s2", "helix_p1"}) {
      const bool slot = name == "slot";
      const bool helix = name == "helix_p1";
      const double area = slot ? 12.0 : exactCrossSection(c, 2.0, 2.0).area;
      for (double ratio : {10.0, 20.0, 40.0, 80.0}) {
        const double h = 6.0 / ratio;
        const double L = 2.5 * h;
        Box3 b;
        b.min = {-30, -30, helix ? -12.0 : -6.0};  // the bore goes 6 mm down
        b.max = {30, 30, 0};
        std::unique_ptr<Stock> stock;
        if (model == "voxel")
          stock = std::make_unique<VoxelStock>(VoxelStock::box(b, h));
        else
          stock = std::make_unique<DexelStock>(DexelStock::box(b, h));
        Stock& s = *stock;
        if (helix) {
          // Six turns; the last two are measured (the first four reach steady state).
          constexpr double Rh = 1.2, pitch = 1.0;
          const double step = L / Rh;
          const int turn = static_cast<int>(std::round(2.0 * kPi / step));
          auto at = [&](int k) {
            return Eigen::Vector3d(Rh * std::cos(k * step), Rh * std::sin(k * step),
                                   -pitch * k * step / (2.0 * kPi));
          };
          const double expected = (Rh + 3.0) * (Rh + 3.0) * pitch * step / 2.0;
          double worst = 0.0, sum = 0.0, seconds = 0.0;
          int n = 0;
          for (int k = 0; k < 6 * turn; ++k) {
            StepPath p;
            p.kind = StepPath::Kind::ArcXY;
            p.start = at(k);
            p.end = at(k + 1);
            p.center = Eigen::Vector3d::Zero();
            p.sweepRad = step;
            const auto t0 = std::chrono::steady_clock::now();
            const double v = s.remove(Sweep(c, p, h)).volume;
            seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (k >= 4 * turn) {
              worst = std::max(worst, std::abs(v / expected - 1.0));
              sum += v / expected - 1.0;
              ++n;
            }
          }
          std::printf(
              "{\"model\": \"%s\", \"case\": \"%s\", \"D_over_h\": %.0f, \"cell_mm\": %.4f, "
              "\"step_mm\": %.4f, \"steps\": %d, \"worst_step_error\": %.5f, "
              "\"mean_step_error\": %.5f, \"ms_per_step\": %.3f, \"memory_mb\": %.1f}\n",
              model.c_str(), name.c_str(), ratio, h, L, n, worst, sum / n,
              1000.0 * seconds / (6 * turn), static_cast<double>(s.memoryBytes()) / 1e6);
          continue;
        }
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
            model.c_str(), name.c_str(), ratio, h, L, n, worst, sum / n, 1000.0 * seconds / (n + 1),
            static_cast<double>(s.memoryBytes()) / 1e6);
      }
    }
  return 0;
}
