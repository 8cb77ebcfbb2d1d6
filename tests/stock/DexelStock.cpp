// Tests of stock/DexelStock.h: the closed forms the voxel stock is tested against
// (tests/stock/VoxelStock.cpp), on the dexel model, cut at 30 degrees to the grid.
//
// Resolution: ray spacing h = D / 20 and steps of L = 2.5 h, as for the voxels. Along a ray
// the removal is exact (to 1e-4 mm); across the rays a column crossed by the cutter's outline
// keeps the share it does not cover: the area of the square column on the far side of the
// outline taken as straight (or, for a radius of 2 h or more, as a circle to second order),
// from the outline's distance and direction; where an earlier outline (a wall, the box's face)
// crosses the column at an angle, the part of the column inside the one and outside the other
// (each column keeps its outline's line). Steps that change height (ramps,
// helices) take the same share from the ray's distance to the swept solid's slice at each
// height. Bounds are about 1.5 x the worst measured (written beside them; in brackets the
// linear share 1/2 - d/h of the outline's distance alone, used before).

#include "stock/DexelStock.h"
#include "cutters/CrossSection.h"
#include "cutters/Error.h"
#include "stock/VoxelStock.h"
#include "tests/stock/StockTestSupport.h"

#include <tbb/task_arena.h>
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

using namespace engage;
using Catch::Matchers::Contains;

using namespace engage::test;

namespace {

Box3 block(double half, double depth) {
  Box3 b;
  b.min = {-half, -half, -depth};
  b.max = {half, half, 0};
  return b;
}

}  // namespace

TEST_CASE("dexel: a box stock holds exactly its volume, wherever its faces fall", "[stock]") {
  // The last row and column of rays carry the share of their column inside the box.
  Box3 b;
  b.min = {0.03, -1.07, 0.0};
  b.max = {10.11, 5.5, 3.33};
  const DexelStock s = DexelStock::box(b, 0.25);
  CHECK(s.volume() == Approx(10.08 * 6.57 * 3.33).epsilon(1e-12));
  CHECK(s.raysX() == 41);  // ceil(10.08 / 0.25)
  CHECK(s.segments() == static_cast<std::size_t>(41 * 27));
  CHECK_THROWS_WITH(DexelStock::box(b, 0.00001), Contains("use a larger spacing"));
  b.max.x() = b.min.x();
  CHECK_THROWS_WITH(DexelStock::box(b, 0.25), Contains("stock box is empty"));
}

TEST_CASE("dexel: full slot at 30 deg, every step D x depth x L", "[stock]") {
  for (const AptCutter& c :
       {AptCutter::flat(6.0, 18.0), AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0),
        AptCutter::taper(6.0, kPi / 12, 18.0)}) {
    INFO(shapeName(c.shape()));
    const double h = 6.0 / 20.0, L = 2.5 * h;
    DexelStock s = DexelStock::box(block(30, 10), h);
    const double area = exactCrossSection(c, 100.0, 2.0).area;
    const auto v = pass(s, c, Eigen::Vector3d(0, 0, -2) - 10.0 * kDir, kDir, 20.0, L);
    // Measured worst 0.0097 % (flat), 0.0065-0.019 % (ball, taper, bull); means within 0.011 %
    // (before the exact share: 0.61 %, 0.06-0.38 %; before the columns' lines, 0.076 % worst).
    CHECK(worstRelative(v, area * L) < 0.0003);
    CHECK(std::abs(meanRelative(v, area * L)) < 0.00017);
  }
}

