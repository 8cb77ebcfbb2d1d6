// Benchmark (not a test): per-step removed-volume error against closed forms as the voxel (or
// the dexel ray spacing) shrinks, for a full slot and a side cut (stepover 2 mm) of a 6 mm flat
// end mill, 2 mm deep, cut at 30 deg to the grid in steps of 2.5 cells, and for a helical bore
// (helix radius 1.2 mm, pitch 1 mm, arc pieces of 2.5 cells; in steady state every step removes
// (1.2 + 3)^2 x 1 x dtheta / 2, see tests/stock/DexelStock.cpp); the time per step and the
// stock's memory, for both stock models. Prints one JSON line per model, case and resolution.
// Then, at the default resolution (D/20), the same cases' sensitivity to where the grid falls:
// 5 deg-free ramps (2-10 deg, any direction, any offset to the grid) of a flat and a taper end
// mill against tests/stock/StockTestSupport.h's rampVolume, and the helical bore at 8 offsets of
// its axis to the grid: the worst step and the worst total over the configurations.

#include "cutters/CrossSection.h"
#include "cutters/Numbers.h"
#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"
#include "tests/stock/StockTestSupport.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

using namespace engage;
using test::line;

int main() {
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
        const std::unique_ptr<Stock> stock = test::boxStock(model, b, h);
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
          const double expected = test::helixSteadyStep(Rh, 3.0, pitch, L);
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
  // Sensitivity to the grid, D/20. Configurations from fixed low-discrepancy sequences (the
  // fractional parts of multiples of the golden ratio and of sqrt 2), so every run is the same.
  auto frac = [](double x) { return x - std::floor(x); };
  const double h = 0.3, L = 2.5 * h;
  for (const std::string model : {"voxel", "dexel"}) {
    for (const AptCutter& t : {AptCutter::flat(6.0, 18.0), AptCutter::taper(6.0, kPi / 12, 18.0)}) {
      double worst = 0.0, worstTotal = 0.0;
      const int configs = 8;
      for (int k = 1; k <= configs; ++k) {
        const double angle = 0.5 * kPi * frac(k * 0.6180339887);
        const double alpha = (2.0 + 8.0 * frac(k * 0.4142135624)) * kPi / 180.0;
        const Eigen::Vector3d d(std::cos(angle), std::sin(angle), 0.0);
        const Eigen::Vector3d a =
            -10.0 * d + h * Eigen::Vector3d(frac(k * 0.7548776662), frac(k * 0.5698402910), 0.0);
        Box3 b;
        b.min = {-30, -30, -10};
        b.max = {30, 30, 0};
        const auto stock = test::boxStock(model, b, h);
        const Eigen::Vector3d slope = d + std::tan(alpha) * Eigen::Vector3d(0, 0, -1);
        double total = 0.0;
        const int steps = 30;
        for (int i = 0; i < steps; ++i) {
          const double v =
              stock->remove(Sweep(t, line(a + i * L * slope, a + (i + 1) * L * slope), h)).volume;
          total += v;
          // Steps ending deeper than 1.75 cells, as in tests/stock/VoxelStock.cpp.
          if (i * L * std::tan(alpha) >= 1.75 * h)
            worst = std::max(worst, std::abs(v / (test::rampVolume(t, alpha, (i + 1) * L) -
                                                  test::rampVolume(t, alpha, i * L)) -
                                             1.0));
        }
        worstTotal =
            std::max(worstTotal, std::abs(total / test::rampVolume(t, alpha, steps * L) - 1.0));
      }
      std::printf(
          "{\"model\": \"%s\", \"case\": \"ramp_2_10deg_any_grid\", \"tool\": \"%s\", "
          "\"D_over_h\": 20, \"configurations\": %d, \"worst_step_error\": %.5f, "
          "\"worst_total_error\": %.5f}\n",
          model.c_str(), std::string(shapeName(t.shape())).c_str(), configs, worst, worstTotal);
    }
    {
      double worst = 0.0, worstMean = 0.0;
      const int configs = 8;
      for (int k = 1; k <= configs; ++k) {
        Box3 b;
        b.min = {-8, -8, -8};
        b.max = {8, 8, 0};
        const auto stock = test::boxStock(model, b, h);
        const Eigen::Vector3d centre(h * frac(k * 0.7548776662), h * frac(k * 0.5698402910), 0.0);
        const std::vector<double> v = test::helix(*stock, c, centre, 1.2, 1.0, 6.0, L);
        const double expected = test::helixSteadyStep(1.2, 3.0, 1.0, L);
        const std::size_t skip = v.size() * 4 / 6;
        worst = std::max(worst, test::worstRelative(v, expected, skip));
        worstMean = std::max(worstMean, std::abs(test::meanRelative(v, expected, skip)));
      }
      std::printf(
          "{\"model\": \"%s\", \"case\": \"helix_p1_any_grid\", \"tool\": \"flat\", "
          "\"D_over_h\": 20, \"configurations\": %d, \"worst_step_error\": %.5f, "
          "\"worst_mean_error\": %.5f}\n",
          model.c_str(), configs, worst, worstMean);
    }
  }
  return 0;
}
