// Both stock models against the exact reference (tests/support/ExactSweep.h), per move, on the
// thin- and grazing-cut programs of data/gcode/thin at the default cell (D/20: 0.3 mm for the
// 6 mm cutters, 0.2 mm for the taper's 4 mm tip). The bounds are issue 18's: the program's total
// within 0.1 %; every move that removes at least 1 mm^3 within 1 %, and 95 % of them within 0.5 %;
// smaller moves within two cell volumes; a move that removes nothing in the reference removes
// exactly nothing. The reference's own error: its cutter is inscribed, at most facetDeviation()
// (0.00023 mm for the flats, 0.00046 mm for the ball's 2-degree chords) inside the true one;
// against itself twice as coarse (bench_thin_cuts --faceting) its moves of 1 mm^3 or more change
// by at most 0.03 % (flat, bull, taper) and 0.25 % (ball), smaller ones by 0.028 mm^3, so at the
// default faceting (the error falls as the square of the facet) about a quarter of that.

#include "tests/support/ReferenceCuts.h"
#include "cutters/Numbers.h"
#include "engine/sim/Simulation.h"
#include "stock/VoxelStock.h"
#include "tests/stock/StockTestSupport.h"
#include "tests/support/ExactSweep.h"
#include "tests/support/RandomPrograms.h"

#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

using namespace engage;

namespace {

// Measured with build/tests/bench/bench_thin_cuts --moves (D/20): the voxels' totals within
// 0.06 % and every move within 0.23 %, the dexels' within 0.071 % and 0.42 %. (Two planes per
// partial voxel had missed the pecks by up to -5.8 %, the skims -4.2 %, a floor re-cut -2.2 %,
// the ramps -1.4 / +1.3 %; the top face skimmed again 0.01 mm lower had taken +0.55 %. The
// dexels' retracts that took what the step before them left, up to 0.042 mm^3, remove nothing
// since the simulation knows they cannot reach material: engine/sim/Simulation.cpp,
// retractsFromCut.)

/// Issue 18's and 44's bounds on one run: every move within them (compareMoves), the total
/// within 0.1 %, and 95 % of the moves of 1 mm^3 or more within 0.5 %.
void checkBounds(const std::string& what, const test::MoveComparison& m) {
  std::string outside;
  for (const std::string& f : m.failures)
    outside += "\n  " + f;
  INFO(what << ": total " << m.measuredTotal << " against " << m.exactTotal << " mm3 ("
            << m.totalPct() << " %); " << m.bigWithinHalfPct << " of " << m.bigMoves
            << " moves of 1 mm3 or more within 0.5 %" << outside);
  CHECK(m.failures.empty());
  CHECK(std::abs(m.totalPct()) <= 0.1);
  CHECK(static_cast<double>(m.bigWithinHalfPct) >= 0.95 * static_cast<double>(m.bigMoves));
}

void checkCase(const std::string& name, const std::string& model) {
  const auto cases = test::referenceCases(ENGAGE_SOURCE_DIR);
  const auto c = std::find_if(cases.begin(), cases.end(),
                              [&](const test::ReferenceCase& k) { return k.name == name; });
  REQUIRE(c != cases.end());
  const double h = 2.0 * c->cutter.radius() / 20.0;
  const std::vector<double>& exact = test::exactPerMove(*c);
  auto stock = test::boxStock(model, c->stock, h);
  const Toolpath path = test::casePath(*c);
  const std::vector<double> measured = test::measuredPerMove(*c, path, *stock);
  REQUIRE(measured.size() == exact.size());
  checkBounds(model + " " + name, test::compareMoves(path, exact, measured, h));
}

}  // namespace

TEST_CASE("the exact reference: a slot's volume in closed form", "[reference]") {
  // A 6 mm flat end mill (256-gon: width 6 mm across X, exactly, as a vertex lies on the Y axis)
  // cutting a 2 mm deep slot through a 40 mm box along X: 40 x 6 x 2 = 480 mm^3, to the
  // exact kernel's conversion to double; a second pass 0.5 mm to the side removes 40 x 0.5 x 2.
  Toolpath path;
  Move a;
  a.kind = MoveKind::Line;
  a.start = {-5.0, 10.0, 8.0};
  a.end = {45.0, 10.0, 8.0};
  Move b = a;
  b.start = {45.0, 10.5, 8.0};
  b.end = {-5.0, 10.5, 8.0};
  path.moves = {a, b};
  Box3 box;
  box.max = {40.0, 30.0, 10.0};
  const AptCutter flat = AptCutter::flat(6.0, 20.0);
  const std::vector<double> v = test::exactRemovals(path, {flat, flat}, box);
  CHECK(v[0] == Approx(480.0).epsilon(1e-12));
  CHECK(v[1] == Approx(40.0).epsilon(1e-12));
  CHECK(test::facetDeviation(flat) == Approx(3.0 * (1.0 - std::cos(kPi / 256))));
}

TEST_CASE("both stock models against the exact reference: floor_recut flat", "[reference]") {
  checkCase("floor_recut flat", "voxel");
  checkCase("floor_recut flat", "dexel");
}

TEST_CASE("both stock models against the exact reference: skims_ramps flat", "[reference]") {
  checkCase("skims_ramps flat", "voxel");
  checkCase("skims_ramps flat", "dexel");
}

TEST_CASE("both stock models against the exact reference: pecks_grazes flat", "[reference]") {
  checkCase("pecks_grazes flat", "voxel");
  checkCase("pecks_grazes flat", "dexel");
}

