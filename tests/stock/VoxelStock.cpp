// Tests of stock/VoxelStock.h: removed volumes against closed forms, cut at 30 degrees to
// the grid (grid-aligned cuts with L a multiple of h look exact and prove nothing).
//
// Resolution: h = D / 20 (10 voxels across the cutter radius, the simulator's default) and
// steps of L = 2.5 h. Per-step errors are boundary effects of planes standing in for curved
// surfaces inside one voxel (tangent planes moved by their curvature's sagitta). Every case
// here stays within the 0.5 % per step: steps that keep their height (slots, side
// cuts, arcs: the swept solid in closed form, a flat bottom's rim as two faces) and plunges
// to 0.09 %; steps that change height (ramps, helices), whose rim a flat end mill's voxels
// sample 4 x 4 x 4, to 0.31 % (flat end mill; 0.25 % taper, 0.13 % or less ball and bull).

#include "stock/VoxelStock.h"
#include "cutters/CrossSection.h"
#include "cutters/Error.h"
#include "stock/DexelStock.h"
#include "tests/stock/StockTestSupport.h"

#include <catch2/catch.hpp>

#include <tbb/global_control.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <vector>

using namespace engage;
using Catch::Matchers::Contains;

using namespace engage::test;

TEST_CASE("a box stock holds exactly its volume, wherever its faces fall", "[stock]") {
  // Per-axis covered fractions sum to the box length / h exactly, so the product does too.
  Box3 b;
  b.min = {0.03, -1.07, 0.0};
  b.max = {10.11, 5.5, 3.33};
  const VoxelStock s = VoxelStock::box(b, 0.25);
  // Fractions are stored as 32-bit floats: 1e-6 relative covers their rounding.
  CHECK(s.volume() == Approx(10.08 * 6.57 * 3.33).epsilon(1e-6));
  CHECK(s.bounds().min.x() <= 0.03);
  CHECK(s.bounds().max.z() >= 3.33);
  CHECK_THROWS_WITH(VoxelStock::box(b, 0.00001), Contains("choose a larger --voxel"));
  b.max.x() = b.min.x();
  CHECK_THROWS_WITH(VoxelStock::box(b, 0.25), Contains("stock box is empty along X"));
}

TEST_CASE("a box stock's memory bound counts its partial faces and the leaves the cuts reach",
          "[stock]") {
  // Voxels of 0.125 mm: leaves of 1 mm (8 voxels). Voxel i covers [(i - 1/2) h, (i + 1/2) h],
  // so a face at (k + 1/2) h lies between voxels and one at k h halves them.
  const double h = 0.125;
  const double cutLeaf = 512 * 40.0;  // bytes a cut leaf holds (VoxelStock.cpp), by hand
  const double faceLeaf = 2.5e3;      // bytes of a leaf of a partly covered face
  Box3 onGrid;  // voxels 0 .. 76 along X and Y (leaves 0 .. 9: 10), -31 .. -1 along Z (4)
  onGrid.min = {-0.5 * h, -0.5 * h, -31.5 * h};
  onGrid.max = {9.5 + 0.5 * h, 9.5 + 0.5 * h, -0.5 * h};
  SECTION("no cut, faces between voxels: nothing") {
    const std::vector<Box3> none;
    CHECK(VoxelStock::memoryBound(onGrid, h, &none) == 0.0);
  }
  SECTION("a cut: its leaves, widened by a voxel, once however often they are reached") {
    // X 2.1 .. 3.9 mm and a voxel each side: voxels 16 .. 32, leaves 2 .. 4 (3); Y 5.05 ..
    // 5.2: voxels 39 .. 43, leaves 4 and 5 (2); Z -1 .. 0: voxels -9 .. 1, within the box's
    // -9 .. -1, leaves -2 and -1 (2).
    Box3 cut;
    cut.min = {2.1, 5.05, -1.0};
    cut.max = {3.9, 5.2, 0.0};
    const std::vector<Box3> reach{cut, cut};
    CHECK(VoxelStock::memoryBound(onGrid, h, &reach) == Approx(3 * 2 * 2 * cutLeaf));
    // Counting stops past `stopAbove`.
    CHECK(VoxelStock::memoryBound(onGrid, h, &reach, cutLeaf) == Approx(2 * cutLeaf));
  }
  SECTION("a top face that halves its voxels: a layer of leaves over the whole top") {
    Box3 b = onGrid;
    b.max.z() = 0.0;
    const std::vector<Box3> none;
    CHECK(VoxelStock::memoryBound(b, h, &none) == Approx(10 * 10 * faceLeaf));
  }
  SECTION("without a reach, every voxel as if cut (the earlier bound, for meshes and files)") {
    CHECK(VoxelStock::memoryBound(onGrid, h) > 80 * 80 * 32 * 40.0);
  }
}

TEST_CASE("full slot at 30 deg: every step removes D x depth x L", "[stock]") {
  for (const AptCutter& c :
       {AptCutter::flat(6.0, 18.0), AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0),
        AptCutter::taper(6.0, kPi / 12, 18.0)}) {
    INFO(shapeName(c.shape()));
    const double h = 6.0 / 20.0;
    const double L = 2.5 * h;
    Box3 b;
    b.min = {-30, -30, -10};
    b.max = {30, 30, 0};
    VoxelStock s = VoxelStock::box(b, h);
    // Slot: the previous pass is far away (s > 2 W): the area is the full profile width.
    const double area = exactCrossSection(c, 100.0, 2.0).area;
    const auto v = pass(s, c, Eigen::Vector3d(0, 0, -2) - 10.0 * kDir, kDir, 20.0, L);
    CHECK(worstRelative(v, area * L) < 0.005);
    // Measured worst 0.012 % (flat), 0.007 %, 0.008 %, 0.005 % (taper); means within 0.001 %.
    CHECK(std::abs(meanRelative(v, area * L)) < 0.002);
  }
}

TEST_CASE("side cut at stepover s: every step removes y_G x L", "[stock]") {
  for (const AptCutter& c :
       {AptCutter::flat(6.0, 18.0), AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0),
        AptCutter::taper(6.0, kPi / 12, 18.0)}) {
    INFO(shapeName(c.shape()));
    const double h = 6.0 / 20.0;
    const double L = 2.5 * h;
    const double stepover = 2.0;
    Box3 b;
    b.min = {-30, -30, -10};
    b.max = {30, 30, 0};
    VoxelStock s = VoxelStock::box(b, h);
    const Eigen::Vector3d a = Eigen::Vector3d(0, 0, -2) - 12.0 * kDir;
    // Previous pass, offset by s away from the stock (toward -kSide), then the measured pass.
    pass(s, c, a - stepover * kSide, kDir, 24.0, 4.0);
    const auto v = pass(s, c, a, kDir, 20.0, L);
    const double expected = exactCrossSection(c, stepover, 2.0).area * L;
    // Measured worst 0.03 % (flat), 0.01 % (ball), 0.04 % (bull), 0.02 % (taper); means
    // within 0.01 %.
    CHECK(worstRelative(v, expected) < 0.005);
    CHECK(std::abs(meanRelative(v, expected)) < 0.001);
  }
}