TEST_CASE("dexel: side cut at stepover s, every step y_G x L", "[stock]") {
  for (const AptCutter& c :
       {AptCutter::flat(6.0, 18.0), AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0),
        AptCutter::taper(6.0, kPi / 12, 18.0)}) {
    INFO(shapeName(c.shape()));
    const double h = 6.0 / 20.0, L = 2.5 * h, stepover = 2.0;
    DexelStock s = DexelStock::box(block(30, 10), h);
    const Eigen::Vector3d a = Eigen::Vector3d(0, 0, -2) - 12.0 * kDir;
    pass(s, c, a - stepover * kSide, kDir, 24.0, 4.0);
    const auto v = pass(s, c, a, kDir, 20.0, L);
    const double expected = exactCrossSection(c, stepover, 2.0).area * L;
    // Measured worst 0.038 % (flat), 0.014-0.026 % (others); means within 0.009 %; spread (sd)
    // 0.016 % at most (before the walls' columns kept their lines: worst 0.58 %, 0.24-0.47 %;
    // before the exact share: 1.30 %, 0.24-0.89 %). Issue 44 asks a spread of 0.5 % at most.
    CHECK(worstRelative(v, expected) < 0.0006);
    CHECK(std::abs(meanRelative(v, expected)) < 0.00015);
    CHECK(spreadRelative(v) < 0.00025);
  }
}

TEST_CASE("dexel: plunge and ramp against their closed forms", "[stock]") {
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  const double h = 6.0 / 20.0;
  SECTION("plunge: pi r^2 per unit depth") {
    DexelStock s = DexelStock::box(block(30, 10), h);
    const Eigen::Vector3d top(0.37, 0.11, 0.0);
    double total = 0.0;
    const double dz = 2.5 * h;
    for (int k = 0; k < 8; ++k)
      total += s.remove(Sweep(c,
                              line(top - k * dz * Eigen::Vector3d::UnitZ(),
                                   top - (k + 1) * dz * Eigen::Vector3d::UnitZ()),
                              h))
                   .volume;
    // Measured -0.00006 % (before -0.05 %); 1e-4 for the rays' 1e-4 mm along them.
    CHECK(total == Approx(kPi * 9.0 * 8 * dz).epsilon(1e-4));
  }
  SECTION("ramp at 5 deg from the top: V(x) = tan a (r x^2 + pi r^2 x)") {
    DexelStock s = DexelStock::box(block(30, 10), h);
    const double t = std::tan(5.0 * kPi / 180.0);
    const Eigen::Vector3d slope = kDir + t * Eigen::Vector3d(0, 0, -1);
    const Eigen::Vector3d a = -10.0 * kDir;
    auto V = [&](double x) { return t * (3.0 * x * x + kPi * 9.0 * x); };
    const double L = 2.5 * h;
    double worst = 0.0, total = 0.0;
    for (int k = 0; k < 30; ++k) {
      const double v =
          s.remove(Sweep(c, line(a + k * L * slope, a + (k + 1) * L * slope), h)).volume;
      total += v;
      if (k >= 8) worst = std::max(worst, std::abs(v / (V((k + 1) * L) - V(k * L)) - 1.0));
    }
    CHECK(worst < 0.003);                               // measured 0.20 % (before 0.57 %)
    CHECK(total == Approx(V(30 * L)).epsilon(0.0005));  // measured +0.016 % (before +0.12 %)
  }
}

TEST_CASE("dexel: helical bore, every step after the first turns the same volume", "[stock]") {
  // A helix of radius Rh < r bores a full hole of radius Rh + r (no island at the axis). Once
  // the tip is a turn below the top, every step removes the same volume (helixSteadyStep).
  const double h = 6.0 / 20.0, L = 2.5 * h, Rh = 1.2, p = 1.0;
  const Eigen::Vector3d centre(0.37, 0.11, 0.0);
  for (const AptCutter& c :
       {AptCutter::flat(6.0, 18.0), AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0)}) {
    INFO(std::string(shapeName(c.shape())));
    DexelStock s = DexelStock::box(block(30, 12), h);
    const std::vector<double> v = helix(s, c, centre, Rh, p, 6.0, L);
    const double expected = helixSteadyStep(Rh, 3.0, p, L);
    // Skip the first four turns: the ball's and bull's full width is r (3 mm) above the tip.
    const std::size_t skip = v.size() * 4 / 6;
    // Measured worst 0.25 % (flat), 0.20 % (ball), 0.56 % (bull); means 0.075 %, 0.067 %,
    // 0.28 % (before: 0.45 %, 0.34 %, 0.48 %; within 0.17 %: the bull's corner, where the band
    // is tall, is the one case the exact share made worse).
    CHECK(worstRelative(v, expected, skip) < 0.008);
    CHECK(std::abs(meanRelative(v, expected, skip)) < 0.0045);
  }
}

