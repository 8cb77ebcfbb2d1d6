// The random campaign of issue 44 (not a test): both stock models at the default cell against
// the exact reference (tests/support/ExactSweep.h) on the programs of
// tests/support/RandomPrograms.h, seed by seed. Prints one JSON line per seed and model (its
// figures against issue 44's bounds, and each move outside them), then the worst seeds.
// The exact removals are kept in --cache DIR (one file per seed and program text), so that a
// second campaign after a change to the stock models costs only the simulations.
//   build/tests/bench/bench_random_cuts --seeds 1-200 [--cache DIR]
//       [--model dexel|voxel|tilted|quarter|mesh] [--max-moves N] [--programs DIR] [--list]
// --programs DIR writes each seed's program (seed-N.ngc) to run it with `engage simulate`: its
// first line names the cutter and the stock box. --list names each seed's case and stops there.
// --model tilted runs the voxel stock on each case carried onto a tilted tool (a table-ac
// machine at A 10-60 deg and any C from the seed, the program and the box turned:
// test::tiltedCase), the turned box read as a mesh, against the same exact removals;
// --model quarter the same at A 90 and C a multiple of 90 (the tool lying along X or Y), the
// turned box a box again (exact fractions); --model mesh the upright case with the box read as
// a mesh (the control of the mesh's edges).

#include "engine/sim/Simulation.h"
#include "stock/VoxelStock.h"
#include "tests/stock/StockTestSupport.h"
#include "tests/support/ExactSweep.h"
#include "tests/support/RandomPrograms.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace engage;

namespace {

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char ch : text)
    h = (h ^ ch) * 1099511628211ull;
  return h;
}

std::vector<double> exactOf(const test::RandomCase& c, const std::string& cacheDir) {
  char name[64];
  std::snprintf(name, sizeof name, "/seed-%llu-%016llx.txt",
                static_cast<unsigned long long>(c.seed),
                static_cast<unsigned long long>(fnv1a(c.program)));
  const std::string path = cacheDir.empty() ? std::string() : cacheDir + name;
  if (!path.empty()) {
    std::ifstream in(path);
    std::vector<double> v;
    double x;
    while (in >> x)
      v.push_back(x);
    if (v.size() == c.path.moves.size()) return v;
  }
  const std::vector<AptCutter> cutters(c.path.moves.size(), c.cutter);
  std::vector<double> v = test::exactRemovals(c.path, cutters, c.stock);
  if (!path.empty()) {
    std::ofstream out(path + ".part");
    char buf[40];
    for (double x : v) {
      std::snprintf(buf, sizeof buf, "%.17g\n", x);
      out << buf;
    }
    out.close();
    std::rename((path + ".part").c_str(), path.c_str());
  }
  return v;
}

/// The case carried onto a tilted tool (test::tiltedCase): through the voxel stock of the
/// turned box read as a mesh (oblique and upright), or of the box itself (quarter turns).
SimulationResult simulateTilted(const test::RandomCase& c, test::Tilt tilt) {
  const test::TiltedCase t = test::tiltedCase(c, tilt);
  if (tilt == test::Tilt::Quarter) {
    VoxelStock stock = VoxelStock::box(t.box, c.cell);
    return simulate(t.path, c.cutter, stock, SimulationOptions{});
  }
  const std::string stl =
      (std::filesystem::temp_directory_path() / ("bench-tilted-" + std::to_string(c.seed) + ".stl"))
          .string();
  writeStl(t.stock, stl);
  VoxelStock stock = VoxelStock::fromMesh(stl, c.cell);
  std::filesystem::remove(stl);
  return simulate(t.path, c.cutter, stock, SimulationOptions{});
}

struct Row {
  std::uint64_t seed;
  std::string model;
  double score;  // the worst of the bounds used: 1 means at a bound
  std::string line;
};

}  // namespace