TEST_CASE("plunge and ramp against their closed forms", "[stock]") {
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  const double h = 6.0 / 20.0;
  Box3 b;
  b.min = {-30, -30, -10};
  b.max = {30, 30, 0};
  SECTION("plunge: pi r^2 per unit depth") {
    VoxelStock s = VoxelStock::box(b, h);
    const Eigen::Vector3d top(0.37, 0.11, 0.0);
    double total = 0.0;
    const double dz = 2.5 * h;
    for (int k = 0; k < 8; ++k)
      total += s.remove(Sweep(c,
                              line(top - k * dz * Eigen::Vector3d::UnitZ(),
                                   top - (k + 1) * dz * Eigen::Vector3d::UnitZ()),
                              h))
                   .volume;
    CHECK(total == Approx(kPi * 9.0 * 8 * dz).epsilon(0.005));
  }
  SECTION("plunge of every tool: each step takes the tool's slice pi W(z)^2 dz") {
    // The tool below the top face at tip depth D holds pi int_0^D W(z)^2 dz; a step from
    // D_k to D_k+1 takes the difference. W from the profile, integrated by Simpson's rule on
    // 2000 intervals (W^2 is a polynomial on each piece of the profile: the rule's error is
    // at the few pieces' ends, below 1e-6 relative).
    for (const AptCutter& t : {AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0),
                               AptCutter::taper(6.0, kPi / 12, 18.0)}) {
      INFO(shapeName(t.shape()));
      VoxelStock s = VoxelStock::box(b, h);
      const Eigen::Vector3d top(0.37, 0.11, 0.0);
      const double dz = 2.5 * h;
      auto slice = [&](double z0, double z1) {
        const int n = 2000;
        double sum = 0.0;
        for (int i = 0; i <= n; ++i) {
          const double z = z0 + (z1 - z0) * i / n;
          const double w = t.radiusAt(z);
          sum += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * w * w;
        }
        return kPi * sum * (z1 - z0) / (3.0 * n);
      };
      double first = 0.0, worst = 0.0;
      for (int k = 0; k < 10; ++k) {
        const double v = s.remove(Sweep(t,
                                        line(top - k * dz * Eigen::Vector3d::UnitZ(),
                                             top - (k + 1) * dz * Eigen::Vector3d::UnitZ()),
                                        h))
                             .volume;
        const double e = std::abs(v / slice(k * dz, (k + 1) * dz) - 1.0);
        (k == 0 ? first : worst) = std::max(k == 0 ? first : worst, e);
      }
      // Measured: later steps 0.006 % (ball), 0.017 % (bull), 0.014 % (taper) at worst; the
      // first step 0.002 %, 0.009 %, 0.031 %. Without the tangent planes' curvature
      // correction (the surface's sagitta) 0.27/0.16/0.07 % and 0.73/0.57/0.08 % (a ball's tip
      // entering the top face has its sphere's sagitta all in fresh voxels); with half of it,
      // about half that. The bounds sit between: 0.05 % and 0.1 %.
      CHECK(worst < 0.0005);
      CHECK(first < 0.001);
    }
  }
  SECTION("plunge through the bottom face, which falls on a voxel centre") {
    // The bottom voxels hold their upper half; the tool's last step must take all of it
    // (a fraction alone kept it: min(1/2, 1 - 1/2), 20 % of that step).
    Box3 thin = b;
    thin.min.z() = -3.0;  // -10 h: a voxel centre
    VoxelStock s = VoxelStock::box(thin, h);
    const Eigen::Vector3d top(0.37, 0.11, 0.0);
    const double dz = 2.5 * h;
    std::vector<double> v;
    for (int k = 0; k < 4; ++k)
      v.push_back(s.remove(Sweep(c,
                                 line(top - k * dz * Eigen::Vector3d::UnitZ(),
                                      top - (k + 1) * dz * Eigen::Vector3d::UnitZ()),
                                 h))
                      .volume);
    // Every step removes pi r^2 dz; the last ends on the bottom face. Measured within 0.02 %.
    for (double x : v)
      CHECK(x == Approx(kPi * 9.0 * dz).epsilon(0.005));
  }
  SECTION("ramp at 5 deg from the top, every tool: rampVolume's V(x)") {
    // V(x) for a ramp of horizontal length x (tests/stock/StockTestSupport.h; for the flat
    // end mill tan a (r x^2 + pi r^2 x)).
    const double alpha = 5.0 * kPi / 180.0;
    const Eigen::Vector3d slope = kDir + std::tan(alpha) * Eigen::Vector3d(0, 0, -1);
    const Eigen::Vector3d a = -10.0 * kDir;
    const double L = 2.5 * h;
    for (const AptCutter& t : {c, AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0),
                               AptCutter::taper(6.0, kPi / 12, 18.0)}) {
      INFO(shapeName(t.shape()));
      VoxelStock s = VoxelStock::box(b, h);
      auto V = [&](double x) { return rampVolume(t, alpha, x); };
      double worst = 0.0;
      double total = 0.0;
      for (int k = 0; k < 30; ++k) {
        const double v =
            s.remove(Sweep(t, line(a + k * L * slope, a + (k + 1) * L * slope), h)).volume;
        total += v;
        // The first 8 steps end shallower than 1.75 voxels (0.066 mm deeper each): their
        // depth, not their length, is below the resolution.
        if (k >= 8) worst = std::max(worst, std::abs(v / (V((k + 1) * L) - V(k * L)) - 1.0));
      }
      // Measured worst 0.13 % (flat), 0.01 % (ball), 0.05 % (bull), 0.15 % (taper).
      CHECK(worst < 0.005);
      // Measured -0.001 % (flat), -0.001 %, -0.003 %, +0.009 % (taper). The bound is 0.1 %,
      // the for stock-before minus stock-after: the steps' errors are boundary
      // effects that alternate in sign and should cancel over the pass (before the rim's
      // sub-cubes cut the material sub-cube by sub-cube, the flat end mill's floor kept
      // 0.03 voxel too much: -0.30 %).
      CHECK(total == Approx(V(30 * L)).epsilon(0.001));
    }
  }
}