TEST_CASE("dexel: concave and convex arcs at stepover s, area x speed of the centroid", "[stock]") {
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  const double h = 6.0 / 20.0;
  const double stepover = 2.0, depth = 2.0, rho = 15.0;
  const CrossSection x = exactCrossSection(c, stepover, depth);
  for (const int side : {+1, -1}) {
    INFO((side > 0 ? "concave" : "convex"));
    DexelStock s = DexelStock::box(side > 0 ? block(40, 10) : block(rho + 1, 10), h);
    auto arcStep = [&](double r, double a0, double a1) {
      return arc(Eigen::Vector3d(0.123, -0.077, 0), r, a0, a1, -depth);
    };
    for (double a = 0; a < 2 * kPi; a += 0.2)
      s.remove(Sweep(c, arcStep(rho - side * stepover, a, a + 0.2), h));
    const double dA = 2.5 * h / rho;
    s.remove(Sweep(c, arcStep(rho, 0.0, 1e-9), h));
    const double expected = x.area * (rho + side * x.centroidX) * dA;
    std::vector<double> v;
    for (double a = 0.0; a < 1.5; a += dA)
      v.push_back(s.remove(Sweep(c, arcStep(rho, a, a + dA), h)).volume);
    // Measured worst 0.013 % (concave), 0.029 % (convex); means 0.0003 %, 0.0002 %; spread (sd)
    // 0.0066 %, 0.011 % (before the walls' columns kept their lines: worst 0.66 %, 0.99 %;
    // before the exact share 1.83 %, 1.88 %). Issue 44 asks a spread of 0.5 % at most.
    CHECK(worstRelative(v, expected, 2) < 0.00045);
    CHECK(std::abs(meanRelative(v, expected, 2)) < 0.0001);
    CHECK(spreadRelative(v, 2) < 0.00017);
  }
}

TEST_CASE("dexel: a stock from a closed mesh, by casting the rays through it", "[stock]") {
  // A cylinder of R 18 from z = -10 to 0 (a 128-gon: area 128/2 R^2 sin(2 pi/128)), caps
  // fanned from the centre, so that rays on the diagonals run along shared edges: columns
  // whose centre is inside count whole, the volume is off by the columns along the rim that
  // are partly in (measured 0.02 % at h = 0.3).
  const DexelStock s =
      DexelStock::fromMesh(ENGAGE_SOURCE_DIR "/tests/data/cylinder_r18_h10.stl", 0.3);
  const double area = 0.5 * 128 * 18.0 * 18.0 * std::sin(2 * kPi / 128);
  CHECK(s.volume() == Approx(area * 10.0).epsilon(0.002));
  CHECK(s.bounds().max.z() == Approx(0.0).margin(1e-5));
  CHECK(s.bounds().min.z() == Approx(-10.0).margin(1e-5));
  CHECK_THROWS_WITH(DexelStock::fromMesh(ENGAGE_SOURCE_DIR "/data/stock/open_box.stl", 0.3),
                    Contains("is not closed"));
}

TEST_CASE("dexel: converted to voxels for stock.vdb and stock.stl, the volume kept", "[stock]") {
  // A box whose faces fall between rays and voxels, with a slot cut at 30 degrees: the
  // voxels' fractions sum to the dexels' volume (32-bit floats: 1e-6 relative).
  Box3 b;
  b.min = {-10.07, -8.13, -5.0};
  b.max = {10.11, 8.02, 0.0};
  DexelStock s = DexelStock::box(b, 0.3);
  pass(s, AptCutter::ball(6.0, 18.0), Eigen::Vector3d(0, 0, -2) - 8.0 * kDir, kDir, 16.0, 0.75);
  const VoxelStock v = VoxelStock::fromDexels(s);
  CHECK(v.voxelSize() == 0.3);
  CHECK(v.volume() == Approx(s.volume()).epsilon(1e-6));
  CHECK(v.bounds().min.x() <= -10.07 + 0.3);
  CHECK(v.bounds().max.y() >= 8.02 - 0.3);
}

