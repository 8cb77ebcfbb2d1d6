// Benchmark (not a test): how exactly each stock model reads a cut's contact
// (engine/physics/Engagement.h) against closed forms (tests/support/ContactCases.h), at cells of
// D/20 (the default) and D/40, for a 10 mm flat end mill 3 mm deep:
//  - straight cuts (slot, half immersion up and down, 10 % radial up and down), the stock's top
//    on a grid line or off it and the wall on a grid line or off it: the worst entry/exit angle
//    error (deg), the worst radial depth error (%), and with the linear coefficients of
//    data/materials/aluminium-7075-t6.json (3 teeth, f_z 0.1 mm) the worst error of Fy, Fz and
//    the torque (% of each) and of Fx (% of the resultant);
//  - concave and convex arcs (tool-centre radius 20 mm, stepovers 1, 2.5, 5 mm, both directions
//    of travel, the centre off the grid): the worst radial depth error (%), the worst angle
//    error (deg);
//  - the mean time of one measurement (us);
//  - a random campaign through the simulation (--random N, default 40 programs per model at
//    D/20): a full circle then three quarters of a circle beside it, the diameter 4-16 mm,
//    the depth 0.5-1 D, the tool-centre radius 1.2-10 D, the stepover 5-100 % of D, concave or
//    convex, either direction, the centre anywhere in a cell; over the second arc's steady
//    steps (a diameter from its ends), the median, 95th percentile and worst error of the
//    width against the stepover and of the analytic model (exact form, fed that width)
//    against the measured MRR.
// Prints one JSON line per model and cell, then one per model for the campaign.
// --show: each campaign step whose width is off by more than 2 %, with its program.
//   build/tests/bench/bench_contact [--random N] [--show]

#include "engine/gcode/GcodeReader.h"
#include "engine/physics/CuttingForces.h"
#include "engine/sim/Simulation.h"
#include "tests/support/ContactCases.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

using namespace engage;

namespace {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

/// The random campaign of arcs through simulate() (see the file's comment).
void randomArcs(int count, bool show) {
  for (const char* model : {"dexel", "voxel"}) {
    std::mt19937_64 rng(20261127);
    auto uniform = [&](double a, double b) { return std::uniform_real_distribution<>(a, b)(rng); };
    std::vector<double> width, analytic;
    int programs = 0;
    for (int n = 0; n < count; ++n) {
      const double D = uniform(4.0, 16.0), r = 0.5 * D, d = uniform(0.5, 1.0) * D;
      const double rho = uniform(1.2, 10.0) * D, s = uniform(0.05, 1.0) * D;
      const bool concave = uniform(0, 1) < 0.5, clockwise = uniform(0, 1) < 0.5;
      const double h = D / 20.0, cx = uniform(0, h), cy = uniform(0, h);
      const double rho1 = concave ? rho - s : rho + s;
      if (rho1 <= 0.0 || (!concave && rho - r <= 0.0)) continue;
      const char* g = clockwise ? "G2" : "G3";
      const double end = clockwise ? -0.5 * kPi : 0.5 * kPi;
      char prog[512];
      std::snprintf(prog, sizeof prog,
                    "G21 G90 G17\nG0 X%.6f Y%.6f Z5\nG1 Z%.6f F300\n%s X%.6f Y%.6f I%.6f J0 "
                    "F600\nG0 Z5\nG0 X%.6f Y%.6f\nG1 Z%.6f F300\n%s X%.6f Y%.6f I%.6f J0 "
                    "F600\nG0 Z5\nM2\n",
                    cx + rho1, cy, -d, g, cx + rho1, cy, -rho1, cx + rho, cy, -d, g,
                    cx + rho * std::cos(end), cy + rho * std::sin(end), -rho);
      const Toolpath path = readProgramText(prog, "arcs.ngc");
      const double extent = std::max(rho, rho1) + r + 2.0;
      Box3 b;
      b.min = {-extent, -extent, -d - 5.0};
      b.max = {extent, extent, 0.0};
      std::unique_ptr<Stock> stock = test::boxStock(model, b, h);
      SimulationOptions o;
      const SimulationResult res = simulate(path, AptCutter::flat(D, 3.0 * D), *stock, o);
      ++programs;
      double along = 0.0;
      for (std::size_t i = 1; i + 1 < res.steps.size(); ++i) {
        const StepRecord& st = res.steps[i];
        if (st.line != 8) continue;
        along += st.length;
        if (along < D + 1.0 || along > 1.5 * kPi * rho - D) continue;
        if (!steadyBetween(res.steps[i - 1].mrr, st.mrr, res.steps[i + 1].mrr)) continue;
        width.push_back(std::abs(st.width / s - 1.0));
        if (show && width.back() > 0.02)
          std::printf(
              "  %s D %.4f depth %.4f rho %.4f stepover %.4f %s %s centre %.4f %.4f: "
              "step %zu at (%.3f, %.3f) width %.4f\n",
              model, D, d, rho, s, concave ? "concave" : "convex", g, cx, cy, i, st.end.x(),
              st.end.y(), st.width);
        analytic.push_back(std::abs(st.mrr / st.mrrExact - 1.0));
      }
    }
    std::printf(
        "{\"model\": \"%s\", \"random_arcs\": %d, \"steady_steps\": %zu, "
        "\"width_pct\": [%.3f, %.3f, %.3f], \"analytic_pct\": [%.3f, %.3f, %.3f]}\n",
        model, programs, width.size(), 100 * quantile(width, 0.5), 100 * quantile(width, 0.95),
        100 * quantile(width, 1.0), 100 * quantile(analytic, 0.5), 100 * quantile(analytic, 0.95),
        100 * quantile(analytic, 1.0));
  }
}

}  // namespace