TEST_CASE("a top face skimmed 0.01 mm deep, then along the same track 0.01 mm deeper", "[stock]") {
  // A flat end mill plunges 0.01 mm into the top face and skims 49.5 mm at 30 deg to the
  // grid, then does the same 0.01 mm deeper: each pass takes the track, a rectangle 2 r wide
  // and its two half discs, 0.01 mm deep. The second pass's rim meets the first one's face,
  // floor and wall in one voxel: it must keep the wall that neither pass reaches. (It had
  // kept the two floors instead, losing the face's material beside the track.)
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  const double h = 6.0 / 20.0;
  const double L = 2.5 * h;
  const double length = 66 * L;
  const double expected = (6.0 * length + kPi * 9.0) * 0.01;
  // The track's offset across the grid and the face's height in its voxel (0: its centre).
  for (const auto& [offset, top] :
       {std::pair{0.0, 0.0}, std::pair{0.1, 0.0}, std::pair{0.0, 0.14}, std::pair{0.23, 0.07}}) {
    INFO("offset " << offset << " mm, face at z = " << top << " mm");
    Box3 b;
    b.min = {0.0, -30.0, -10.0};
    b.max = {60.0, 30.0, top};
    VoxelStock s = VoxelStock::box(b, h);
    auto skim = [&](double depth) {
      const Eigen::Vector3d a(8.0, offset - 15.0, top - depth);
      double v = s.remove(Sweep(c, line(a + Eigen::Vector3d::UnitZ(), a), h)).volume;
      for (int k = 0; k < 66; ++k)
        v += s.remove(Sweep(c, line(a + k * L * kDir, a + (k + 1) * L * kDir), h)).volume;
      return v;
    };
    const double first = skim(0.01);
    const double second = skim(0.02);
    // Measured: both passes +0.007 % at every placement (the old pair: the second +0.18 to
    // +0.33 %); 0.05 % is a tenth of the bound for a move.
    CHECK(first == Approx(expected).epsilon(0.0005));
    CHECK(second == Approx(expected).epsilon(0.0005));
  }
}

TEST_CASE("helical bore: every step after the first turns the same volume", "[stock]") {
  // The closed form of helixSteadyStep (tests/stock/StockTestSupport.h).
  const double h = 6.0 / 20.0, L = 2.5 * h, Rh = 1.2, p = 1.0;
  Box3 b;
  b.min = {-8, -8, -8};
  b.max = {8, 8, 0};
  for (const AptCutter& c : {AptCutter::flat(6.0, 18.0), AptCutter::ball(6.0, 18.0)}) {
    INFO(std::string(shapeName(c.shape())));
    VoxelStock s = VoxelStock::box(b, h);
    const std::vector<double> v = helix(s, c, Eigen::Vector3d(0.37, 0.11, 0.0), Rh, p, 6.0, L);
    const double expected = helixSteadyStep(Rh, 3.0, p, L);
    const std::size_t skip = v.size() * 4 / 6;
    // Measured worst 0.31 % (flat), 0.07 % (ball); means 0.09 % and -0.00 %. (Centred on
    // the grid, as in bench_stock_accuracy: 0.30 % and 0.13 %.)
    CHECK(worstRelative(v, expected, skip) < 0.005);
    CHECK(std::abs(meanRelative(v, expected, skip)) < 0.002);
  }
}

TEST_CASE("concave and convex arcs at stepover s: area x speed of the centroid", "[stock]") {
  for (const AptCutter& c :
       {AptCutter::flat(6.0, 18.0), AptCutter::ball(6.0, 18.0), AptCutter::bull(6.0, 1.0, 18.0),
        AptCutter::taper(6.0, kPi / 12, 18.0)}) {
    const double h = 6.0 / 20.0;
    const double stepover = 2.0, depth = 2.0, rho = 15.0;
    const CrossSection x = exactCrossSection(c, stepover, depth);
    for (const int side : {+1, -1}) {  // +1 concave: stock outside; -1 convex: stock inside
      INFO(shapeName(c.shape()) << (side > 0 ? " concave" : " convex"));
      Box3 b;
      b.min = {-40, -40, -10};
      b.max = {40, 40, 0};
      if (side < 0) {  // convex: a disk of stock inside the path
        b.min = {-rho - 1, -rho - 1, -10};
        b.max = {rho + 1, rho + 1, 0};
      }
      VoxelStock s = VoxelStock::box(b, h);
      auto arcStep = [&](double r, double a0, double a1) {
        return arc(Eigen::Vector3d(0.123, -0.077, 0), r, a0, a1, -depth);
      };
      if (side < 0) {
        // Clear everything outside the previous pass radius (rho + s), then cut the pass there.
        for (double a = 0; a < 2 * kPi; a += 0.2)
          s.remove(Sweep(c, arcStep(rho + stepover, a, a + 0.2), h));
      } else {
        for (double a = 0; a < 2 * kPi; a += 0.2)
          s.remove(Sweep(c, arcStep(rho - stepover, a, a + 0.2), h));
      }
      const double dA = 2.5 * h / rho;  // steps of 2.5 voxels at the tool centre
      s.remove(Sweep(c, arcStep(rho, 0.0, 0.0 + 1e-9), h));
      const double expected = x.area * (rho + side * x.centroidX) * dA;  // Pappus
      std::vector<double> v;
      for (double a = 0.0; a < 1.5; a += dA)
        v.push_back(s.remove(Sweep(c, arcStep(rho, a, a + dA), h)).volume);
      // Measured worst 0.01-0.09 % (the four tools, concave and convex); means within 0.01 %.
      CHECK(worstRelative(v, expected, 2) < 0.005);
      CHECK(std::abs(meanRelative(v, expected, 2)) < 0.001);
    }
  }
}

TEST_CASE("removed volume accounts for all the stock lost, at any thread count", "[stock]") {
  const AptCutter c = AptCutter::ball(4.0, 12.0);
  Box3 b;
  b.min = {-10, -10, -5};
  b.max = {10, 10, 0};
  auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
    VoxelStock s = VoxelStock::box(b, 0.2);
    const double before = s.volume();
    double removed = 0.0;
    std::vector<double> steps;
    for (int k = 0; k < 40; ++k) {
      const Eigen::Vector3d p0 = Eigen::Vector3d(-8 + 0.4 * k, -3 + 0.15 * k, -1.5);
      const Removal r = s.remove(Sweep(c, line(p0, p0 + Eigen::Vector3d(0.4, 0.15, -0.02)), 0.2));
      removed += r.volume;
      steps.push_back(r.volume);
    }
    CHECK(removed == Approx(before - s.volume()).epsilon(1e-9));
    return steps;
  };
  const auto one = run(1);
  const auto two = run(2);
  CHECK(one == two);  // bit for bit
}