TEST_CASE("dexel: the captured removal puts each step's material where it was", "[stock]") {
  // A slot at 30 degrees (its walls leave columns at partial shares), then one 2 mm wider and
  // 1 mm deeper across it: the second cut takes a wall column's rest above 2 mm and all of it
  // below. The log (per column, step and voxel height) must hold no more than a column's
  // material at any voxel height (what removed.vdb's voxels are made of), and the removed
  // volume in all.
  Box3 b;
  b.min = {-10.07, -8.13, -5.0};
  b.max = {10.11, 8.02, 0.0};
  DexelStock s = DexelStock::box(b, 0.3);
  s.captureRemoved(true);
  const double before = s.volume();
  pass(s, AptCutter::flat(6.0, 18.0), Eigen::Vector3d(0, 0, -2) - 8.0 * kDir, kDir, 16.0, 0.75);
  pass(s, AptCutter::flat(8.0, 18.0), Eigen::Vector3d(0, 0, -3) - 8.0 * kDir, kDir, 16.0, 0.75);
  const double h = s.resolution();
  double logged = 0.0, beyond = 0.0;
  for (int j = 0; j < s.raysY(); ++j)
    for (int i = 0; i < s.raysX(); ++i)
      if (const DexelStock::LostColumn* c = s.removedColumn(i, j))
        for (const DexelStock::Lost& cell : c->cells) {
          logged += static_cast<double>(cell.share) * h * h * h;
          // What a cell lost beyond the column's material there (its weight; floats: 1e-6).
          // The whole cut's span at one mean share, before, had put 5.6 mm^3 of 515 beyond.
          beyond = std::max(beyond, static_cast<double>(cell.share) - s.weight(i, j));
        }
  // The shares are 32-bit floats: 1e-6 relative.
  CHECK(logged == Approx(before - s.volume()).epsilon(1e-6));
  INFO("removed " << logged << " mm^3; the most a cell lost beyond its column's material "
                  << beyond);
  CHECK(beyond < 1e-6);
}

