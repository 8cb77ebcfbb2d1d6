// Benchmark (not a test): per-move removed-volume error of both stock models against the exact
// reference (tests/support/ExactSweep.h) on the thin- and grazing-cut programs of
// data/gcode/thin, at cells of D/10, D/20 (the default) and D/40 (D: twice the cutter's APT r,
// 6 mm, and the taper's 4 mm tip).
// Prints one JSON line per model and cell: the worst total error over the programs; over the
// moves that remove at least 1 mm^3, the median, 95th percentile and worst relative error; over
// the smaller ones, the worst error in cell volumes; and the most removed by a move that removes
// nothing in the reference. With --moves, every move's figures first; with --faceting, the
// reference against itself at a coarser faceting instead.
//   build/tests/bench/bench_thin_cuts [--moves | --faceting [PROGRAM]]

#include "tests/stock/StockTestSupport.h"
#include "tests/support/ExactSweep.h"
#include "tests/support/ReferenceCuts.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

using namespace engage;

namespace {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::floor(q * static_cast<double>(v.size() - 1) + 0.5))];
}

}  // namespace

int run(int argc, char** argv) {
  const bool moves = argc > 1 && std::strcmp(argv[1], "--moves") == 0;
  const bool faceting = argc > 1 && std::strcmp(argv[1], "--faceting") == 0;
  if (argc > 3 || (argc > 1 && !moves && !faceting)) {
    std::fprintf(stderr, "usage: bench_thin_cuts [--moves | --faceting [PROGRAM]]\n");
    return 2;
  }
  // An optional last argument keeps the programs whose name contains it.
  std::vector<test::ReferenceCase> cases = test::referenceCases(ENGAGE_SOURCE_DIR);
  if (argc > 2)
    cases.erase(std::remove_if(cases.begin(), cases.end(),
                               [&](const test::ReferenceCase& c) {
                                 return c.name.find(argv[argc - 1]) == std::string::npos;
                               }),
                cases.end());
  if (cases.empty()) {
    std::fprintf(stderr, "bench_thin_cuts: no program's name contains '%s'\n", argv[argc - 1]);
    return 2;
  }
  if (faceting) {
    // The reference's own error: the default faceting against one twice as coarse (half the
    // ring vertices, twice the chord angle). The error falls as the square of the facet size,
    // so the default's is about a quarter of the difference printed.
    for (const test::ReferenceCase& c : cases) {
      const Toolpath path = test::casePath(c);
      const std::vector<AptCutter> cutters(path.moves.size(), c.cutter);
      const std::vector<double>& fine = test::exactPerMove(c);
      const std::vector<double> coarse = test::exactRemovals(path, cutters, c.stock, {128, 4.0});
      double worstRel = 0.0, worstAbs = 0.0;
      for (std::size_t i = 0; i < fine.size(); ++i) {
        const double d = std::abs(coarse[i] - fine[i]);
        if (fine[i] >= 1.0)
          worstRel = std::max(worstRel, d / fine[i]);
        else
          worstAbs = std::max(worstAbs, d);
      }
      std::printf(
          "{\"case\": \"%s\", \"coarse_vs_default_worst_pct\": %.4f, "
          "\"small_moves_worst_mm3\": %.5f}\n",
          c.name.c_str(), 100.0 * worstRel, worstAbs);
      std::fflush(stdout);
    }
    return 0;
  }
  for (const test::ReferenceCase& c : cases) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t n = test::exactPerMove(c).size();
    std::fprintf(stderr, "reference %s: %zu moves, %.1f s\n", c.name.c_str(), n,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  for (const char* model : {"voxel", "dexel"}) {
    for (double fraction : {10.0, 20.0, 40.0}) {
      std::vector<double> bigErrors;
      double worstTotal = 0.0, worstSmall = 0.0, worstNothing = 0.0, worstBig = 0.0;
      std::string worstBigAt, worstSmallAt;
      for (const test::ReferenceCase& c : cases) {
        const std::vector<double>& exact = test::exactPerMove(c);
        const double h = 2.0 * c.cutter.radius() / fraction;
        auto stock = test::boxStock(model, c.stock, h);
        const Toolpath path = test::casePath(c);
        const std::vector<double> measured = test::measuredPerMove(c, path, *stock);
        double exactTotal = 0.0, measuredTotal = 0.0;
        for (std::size_t i = 0; i < exact.size(); ++i) {
          exactTotal += exact[i];
          measuredTotal += measured[i];
          const double err = measured[i] - exact[i];
          const std::string at = c.name + " line " + std::to_string(path.moves[i].line);
          if (moves && (exact[i] > 0.0 || measured[i] != 0.0))
            std::printf("%s D/%g %s: exact %.4f measured %.4f mm3 (%+.3f %%, %+.2f cells)\n", model,
                        fraction, at.c_str(), exact[i], measured[i],
                        exact[i] > 0 ? 100.0 * err / exact[i] : 0.0, err / (h * h * h));
          if (exact[i] >= 1.0) {
            const double rel = std::abs(err) / exact[i];
            bigErrors.push_back(rel);
            if (rel > worstBig) worstBig = rel, worstBigAt = at;
          } else if (std::abs(err) / (h * h * h) > worstSmall) {
            worstSmall = std::abs(err) / (h * h * h);
            worstSmallAt = at;
          }
          if (exact[i] == 0.0) worstNothing = std::max(worstNothing, std::abs(measured[i]));
        }
        worstTotal = std::max(worstTotal, std::abs(measuredTotal / exactTotal - 1.0));
      }
      std::printf(
          "{\"model\": \"%s\", \"cell\": \"D/%g\", \"worst_total_pct\": %.4f, \"moves_1mm3\": %zu, "
          "\"median_pct\": %.3f, \"p95_pct\": %.3f, \"worst_pct\": %.3f, \"worst_at\": \"%s\", "
          "\"worst_small_cells\": %.3f, \"worst_small_at\": \"%s\", \"from_nothing_mm3\": %.4g}\n",
          model, fraction, 100.0 * worstTotal, bigErrors.size(), 100.0 * quantile(bigErrors, 0.5),
          100.0 * quantile(bigErrors, 0.95), 100.0 * worstBig, worstBigAt.c_str(), worstSmall,
          worstSmallAt.c_str(), worstNothing);
      std::fflush(stdout);
    }
  }
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {  // a program of data/gcode/thin missing or unreadable
    std::fprintf(stderr, "bench_thin_cuts: %s\n", e.what());
    return 1;
  }
}