TEST_CASE("the axial depth of a slot at 30 degrees to the grid", "[stock]") {
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  const double h = 0.3;
  Box3 b;
  b.min = {-30, -30, -10};
  b.max = {30, 30, 0};
  VoxelStock s = VoxelStock::box(b, h);
  const Eigen::Vector3d a = Eigen::Vector3d(0, 0, -2) - 10.0 * kDir;
  s.remove(Sweep(c, line(a, a), h));
  Removal r;
  for (int k = 0; k < 10; ++k)
    r = s.remove(Sweep(c, line(a + k * 0.75 * kDir, a + (k + 1) * 0.75 * kDir), h));
  // The stock's top lies on the middle of a voxel layer: the depth 2 mm to float rounding
  // of the fractions (a boundary crossing a voxel is placed by its lost share).
  CHECK(r.axialDepth == Approx(2.0).margin(1e-4));
  CHECK(r.top == Approx(2.0).margin(1e-4));
}

namespace {

/// A file name in the temporary folder for this test run.
std::string tempVdb(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("engage_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

}  // namespace

TEST_CASE("a stock.vdb's bounds come from its metadata, before the grid is read", "[stock][vdb]") {
  // The box's partial voxels reach out to whole voxels of 0.5 mm (voxel i covers
  // [(i - 1/2) h, (i + 1/2) h]): X 0.13 .. 10.11 lies in voxels 0 .. 20, so -0.25 .. 10.25.
  Box3 b;
  b.min = {0.13, -1.07, -3.21};
  b.max = {10.11, 5.5, 0.0};
  const std::string path = tempVdb("bounds.vdb");
  VoxelStock::box(b, 0.5).writeStockVdb(path);
  const std::optional<Box3> r = VoxelStock::fileBounds(path);
  REQUIRE(r);
  CHECK(r->min.x() == Approx(-0.25));  // voxel 0
  CHECK(r->max.x() == Approx(10.25));  // voxel 20
  CHECK(r->min.y() == Approx(-1.25));  // voxel -2
  CHECK(r->max.y() == Approx(5.75));   // voxel 11
  CHECK(r->min.z() == Approx(-3.25));  // voxel -6
  CHECK(r->max.z() == Approx(0.25));   // voxel 0, half material
  CHECK_FALSE(VoxelStock::fileBounds(tempVdb("missing.vdb") + ".none"));
}

TEST_CASE("a stock.vdb read back holds the volume it was written with, at any voxel size",
          "[stock][vdb]") {
  // A box off the grid: its shell voxels are partial. Written at h0 = 0.5, read at 0.5 (a
  // copy), 0.3 and 0.7 (resampled by overlap, which keeps the material) and as dexels.
  Box3 b;
  b.min = {0.13, -1.07, -3.21};
  b.max = {10.11, 5.5, 0.0};
  const double boxVolume = 9.98 * 6.57 * 3.21;
  const std::string path = tempVdb("box.vdb");
  VoxelStock::box(b, 0.5).writeStockVdb(path);
  // Fractions are 32-bit floats, resampled with double sums rounded to floats: 1e-5 relative
  // covers their rounding (a voxel's fraction carries 6e-8; the shell is a few thousand).
  CHECK(VoxelStock::fromVdb(path, 0.5).volume() == Approx(boxVolume).epsilon(1e-6));
  for (double h : {0.3, 0.7}) {
    INFO("h = " << h);
    const VoxelStock v = VoxelStock::fromVdb(path, h);
    CHECK(v.voxelSize() == h);
    CHECK(v.volume() == Approx(boxVolume).epsilon(1e-5));
    // The material spreads at most over the new voxels the old shell overlaps.
    const Box3 r = v.bounds();
    CHECK(r.min.x() >= b.min.x() - 0.5 - h);
    CHECK(r.max.z() <= b.max.z() + 0.5 + h);
    CHECK(r.max.z() >= b.max.z() - 1e-9);
  }
  for (double h : {0.5, 0.3, 0.7}) {
    INFO("dexels, h = " << h);
    const DexelStock d = VoxelStock::dexelsFromVdb(path, h);
    CHECK(d.volume() == Approx(boxVolume).epsilon(1e-5));
    // No material above the top face, at the walls' edges and corners too: a flat end mill
    // over the whole block lifted off the top face meets none (to the fractions' float
    // rounding), and the bounds hold the box's heights (1e-6 mm). Taking a corner voxel as a wall's
    // share of its full height had put 0.155 mm^3 (on the file's grid) and 0.075 and 0.72 mm^3
    // (resampled) above the face; resampling a corner (three faces) by two of its planes
    // 0.025 and 0.014 mm^3.
    DexelStock lifted = d;
    const double met = lifted
                           .remove(Sweep(AptCutter::flat(30.0, 10.0),
                                         line({5.0, 2.2, b.max.z()}, {5.0, 2.2, 10.0}), h))
                           .volume;
    CHECK(met <= 1e-6);  // (measured 0 on the file's grid, 1e-8 mm^3 resampled: float sums)
    CHECK(d.bounds().max.z() <= b.max.z() + 1e-6);
    CHECK(d.bounds().min.z() >= b.min.z() - 1e-6);
  }
  std::filesystem::remove(path);
}

TEST_CASE("a cut continued from a stock.vdb removes what the same cut in one run removes",
          "[stock][vdb]") {
  // Rough a slot (flat D = 6, 2 mm deep, along X through a 40 mm block), write the stock, then
  // finish it 0.3 mm deeper and 0.3 mm wider on one side, in the same stock and in stocks read
  // from the file: as voxels of the same size, of another size, and as dexels. The finishing
  // cut's closed form: the new section (6 x 2.3) less the old one inside it (5.7 x 2), times 40.
  const double h = 0.3;
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  Box3 b;
  b.min = {0.0, 0.0, -10.0};
  b.max = {40.0, 20.0, 0.0};
  auto cut = [&](Stock& s, double y, double z) {
    return s.remove(Sweep(c, line({-5.0, y, z}, {45.0, y, z}), s.resolution())).volume;
  };
  VoxelStock one = VoxelStock::box(b, h);
  const double rough = cut(one, 10.0, -2.0);
  CHECK(rough == Approx(6.0 * 2.0 * 40.0).epsilon(1e-4));  // (measured 2e-6 relative)
  const std::string path = tempVdb("rough.vdb");
  one.writeStockVdb(path);
  const double finish = 40.0 * (6.0 * 2.3 - 5.7 * 2.0);  // 96 mm^3
  const double inOne = cut(one, 10.3, -2.3);
  VoxelStock same = VoxelStock::fromVdb(path, h);
  VoxelStock finer = VoxelStock::fromVdb(path, 0.2);
  DexelStock dexels = VoxelStock::dexelsFromVdb(path, h);
  const double fromSame = cut(same, 10.3, -2.3), fromFiner = cut(finer, 10.3, -2.3),
               fromDexels = cut(dexels, 10.3, -2.3);
  INFO("one run " << inOne << ", from the file " << fromSame << " / " << fromFiner << " / "
                  << fromDexels << " mm^3 against " << finish);
  // The bar: rough then finish from the file totals one run within 0.1 %.
  CHECK(std::abs((rough + fromSame) - (rough + inOne)) < 1e-3 * (rough + inOne));
  CHECK(std::abs((rough + fromFiner) - (rough + inOne)) < 1e-3 * (rough + inOne));
  // Against the closed form, each finishing cut within 1 % (a 0.3 mm floor re-cut is a thin
  // cut, where the voxels' known error is ~2 %, issue 18). Measured: one run -0.53 %, from the
  // file -0.011 % (same voxels: the planes come back, but not which step made them, and the
  // rule for a cut continuing the last step's plane is not applied), -0.0003 % (0.2 mm
  // voxels), -0.03 % (dexels).
  CHECK(fromSame == Approx(finish).epsilon(0.01));
  CHECK(fromFiner == Approx(finish).epsilon(0.01));
  CHECK(fromDexels == Approx(finish).epsilon(0.01));
  std::filesystem::remove(path);
}

namespace {

/// The stock.vdb tests' dexel stock: a box whose sides are not on the ray lattice (its last
/// columns covered in part), 0.3 mm rays.
constexpr double kRays = 0.3;
DexelStock offLatticeBox() {
  Box3 b;
  b.min = {0.05, 0.1, -10.0};
  b.max = {40.0, 20.02, 0.0};
  return DexelStock::box(b, kRays);
}

/// A slot 2 mm deep and a ramp across it with a 6 mm flat end mill: the volume they remove.
double slotAndRamp(Stock& s) {
  const AptCutter c = AptCutter::flat(6.0, 18.0);
  double v = s.remove(Sweep(c, line({-5.0, 10.0, -2.0}, {45.0, 10.0, -2.0}), kRays)).volume;
  v += s.remove(Sweep(c, line({5.0, 3.0, 0.5}, {35.0, 17.0, -3.1}), kRays)).volume;
  return v;
}

}  // namespace

TEST_CASE("a dexel stock written to stock.vdb comes back ray for ray", "[stock][vdb]") {
  // A box whose sides are not on the ray lattice (its last columns covered in part), a slot
  // and a ramp cut in dexels of 0.3 mm, written as a dexel run writes stock.vdb: read back at
  // the same spacing, every ray, interval and column share is the same number, so the same
  // cuts again remove exactly nothing (through the voxels' fractions alone they removed 17.8
  // mm^3 again on the Fusion 360 pocket); at another spacing the fractions are read as before.
  const double h = kRays;
  DexelStock d = offLatticeBox();
  REQUIRE(slotAndRamp(d) > 400.0);
  const std::string path = tempVdb("dexel_rays.vdb");
  VoxelStock::fromDexels(d).writeStockVdb(path, &d);
  DexelStock back = VoxelStock::dexelsFromVdb(path, h);
  REQUIRE(back.raysX() == d.raysX());
  REQUIRE(back.raysY() == d.raysY());
  CHECK(back.originX() == d.originX());
  CHECK(back.originY() == d.originY());
  std::size_t intervals = 0;
  for (int j = 0; j < d.raysY(); ++j)
    for (int i = 0; i < d.raysX(); ++i) {
      CHECK(back.weight(i, j) == d.weight(i, j));
      const auto &a = d.ray(i, j), &r = back.ray(i, j);
      REQUIRE(r.size() == a.size());
      for (std::size_t n = 0; n < a.size(); ++n) {
        CHECK(r[n].z0 == a[n].z0);
        CHECK(r[n].z1 == a[n].z1);
        CHECK(r[n].f == a[n].f);
        ++intervals;
      }
    }
  CHECK(intervals > static_cast<std::size_t>(d.raysX() * d.raysY()));  // the cuts split rays
  CHECK(back.volume() == d.volume());
  CHECK(slotAndRamp(back) == 0.0);
  // Another spacing: the fractions, whose volume is the stock's to their float rounding.
  const DexelStock other = VoxelStock::dexelsFromVdb(path, 0.25);
  CHECK(other.volume() == Approx(d.volume()).epsilon(1e-4));
  std::filesystem::remove(path);
}

TEST_CASE(
    "a dexel run's stock.vdb of a large grid: fractions coarser than the rays, the rays exact",
    "[stock][vdb]") {
  // The band estimate on a box on the ray lattice (h 0.25, 6 x 4.5 x 3 mm: 24 x 18 rays, each
  // one whole interval): 7 (2 (25 x 19 + 19 x 13 + 13 x 25) + 2 x 24 x 18) = 20,706 voxels
  // (the bounds' faces in voxels, 25 x 19 x 13, and two partial voxels a ray), by hand.
  const double h = 0.25;
  Box3 b;
  b.min = {0.0, 0.0, -3.0};
  b.max = {6.0, 4.5, 0.0};
  const DexelStock box = DexelStock::box(b, h);
  REQUIRE(box.raysX() == 24);
  REQUIRE(box.raysY() == 18);
  const double band = 20706.0;
  CHECK(VoxelStock::dexelFileFactor(box, band) == 1);
  CHECK(VoxelStock::dexelFileFactor(box, band - 1.0) == 2);        // band / 4 fits
  CHECK(VoxelStock::dexelFileFactor(box, band / 4.0 - 1.0) == 4);  // band / 16 fits
  CHECK(VoxelStock::dexelFileFactor(box, band / 16.0 - 1.0) == 8);
  CHECK(VoxelStock::dexelFileFactor(box, 1.0) == 8);  // (8 at most)
  // From the box alone (the memory estimate's, before any ray exists): the same band.
  CHECK(VoxelStock::dexelFileFactor(b, h, band) == 1);
  CHECK(VoxelStock::dexelFileFactor(b, h, band - 1.0) == 2);
  CHECK(VoxelStock::dexelFileFactor(b, h, band / 16.0 - 1.0) == 8);
  // Written at factor 4 (band / 16 = 1294 fits 2000): 1 mm voxels whose centres lie at
  // 0.375 mm + k mm; the box's 81 mm^3 in 32-bit fractions (0.875 and 0.125 at its faces,
  // exact in binary); bounds as the voxels at h would have them, half a voxel (0.125 mm) out.
  const std::string coarse = tempVdb("dexel_coarse.vdb"), fine = tempVdb("dexel_fine.vdb");
  VoxelStock::writeDexelStockVdb(box, coarse, 2000.0);
  CHECK(VoxelStock::fileVolume(coarse) == Approx(81.0).epsilon(1e-9));
  const std::optional<Box3> bounds = VoxelStock::fileBounds(coarse);
  REQUIRE(bounds);
  CHECK(bounds->min.isApprox(Eigen::Vector3d(-0.125, -0.125, -3.125), 1e-12));
  CHECK(bounds->max.isApprox(Eigen::Vector3d(6.125, 4.625, 0.125), 1e-12));
  VoxelStock::fromDexels(box).writeStockVdb(fine, &box);
  const std::optional<Box3> fineBounds = VoxelStock::fileBounds(fine);
  REQUIRE(fineBounds);
  CHECK(fineBounds->min.isApprox(bounds->min, 1e-12));
  CHECK(fineBounds->max.isApprox(bounds->max, 1e-12));

  // A box off the lattice, a slot and a ramp cut (as above), at each factor: the rays come
  // back exactly, a voxel run from the file starts from the voxels fromDexels makes of them
  // (to the bit), and the coarse fractions keep the stock's volume (to 32-bit floats).
  DexelStock d = offLatticeBox();
  REQUIRE(slotAndRamp(d) > 400.0);
  const double voxels = VoxelStock::fromDexels(d).volume();
  for (const int factor : {2, 4, 8}) {
    double budget = 1e9;  // the largest band budget that asks for this factor
    while (budget > 1.0 && VoxelStock::dexelFileFactor(d, budget) < factor)
      budget /= 2.0;
    REQUIRE(VoxelStock::dexelFileFactor(d, budget) == factor);
    VoxelStock::writeDexelStockVdb(d, coarse, budget);
    CHECK(VoxelStock::fileVolume(coarse) == Approx(d.volume()).epsilon(1e-6));
    DexelStock back = VoxelStock::dexelsFromVdb(coarse, kRays);
    CHECK(back.volume() == d.volume());
    CHECK(back.segments() == d.segments());
    CHECK(slotAndRamp(back) == 0.0);
    CHECK(VoxelStock::fromVdb(coarse, kRays).volume() == voxels);
    CHECK(VoxelStock::dexelsFromVdb(coarse, 0.25).volume() == Approx(d.volume()).epsilon(1e-4));
  }
  std::filesystem::remove(coarse);
  std::filesystem::remove(fine);
}

TEST_CASE("a dexel stock.vdb's uncut blocks of rays are tiles, read back ray for ray",
          "[stock][vdb]") {
  // The stock.vdb tests' box (133 x 67 rays of 0.3 mm), cut only where rays of every block of
  // 8 x 64 (a leaf of first intervals) are not: a 1 mm slot along its far side (y 19.3-20.3,
  // rays 64 and on) and a ramp at x 2-8. The blocks at x 12-38 and y 0-19.2 are uncut: each
  // is written as one tile a grid (layout 3), and every ray, in or out of them, must come back
  // as it was, the cuts again removing what they remove from the stock itself; at each
  // coarser factor the same.
  DexelStock d = offLatticeBox();
  const AptCutter c = AptCutter::flat(1.0, 6.0);
  auto cuts = [&](Stock& s) {
    double v = s.remove(Sweep(c, line({-2.0, 19.8, -0.5}, {42.0, 19.8, -0.5}), kRays)).volume;
    v += s.remove(Sweep(c, line({2.0, 2.0, 0.2}, {8.0, 15.0, -1.3}), kRays)).volume;
    return v;
  };
  REQUIRE(cuts(d) > 20.0);
  // The same cuts again in the stock itself: what a stock read back exactly must remove too
  // (6e-17 mm^3 of rounding here, not 0).
  DexelStock again = d;
  const double twice = cuts(again);
  REQUIRE(twice < 1e-12);
  const std::string path = tempVdb("dexel_tiles.vdb");
  auto same = [&](const DexelStock& back) {
    REQUIRE(back.raysX() == d.raysX());
    REQUIRE(back.raysY() == d.raysY());
    std::size_t differ = 0;
    for (int j = 0; j < d.raysY(); ++j)
      for (int i = 0; i < d.raysX(); ++i) {
        const auto &a = d.ray(i, j), &r = back.ray(i, j);
        bool alike = r.size() == a.size() && back.weight(i, j) == d.weight(i, j);
        for (std::size_t n = 0; alike && n < a.size(); ++n)
          alike = r[n].z0 == a[n].z0 && r[n].z1 == a[n].z1 && r[n].f == a[n].f &&
                  r[n].mx == a[n].mx && r[n].my == a[n].my;
        differ += alike ? 0 : 1;
      }
    CHECK(differ == 0);
  };
  VoxelStock::fromDexels(d).writeStockVdb(path, &d);
  DexelStock back = VoxelStock::dexelsFromVdb(path, kRays);
  same(back);
  CHECK(cuts(back) == twice);
  for (const int factor : {2, 8}) {
    VoxelStock::writeDexelStockVdbAt(d, path, factor);
    DexelStock coarse = VoxelStock::dexelsFromVdb(path, kRays);
    same(coarse);
    CHECK(cuts(coarse) == twice);
  }
  std::filesystem::remove(path);
}

TEST_CASE("a dexel run's removed.vdb holds the removed volume, coarser when it is large",
          "[stock][vdb]") {
  // removedFileFactor: the least of 1, 2, 4, 8 that keeps 3 values a voxel within the
  // budget; by hand for 1000 voxels (3000 values).
  CHECK(VoxelStock::removedFileFactor(1000.0, 3000.0) == 1);
  CHECK(VoxelStock::removedFileFactor(1000.0, 2999.0) == 2);  // 375 values fit
  CHECK(VoxelStock::removedFileFactor(1000.0, 374.0) == 4);   // 46.9 fit
  CHECK(VoxelStock::removedFileFactor(1000.0, 46.0) == 8);
  CHECK(VoxelStock::removedFileFactor(1000.0, 1.0) == 8);  // (8 at most)
  // A slot and a ramp (as above) in the box's rays, the log captured: at each factor the file's
  // grid "removed" sums (times its voxel's volume, (factor h)^3) to the volume removed, to its
  // 32-bit floats; a voxel holding more than its own volume would be capped and lose some.
  DexelStock d = offLatticeBox();
  d.captureRemoved(true);
  const double removed = slotAndRamp(d);
  REQUIRE(removed > 400.0);
  double cells = 0.0;  // the log's cells, which the factor is chosen by
  for (int j = 0; j < d.raysY(); ++j)
    for (int i = 0; i < d.raysX(); ++i)
      if (const DexelStock::LostColumn* c = d.removedColumn(i, j))
        cells += static_cast<double>(c->cells.size());
  const std::string path = tempVdb("removed_coarse.vdb");
  for (const int factor : {1, 2, 4, 8}) {
    const double budget = 3.0 * cells / (factor * factor * factor);  // just fits this factor
    REQUIRE(VoxelStock::removedFileFactor(cells, budget) == factor);
    VoxelStock::writeRemovedVdb(d, path, budget);
    INFO("factor " << factor);
    CHECK(VoxelStock::fileVolume(path, "removed") == Approx(removed).epsilon(1e-5));
  }
  // A voxel stock's removed.vdb (its capture grids, coarsened leaf by leaf) the same way.
  Box3 b;  // (offLatticeBox's)
  b.min = {0.05, 0.1, -10.0};
  b.max = {40.0, 20.02, 0.0};
  VoxelStock v = VoxelStock::box(b, kRays);
  v.captureRemoved(true);
  const double fromVoxels = slotAndRamp(v);
  REQUIRE(fromVoxels > 400.0);
  const double voxels = static_cast<double>(v.removedVoxels());
  for (const int factor : {1, 2, 4, 8}) {
    const double budget = 3.0 * voxels / (factor * factor * factor);
    REQUIRE(VoxelStock::removedFileFactor(voxels, budget) == factor);
    v.writeRemovedVdb(path, budget);
    INFO("voxels, factor " << factor);
    CHECK(VoxelStock::fileVolume(path, "removed") == Approx(fromVoxels).epsilon(1e-5));
  }
  std::filesystem::remove(path);
}

TEST_CASE("a dexel run's stock.vdb of the first layout is still read ray for ray", "[stock][vdb]") {
  // Written by the build before the packed layout (5f33fb8): `engage simulate` of a 2 mm flat
  // end mill 1 mm deep across a 6 x 5 x 3 mm box at 0.3 mm (tests/data/dexel_slot_layout1.vdb;
  // G1 X-3 Y2.5 Z-1 to X9), rays at (i, j, n). Its summary: 78.0045 mm^3 left of 90.
  const DexelStock d =
      VoxelStock::dexelsFromVdb(ENGAGE_SOURCE_DIR "/tests/data/dexel_slot_layout1.vdb", 0.3);
  CHECK(d.raysX() == 20);                                   // ceil(6 / 0.3)
  CHECK(d.raysY() == 17);                                   // ceil(5 / 0.3)
  CHECK(d.volume() == Approx(78.0045).epsilon(1e-6));       // (summary.json's 6 digits)
  CHECK(d.segments() > static_cast<std::size_t>(20 * 17));  // the slot's walls split rays
  // The slot's floor 1 mm down on the ray under its path, the box's top beside it.
  CHECK(d.ray(10, 8).back().z1 == Approx(-1.0).margin(1e-4));
  CHECK(d.ray(10, 1).back().z1 == Approx(0.0).margin(1e-12));
}

TEST_CASE(
    "thin cuts into a face: pecks and a wall skim against their closed forms, and pecks "
    "continued from a stock.vdb",
    "[stock][vdb]") {
  // A flat end mill (D = 6) pecks 0.05 mm at a time into a box's top face, which lies inside a
  // voxel (10 / 0.3 = 33.3): each peck takes the cylinder pi r^2 0.05. The rim of each leaves
  // face, floor and wall in one voxel, which two planes cannot hold (the first peck took
  // -5.8 %, the next ones -0.4 to -1.5 %). Then the tool skims 0.01 mm off the side face X60
  // over its whole length (y -5 to 45, bottom at z 4): the slab 0.01 x 6 x 40 mm exactly (a
  // single wedge plane across the rim had cut the wall above it: +1.7 %). Measured: every
  // peck +0.096 % (from the file the same), the skim -0.02 %; bound 0.5 %, issue 18's bar for
  // 95 % of the moves of 1 mm^3 or more.
  const double h = 0.3;
  const AptCutter c = AptCutter::flat(6.0, 20.0);
  Box3 b;
  b.min = {0.0, 0.0, 0.0};
  b.max = {60.0, 40.0, 10.0};
  const double peck = kPi * 9.0 * 0.05;
  auto pecks = [&](Stock& s, int from, int to) {
    std::vector<double> v;
    for (int k = from; k < to; ++k)
      v.push_back(
          s
              .remove(Sweep(
                  c, line({30.0, 30.0, 10.0 - 0.05 * k}, {30.0, 30.0, 10.0 - 0.05 * (k + 1)}), h))
              .volume);
    return v;
  };
  VoxelStock s = VoxelStock::box(b, h);
  for (double v : pecks(s, 0, 2))
    CHECK(v == Approx(peck).epsilon(0.005));
  const std::string path = tempVdb("pecked.vdb");
  s.writeStockVdb(path);
  VoxelStock again = VoxelStock::fromVdb(path, h);
  std::filesystem::remove(path);
  for (Stock* t : {static_cast<Stock*>(&s), static_cast<Stock*>(&again)})
    for (double v : pecks(*t, 2, 5))
      CHECK(v == Approx(peck).epsilon(0.005));
  const double skim = s.remove(Sweep(c, line({62.99, -5.0, 4.0}, {62.99, 45.0, 4.0}), h)).volume;
  CHECK(skim == Approx(0.01 * 6.0 * 40.0).epsilon(0.005));
}

TEST_CASE("stock.vdb's surface holds the signed distance to the stock's surface", "[stock][vdb]") {
  // A block off the grid with a ball end mill's bowl (D = 12 plunged 6 mm: the lower half of a
  // sphere of radius 6 about c, its rim on the top face), h = 0.3, as voxels and as dexels.
  // The exact signed distance (negative in the material): in the material, the nearer of the
  // top face and the sphere; inside the bowl, to the sphere; above the top face, to the face
  // or, over the bowl, to its rim. Left out: the points within 3 h of the rim (an edge, which
  // the fractions' 0.5 iso-surface rounds: up to 0.6 h there) and near the block's other
  // faces.
  const double h = 0.3, r = 6.0;
  const Eigen::Vector3d c(20.13, 19.91, 0.0);
  Box3 b;
  b.min = {0.13, -0.07, -10.0};
  b.max = {40.13, 39.93, 0.0};
  const AptCutter ball = AptCutter::ball(2.0 * r, 20.0);
  auto exact = [&](const Eigen::Vector3d& p) {
    const double q = (p - c).norm(), rho = std::hypot(p.x() - c.x(), p.y() - c.y());
    if (p.z() >= 0.0) return rho >= r ? p.z() : std::hypot(r - rho, p.z());
    if (q < r) return r - q;
    return -std::min(-p.z(), q - r);
  };
  auto checked = [&](const Eigen::Vector3d& p) {
    const double rho = std::hypot(p.x() - c.x(), p.y() - c.y());
    return std::hypot(rho - r, p.z()) >= 3.0 * h && p.z() > -8.0 &&
           std::abs(p.x() - c.x()) < 15.0 && std::abs(p.y() - c.y()) < 15.0;
  };
  VoxelStock voxels = VoxelStock::box(b, h);
  DexelStock dexels = DexelStock::box(b, h);
  const Sweep plunge(ball, line(c + Eigen::Vector3d(0, 0, 5.0), c - Eigen::Vector3d(0, 0, r)), h);
  voxels.remove(plunge);
  dexels.remove(plunge);
  std::vector<std::pair<const char*, VoxelStock>> stocks;
  stocks.emplace_back("voxels", std::move(voxels));
  stocks.emplace_back("dexels", VoxelStock::fromDexels(dexels));
  for (const auto& [model, s] : stocks) {
    double worst = 0.0, sum = 0.0;
    std::size_t n = 0;
    std::set<std::array<long, 3>> band;
    for (const auto& [p, d] : s.surfaceBand()) {
      band.insert({std::lround(p.x() / h), std::lround(p.y() / h), std::lround(p.z() / h)});
      if (!checked(p)) continue;
      const double e = std::abs(d - exact(p));
      worst = std::max(worst, e);
      sum += e;
      ++n;
    }
    // Every voxel within 2.5 h of the surface is in the band (3 h, less the 0.2 h it can be
    // off and a margin).
    std::size_t missing = 0, near = 0;
    for (int i = static_cast<int>(std::lround(5.5 / h));
         i <= static_cast<int>(std::lround(34.5 / h)); ++i)
      for (int j = static_cast<int>(std::lround(5.5 / h));
           j <= static_cast<int>(std::lround(34.5 / h)); ++j)
        for (int k = static_cast<int>(std::lround(-7.5 / h));
             k <= static_cast<int>(std::lround(1.5 / h)); ++k) {
          const Eigen::Vector3d p(i * h, j * h, k * h);
          if (!checked(p) || !(std::abs(exact(p)) < 2.5 * h)) continue;
          ++near;
          if (!band.count({long(i), long(j), long(k)})) ++missing;
        }
    const double mean = sum / static_cast<double>(n);
    INFO(model << ": " << n << " points, worst " << worst / h << " h, mean " << mean / h << " h; "
               << missing << " of " << near << " within 2.5 h not in the band");
    CHECK(near > 10000);
    CHECK(missing == 0);
    // Measured 0.181 and 0.197 h worst, 0.0088 and 0.0095 h mean (OpenVDB's fast sweeping,
    // before: 0.37 and 0.40 h, 0.013 and 0.014 h): a quarter more for other compilers'
    // rounding.
    CHECK(worst < 0.25 * h);
    CHECK(mean < 0.012 * h);
  }
}

TEST_CASE("a stock.vdb that is not an engage stock is refused with its reason", "[stock][vdb]") {
  const std::string missing = tempVdb("missing.vdb");
  CHECK_THROWS_WITH(VoxelStock::fromVdb(missing, 0.3), Contains("no such file"));
  const std::string text = tempVdb("text.vdb");
  std::ofstream(text) << "not a grid\n";
  CHECK_THROWS_WITH(VoxelStock::fromVdb(text, 0.3), Contains("not a VDB file"));
  std::filesystem::remove(text);
  // removed.vdb has grids, but not "stock".
  Box3 b;
  b.min = {0.0, 0.0, -2.0};
  b.max = {4.0, 4.0, 0.0};
  VoxelStock s = VoxelStock::box(b, 0.5);
  s.captureRemoved(true);
  s.remove(Sweep(AptCutter::flat(2.0, 6.0), line({-2, 2, -1}, {6, 2, -1}), 0.5));
  const std::string removed = tempVdb("removed.vdb");
  s.writeRemovedVdb(removed);
  CHECK_THROWS_WITH(VoxelStock::fromVdb(removed, 0.5),
                    Contains("has no grid named 'stock'") && Contains("removed, step"));
  std::filesystem::remove(removed);
}

TEST_CASE("voxel surface within a triangle budget: fewer triangles, the same solid to a cell",
          "[stock][vdb]") {
  // A slot across a box, 0.2 mm voxels: the full grid's surface against a budget of 2,000.
  Box3 b;
  b.min = {0.0, 0.0, -10.0};
  b.max = {40.0, 30.0, 0.0};
  VoxelStock s = VoxelStock::box(b, 0.2);
  s.remove(Sweep(AptCutter::ball(6.0, 18.0), line({-5, 15, -2}, {45, 15, -2}), 0.2));
  const TriangleMesh a = s.viewMesh(0);
  double cell = 0.0;
  const TriangleMesh c = s.viewMesh(2000, &cell);
  CHECK(boundaryEdgeCount(a) == 0);  // closed
  CHECK(boundaryEdgeCount(c) == 0);
  CHECK(c.triangles.size() <= 2000);
  CHECK(c.triangles.size() * 10 < a.triangles.size());
  // The coarser surface lies within about half of one of its cells (2, 4 or 8 voxels) of the
  // stock's: its volume within the box's surface area (3,800 mm^2, the slot's less than 300
  // more) times half a cell.
  INFO("cell " << cell << " mm");
  CHECK(std::abs(meshVolume(c) - s.volume()) <= 4100.0 * cell / 2.0);
}