int run(int argc, char** argv) {
  std::uint64_t first = 1, last = 20;
  std::string cache, programs;
  std::vector<std::string> models = {"dexel", "voxel"};
  int maxMoves = 30;
  bool list = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool more = i + 1 < argc;
    if (a == "--seeds" && more) {
      const std::string r = argv[++i];
      const auto dash = r.find('-');
      first = std::stoull(r.substr(0, dash));
      last = dash == std::string::npos ? first : std::stoull(r.substr(dash + 1));
    } else if (a == "--cache" && more) {
      cache = argv[++i];
    } else if (a == "--programs" && more) {
      programs = argv[++i];
    } else if (a == "--model" && more) {
      models = {argv[++i]};
    } else if (a == "--list") {
      list = true;
    } else if (a == "--max-moves" && more) {
      maxMoves = std::stoi(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: bench_random_cuts [--seeds A-B] [--cache DIR] [--model "
                   "dexel|voxel|tilted|quarter|mesh] "
                   "[--max-moves N] [--programs DIR] [--list]\n");
      return 2;
    }
  }
  std::vector<Row> rows;
  for (std::uint64_t seed = first; seed <= last; ++seed) {
    const test::RandomCase c = test::randomCase(seed, maxMoves);
    if (!programs.empty())
      std::ofstream(programs + "/seed-" + std::to_string(seed) + ".ngc") << c.program;
    if (list) {
      std::printf("%s: %zu moves, cell %.4g mm\n", c.name.c_str(), c.path.moves.size(), c.cell);
      continue;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<double> exact = exactOf(c, cache);
    const double exactSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const std::string& model : models) {
      SimulationResult r;
      try {
        r = model == "tilted"    ? simulateTilted(c, test::Tilt::Oblique)
            : model == "quarter" ? simulateTilted(c, test::Tilt::Quarter)
            : model == "mesh"    ? simulateTilted(c, test::Tilt::Upright)
                              : simulate(c.path, c.cutter, *test::boxStock(model, c.stock, c.cell),
                                         SimulationOptions{});
      } catch (const std::exception& e) {
        // (A stock the model cannot hold at this cell: a turned box's mesh is checked for
        // memory as if cut everywhere.) Said on its own line; the campaign goes on.
        std::string what = e.what();
        std::replace(what.begin(), what.end(), '"', '\'');
        std::printf("{\"seed\": %llu, \"model\": \"%s\", \"error\": \"%s\"}\n",
                    static_cast<unsigned long long>(seed), model.c_str(), what.c_str());
        continue;
      }
      std::vector<double> measured(c.path.moves.size(), 0.0);
      for (const StepRecord& s : r.steps)
        measured.at(s.move) += s.removed;
      const test::MoveComparison m = test::compareMoves(c.path, exact, measured, c.cell);
      std::ostringstream line;
      char buf[600];
      std::snprintf(buf, sizeof buf,
                    "{\"seed\": %llu, \"model\": \"%s\", \"case\": \"%s\", \"cell_mm\": %.5g, "
                    "\"moves\": %zu, \"exact_total_mm3\": %.6g, \"total_pct\": %.4f, "
                    "\"big_moves\": %zu, \"worst_big_pct\": %.3f, \"worst_big_line\": %d, "
                    "\"worst_small_cells\": %.3f, \"worst_small_line\": %d, "
                    "\"worst_zero_mm3\": %.3g, \"failures\": %zu, \"exact_s\": %.1f",
                    static_cast<unsigned long long>(seed), model.c_str(), c.name.c_str(), c.cell,
                    c.path.moves.size(), m.exactTotal, m.totalPct(), m.bigMoves, m.worstBigPct,
                    c.path.moves[m.worstBigMove].line, m.worstSmallCells,
                    c.path.moves[m.worstSmallMove].line, m.worstZeroMm3, m.failures.size(),
                    exactSeconds);
      line << buf;
      if (!m.failures.empty()) {
        line << ", \"outside\": [";
        for (std::size_t k = 0; k < m.failures.size(); ++k)
          line << (k ? ", " : "") << '"' << m.failures[k] << '"';
        line << "]";
      }
      line << "}";
      std::printf("%s\n", line.str().c_str());
      std::fflush(stdout);
      const double score =
          std::max({std::abs(m.totalPct()) / 0.1, std::abs(m.worstBigPct) / 1.0,
                    std::abs(m.worstSmallCells) / 2.0, m.worstZeroMm3 > 0.0 ? 1e9 : 0.0});
      rows.push_back({seed, model, score, line.str()});
    }
  }
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.score > b.score; });
  std::size_t outside = 0;
  for (const Row& r : rows)
    outside += r.score > 1.0;
  std::printf("{\"runs\": %zu, \"outside_bounds\": %zu}\n", rows.size(), outside);
  std::printf("worst (score 1 = at a bound):\n");
  for (std::size_t k = 0; k < rows.size() && k < 10; ++k)
    std::printf("  seed %llu %s: score %.3g\n", static_cast<unsigned long long>(rows[k].seed),
                rows[k].model.c_str(), rows[k].score);
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_random_cuts: %s\n", e.what());
    return 1;
  }
}