int main(int argc, char** argv) {
  int random = 40;
  bool show = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--random") == 0 && i + 1 < argc) random = std::atoi(argv[++i]);
    if (std::strcmp(argv[i], "--show") == 0) show = true;
  }
  const double R = 5.0, ap = 3.0, c = 0.1;
  const int N = 3;
  Material m;
  m.model = ForceModel::Linear;
  m.linear = {767.01, 168.8, 222.0, 27.7, 26.6, 0.7};  // aluminium-7075-t6.json
  struct Straight {
    double ae;
    bool left;
  };
  for (const char* model : {"dexel", "voxel"})
    for (const double cells : {20.0, 40.0}) {
      const double h = 2 * R / cells;
      double angle = 0.0, width = 0.0, force = 0.0, fx = 0.0;
      for (const double top : {0.0, 0.37})
        for (const double across : {0.0, 0.29})
          for (const Straight& k : {Straight{2 * R, true}, Straight{R, true}, Straight{R, false},
                                    Straight{0.2 * R, true}, Straight{0.2 * R, false}}) {
            const EdgeEngagement e =
                test::straightContact(model, h, R, ap, k.ae, k.left, top, across);
            const std::array<double, 2> want = test::straightAngles(R, k.ae, k.left);
            angle = std::max({angle, std::abs(e.entry - want[0]), std::abs(e.exit - want[1])});
            width = std::max(width, std::abs(radialDepth(e) / k.ae - 1.0));
            const StepLoad load = cuttingLoad(e, m, {N, 0.0, R}, c, 10000.0);
            const test::MeanLoad closed =
                test::linearMeanLoad(m.linear, N, ap, c, R, want[0], want[1]);
            force = std::max({force, std::abs(load.force.y() / closed.fy - 1.0),
                              std::abs(load.force.z() / closed.fz - 1.0),
                              std::abs(load.torque / closed.torque - 1.0)});
            fx = std::max(fx,
                          std::abs(load.force.x() - closed.fx) / std::hypot(closed.fx, closed.fy));
          }
      double arcWidth = 0.0, arcAngle = 0.0;
      const Eigen::Vector3d centre(0.137, -0.261, 0.0);
      for (const bool concave : {true, false})
        for (const bool clockwise : {true, false})
          for (const double ae : {1.0, 2.5, 5.0}) {
            const double rho = 20.0;
            const EdgeEngagement e = test::arcContact(
                model, h, R, ap, rho, concave ? rho - ae : rho + ae, clockwise, centre);
            const std::array<double, 2> want = test::arcAngles(R, rho, ae, concave, clockwise);
            arcAngle =
                std::max({arcAngle, std::abs(e.entry - want[0]), std::abs(e.exit - want[1])});
            arcWidth = std::max(arcWidth, std::abs(radialDepth(e) / ae - 1.0));
          }
      // The measurement alone: one slot's contact read again and again.
      Box3 b;
      b.min = {-30, -20, -20};
      b.max = {30, 20, 0};
      std::unique_ptr<Stock> s = test::boxStock(model, b, h);
      const AptCutter flat = AptCutter::flat(2 * R, 20.0);
      s->remove(Sweep(flat, test::line({-40, 0.3, -ap}, {0, 0.3, -ap}), h));
      const auto t0 = std::chrono::steady_clock::now();
      const int reps = 200;
      for (int k = 0; k < reps; ++k)
        (void)measureEngagement(*s, flat, {0, 0.3, -ap}, {1.0, 0.0}, true, ap + h);
      const double us =
          1e6 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / reps;
      std::printf(
          "{\"model\": \"%s\", \"cell\": \"D/%.0f\", \"straight_angle_deg\": %.3f, "
          "\"straight_width_pct\": %.3f, \"force_pct\": %.3f, \"fx_pct_of_resultant\": %.3f, "
          "\"arc_width_pct\": %.3f, \"arc_angle_deg\": %.3f, \"slot_measurement_us\": %.0f}\n",
          model, cells, angle * kDegPerRad, 100 * width, 100 * force, 100 * fx, 100 * arcWidth,
          arcAngle * kDegPerRad, us);
    }
  randomArcs(random, show);
}