TEST_CASE(
    "dexel: every step and its captured losses the same at any thread count, in batches or not",
    "[stock]") {
  // A removal runs tile by tile (16 x 16 columns), the tiles side by side on several cores
  // when the steps' boxes hold enough columns, each tile applying the steps that reach it in
  // their order, and each step's sums taken tile by tile in the tiles' order: one thread and
  // four, and steps one at a time or in batches, give the same bits. A 6 mm ball ramping down
  // and across at 0.3 mm (about 20 x 22 columns a step, two to four tiles) and a 10 mm flat
  // end mill's level pass over the ramp's groove (about 35 x 36). The ball's holder (16 mm
  // across, from 1.5 mm above the tip; a cell slimmer for the first question) is asked after
  // each ramp step what it meets: from the 16th step it dips into the block.
  const AptCutter ball = AptCutter::ball(6.0, 18.0), flat = AptCutter::flat(10.0, 18.0);
  const AptCutter holder = AptCutter::flat(16.0, 10.0), slim = AptCutter::flat(15.4, 10.0);
  std::vector<Sweep> sweeps, holders;
  for (int k = 0; k < 24; ++k) {
    const Eigen::Vector3d p0(-15.0 + 1.2 * k, -4.0 + 0.35 * k, -0.1 * k);
    const Eigen::Vector3d step(1.2, 0.35, -0.1), up(0.0, 0.0, 1.5);
    sweeps.emplace_back(ball, line(p0, p0 + step), 0.3);
    holders.emplace_back(slim, line(p0 + up, p0 + up + step), 0.3);
    holders.emplace_back(holder, line(p0 + up, p0 + up + step), 0.3);
  }
  // The holder's question for step n (none for the flat end mill's steps).
  const double threshold = 0.5 * 0.3 * 0.3 * 0.3;
  auto parts = [&](std::size_t n) {
    return n < 24 ? std::vector<PartSweep>{{&holders[2 * n], &holders[2 * n + 1], 0.0, threshold}}
                  : std::vector<PartSweep>{};
  };
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p0(-14.0 + 3.5 * k, 1.0, -1.0);
    sweeps.emplace_back(flat, line(p0, p0 + Eigen::Vector3d(3.5, 0.0, 0.0)), 0.3);
  }
  // batch 0: remove() and materialInside step by step; else removeSteps() in batches of that
  // many steps.
  auto removeAll = [&](std::size_t batch) {
    DexelStock s = DexelStock::box(block(20.0, 6.0), 0.3);
    s.captureRemoved(true);
    std::vector<Removal> steps;
    for (std::size_t k = 0; k < sweeps.size(); k += std::max<std::size_t>(batch, 1)) {
      if (batch == 0) {
        steps.push_back(s.remove(sweeps[k], static_cast<int>(k), 0.1));
        for (const PartSweep& part : parts(k))
          steps.back().partsMet.emplace_back(s.materialInside(*part.slim, part.top),
                                             s.materialInside(*part.full, part.top));
        continue;
      }
      std::vector<StepCut> cuts;
      for (std::size_t n = k; n < std::min(sweeps.size(), k + batch); ++n)
        cuts.push_back({&sweeps[n], static_cast<int>(n), 0.1, parts(n)});
      for (const Removal& r : s.removeSteps(cuts))
        steps.push_back(r);
    }
    std::vector<double> numbers, met;  // every field of every step's removal; the holder's
    for (const Removal& r : steps) {
      numbers.insert(numbers.end(),
                     {r.volume, r.axialDepth, r.top, r.lateral,
                      static_cast<double>(r.voxelsChanged), static_cast<double>(r.voxelsVisited)});
      for (const auto& [slimMet, fullMet] : r.partsMet)
        met.insert(met.end(), {slimMet, slimMet > threshold ? fullMet : 0.0});
    }
    std::vector<double> rest;  // what every ray holds after, and what it lost, when
    for (int j = 0; j < s.raysY(); ++j)
      for (int i = 0; i < s.raysX(); ++i) {
        for (const DexelStock::Interval& x : s.ray(i, j))
          rest.insert(rest.end(), {x.z0, x.z1, x.f});
        if (const DexelStock::LostColumn* c = s.removedColumn(i, j))
          for (const DexelStock::Lost& cell : c->cells)
            rest.insert(rest.end(), {static_cast<double>(cell.share), 1.0 * cell.step});
      }
    return std::make_tuple(numbers, rest, steps.front().volume, s.stepMrr(), met);
  };
  // In an arena of one thread the tiles go one after another; of four, side by side.
  auto run = [&](int threads, std::size_t batch) {
    return tbb::task_arena(threads).execute([&] { return removeAll(batch); });
  };
  const auto one = run(1, 1);
  for (const auto& [threads, batch] :
       {std::pair<int, std::size_t>{4, 1}, {1, 32}, {4, 32}, {4, 5}, {4, 0}}) {
    INFO(threads << " threads, batches of " << batch << " steps");
    const auto other = run(threads, batch);
    CHECK(std::get<0>(one) == std::get<0>(other));  // bit for bit
    CHECK(std::get<1>(one) == std::get<1>(other));
    CHECK(std::get<3>(one) == std::get<3>(other));
    // What the holder meets: summed tile by tile in a batch, over the whole box at once by
    // materialInside: the same to rounding.
    const auto& a = std::get<4>(one);
    const auto& b = std::get<4>(other);
    REQUIRE(a.size() == b.size());
    for (std::size_t k = 0; k < a.size(); ++k)
      CHECK(b[k] == Approx(a[k]).epsilon(1e-12).margin(1e-12));
  }
  // (The holder meets material, far beyond its threshold, in the ramp's last steps: at the
  // last its face is 0.8-0.9 mm into the block, a 16 mm disc moving 1.25 mm: 0.8 x (201 + 20)
  // = 177 mm^3 at least, less the ball's groove under it, at most 6 mm x 0.9 mm x 17.3 mm =
  // 93 mm^3: more than 80 mm^3.)
  CHECK(std::get<4>(one).back() > 80.0);
  // (Cuts were made: not a comparison of nothing. The first step, the ball from z = 0 down
  // 0.1 mm over 1.25 mm, takes at least a few mm^3.)
  CHECK(std::get<2>(one) > 0.1);
  CHECK(std::get<1>(one).size() > 3 * static_cast<std::size_t>(134 * 134));
}