TEST_CASE("both stock models against the exact reference: ball_steps ball", "[reference]") {
  checkCase("ball_steps ball", "voxel");
  checkCase("ball_steps ball", "dexel");
}

TEST_CASE("both stock models against the exact reference: bull_taper bull", "[reference]") {
  checkCase("bull_taper bull", "voxel");
  checkCase("bull_taper bull", "dexel");
}

TEST_CASE("both stock models against the exact reference: bull_taper taper", "[reference]") {
  checkCase("bull_taper taper", "voxel");
  checkCase("bull_taper taper", "dexel");
}

namespace {

// Seeds of the random campaign (tests/support/RandomPrograms.h; the whole campaign is
// scripts/random_campaign.sh, its figures in docs/accuracy.md) kept in the suite, both models
// at the default cell on issue 44's bounds (compareMoves): a tapered ball's ramps, a taper's
// ramps, a taper's polyline helix, a flat end mill's re-cuts 0.01-0.1 mm beside and below its
// passes. The reference takes 10-70 s each.
void checkRandom(std::uint64_t seed) {
  const test::RandomCase c = test::randomCase(seed);
  const std::vector<AptCutter> cutters(c.path.moves.size(), c.cutter);
  const std::vector<double> exact = test::exactRemovals(c.path, cutters, c.stock);
  for (const std::string model : {"dexel", "voxel"}) {
    auto stock = test::boxStock(model, c.stock, c.cell);
    const SimulationResult r = simulate(c.path, c.cutter, *stock, SimulationOptions{});
    std::vector<double> measured(c.path.moves.size(), 0.0);
    for (const StepRecord& s : r.steps)
      measured.at(s.move) += s.removed;
    checkBounds(model + " " + c.name, test::compareMoves(c.path, exact, measured, c.cell));
  }
  // The case carried onto a tilted tool (issue 48, test::tiltedCase), against the same exact
  // removals (a rotation keeps volumes): the tool lying along X or Y in the box turned by a
  // quarter (a box again), on the same bounds; and leaning 10-60 deg in the box turned so,
  // read as a mesh, on the same bounds but for moves that cannot reach material: a retract's
  // column is known empty only up to the stock's extent along the axis, which the bounding box
  // of a turned box overstates, so such moves are measured, within a fifth of a cell's volume
  // (measured: up to 0.1).
  for (const test::Tilt tilt : {test::Tilt::Quarter, test::Tilt::Oblique}) {
    const test::TiltedCase t = test::tiltedCase(c, tilt);
    const std::string stl =
        (std::filesystem::temp_directory_path() /
         ("engage-tilted-" + std::to_string(seed) + "-" + std::to_string(getpid()) + ".stl"))
            .string();
    writeStl(t.stock, stl);
    VoxelStock stock = tilt == test::Tilt::Quarter ? VoxelStock::box(t.box, c.cell)
                                                   : VoxelStock::fromMesh(stl, c.cell);
    std::filesystem::remove(stl);
    const SimulationResult r = simulate(t.path, c.cutter, stock, SimulationOptions{});
    std::vector<double> measured(c.path.moves.size(), 0.0);
    for (const StepRecord& s : r.steps)
      measured.at(s.move) += s.removed;
    const test::MoveComparison m = test::compareMoves(c.path, exact, measured, c.cell);
    std::ostringstream what;
    what << (tilt == test::Tilt::Quarter ? "lying " : "leaning ") << c.name << " at A " << t.abc.x()
         << " C " << t.abc.z();
    if (tilt == test::Tilt::Quarter) {
      checkBounds(what.str(), m);
      continue;
    }
    std::string outside;
    for (const std::string& f : m.failures)
      outside += "\n  " + f;
    INFO(what.str() << ": total " << m.measuredTotal << " against " << m.exactTotal << " mm3"
                    << outside);
    CHECK(std::abs(m.totalPct()) <= 0.1);
    CHECK(std::abs(m.worstBigPct) <= 1.0);
    CHECK(std::abs(m.worstSmallCells) <= 2.0);
    CHECK(m.worstZeroMm3 <= 0.2 * c.cell * c.cell * c.cell);
  }
}

}  // namespace

TEST_CASE("both stock models against the exact reference: random seed 3 (taper ramps)",
          "[reference]") {
  checkRandom(3);
}

TEST_CASE("both stock models against the exact reference: random seed 4 (taper helix)",
          "[reference]") {
  checkRandom(4);
}

TEST_CASE("both stock models against the exact reference: random seed 2 (tapered ball ramps)",
          "[reference]") {
  checkRandom(2);
}

TEST_CASE("both stock models against the exact reference: random seed 105 (flat re-cuts)",
          "[reference]") {
  checkRandom(105);
}

TEST_CASE("the random programs: a seed is one program, the tool starting above the stock",
          "[reference]") {
  // The generator's own promises: the same seed gives the same text; every move is straight;
  // the first move starts above the stock (it must not cut on its way to the program).
  const test::RandomCase a = test::randomCase(17), b = test::randomCase(17);
  CHECK(a.program == b.program);
  CHECK(a.program != test::randomCase(18).program);
  REQUIRE_FALSE(a.path.moves.empty());
  CHECK(a.path.moves.front().start.z() > a.stock.max.z());
  for (const Move& m : a.path.moves)
    CHECK((m.kind == MoveKind::Line || m.kind == MoveKind::Rapid));
  CHECK(a.cell > 0.0);
}
