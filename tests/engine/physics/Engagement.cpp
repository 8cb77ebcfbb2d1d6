// Tests of engine/physics/Engagement.h: the contact measured in a real stock after a straight
// pass, against the closed forms of a flat end mill's immersion (Altintas, ch. 2.4):
// up milling engages phi in [0, acos(1 - 2 ae / D)], down milling [pi - acos(1 - 2 ae / D), pi],
// a slot [0, pi]; the engaged height is the axial depth.

#include "engine/physics/Engagement.h"

#include "cutters/Numbers.h"
#include "cutters/Sweep.h"
#include "stock/DexelStock.h"
#include "tests/stock/StockTestSupport.h"
#include "tests/support/ContactCases.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <string>

using namespace engage;

namespace {
constexpr double D = 10.0, R = 5.0, ap = 3.0, h = 0.2;

/// A 60 x 40 x 20 mm block (top at z = 0), cut by one pass along +X from outside it to x = 0
/// with the tip at z = -ap and the axis at y = yc; returns the stock.
std::unique_ptr<Stock> cutBlock(bool voxel, double yc) {
  Box3 b;
  b.min = {-30, -20, -20};
  b.max = {30, 20, 0};
  std::unique_ptr<Stock> s = test::boxStock(voxel ? "voxel" : "dexel", b, h);
  const AptCutter flat = AptCutter::flat(D, 20.0);
  StepPath p;
  p.start = {-40.0, yc, -ap};
  p.end = {0.0, yc, -ap};
  s->remove(Sweep(flat, p, h));
  return s;
}

/// The engaged height: the slices in contact, mm.
double engagedHeight(const EdgeEngagement& e) {
  double z = 0.0;
  for (const EdgeSlice& s : e.slices)
    z += s.dz;
  return z;
}

}  // namespace

TEST_CASE("engagement of a flat end mill: slot, up and down milling, against closed forms",
          "[physics]") {
  const AptCutter flat = AptCutter::flat(D, 20.0);
  for (const bool voxel : {true, false}) {
    CAPTURE(voxel);
    // Tolerances: a boundary is read where the wall it ends at, read beyond the cells the cut
    // crossed and followed back to the cutter, meets the edge: exact for these plane walls
    // to the readers' hundredth of a cell (0.01 h / (d gap / d phi) <= 0.03 deg here) and the
    // bisection's 0.006 deg; 0.1 deg. The engaged height is the depth, its top found by
    // bisection to 0.001 mm.
    const double angleTol = 0.1 * kPi / 180.0;
    SECTION("a slot engages the whole front half over the depth") {
      auto stock = cutBlock(voxel, 0.0);
      const EdgeEngagement e =
          measureEngagement(*stock, flat, {0.0, 0.0, -ap}, {1.0, 0.0}, true, 3.0);
      REQUIRE(e.any());
      CHECK(e.entry == Approx(0.0).margin(angleTol));
      CHECK(e.exit == Approx(kPi).margin(angleTol));
      CHECK(engagedHeight(e) == Approx(ap).margin(1e-3));
      CHECK(axialDepth(e) == Approx(ap).margin(1e-3));
      CHECK(radialDepth(e) == Approx(D).epsilon(1e-3));
      for (const EdgeSlice& s : e.slices) {
        CHECK(s.kappa == Approx(kPi / 2).margin(1e-9));  // a cylinder
        CHECK(s.radius == Approx(R));
      }
    }
    SECTION("a 10 % side cut with the stock on the left is up milling under M3") {
      // The block spans y in [-20, 20]; the axis at y = -20 - R + ae overlaps it by ae on the
      // cutter's left (+Y, the feed being +X).
      const double ae = 1.0, yc = -20.0 - R + ae;
      auto stock = cutBlock(voxel, yc);
      const EdgeEngagement e =
          measureEngagement(*stock, flat, {0.0, yc, -ap}, {1.0, 0.0}, true, 3.0);
      REQUIRE(e.any());
      const double phiEx = std::acos(1.0 - 2.0 * ae / D);  // 36.87 deg
      CHECK(e.entry == Approx(0.0).margin(angleTol));
      CHECK(e.exit == Approx(phiEx).margin(angleTol));
      CHECK(engagedHeight(e) == Approx(ap).margin(1e-3));
      CHECK(radialDepth(e) == Approx(ae).epsilon(0.01));
      // The same cut with a counter-clockwise spindle (M4) is down milling.
      const EdgeEngagement m4 =
          measureEngagement(*stock, flat, {0.0, yc, -ap}, {1.0, 0.0}, false, 3.0);
      CHECK(m4.entry == Approx(kPi - phiEx).margin(angleTol));
      CHECK(m4.exit == Approx(kPi).margin(angleTol));
    }
    SECTION("half immersion with the stock on the right is down milling under M3") {
      // The axis on the block's left edge y = 20: the material on the cutter's right.
      auto stock = cutBlock(voxel, 20.0);
      const EdgeEngagement e =
          measureEngagement(*stock, flat, {0.0, 20.0, -ap}, {1.0, 0.0}, true, 3.0);
      REQUIRE(e.any());
      // The entry is where the block's own side face crosses the cut's front.
      CHECK(e.entry == Approx(kPi / 2).margin(angleTol));
      CHECK(e.exit == Approx(kPi).margin(angleTol));
      CHECK(radialDepth(e) == Approx(R).epsilon(0.01));
    }
    SECTION("in air nothing is engaged") {
      auto stock = cutBlock(voxel, 0.0);
      const EdgeEngagement e =
          measureEngagement(*stock, flat, {0.0, 0.0, 10.0}, {1.0, 0.0}, true, 3.0);
      CHECK_FALSE(e.any());
      CHECK(std::isnan(e.entry));
    }
  }
}

TEST_CASE("engagement of a ball end mill: the lead angle and a shallow cut's contact",
          "[physics]") {
  // A 10 mm ball slotting 1 mm deep: the contact reaches up to the depth, and the lead angle
  // of a slice at height z is asin(r(z) / R) with r(z) = sqrt(z (2R - z)) (the sphere's normal).
  const AptCutter ball = AptCutter::ball(D, 20.0);
  const double depth = 1.0;
  Box3 b;
  b.min = {-30, -20, -20};
  b.max = {30, 20, 0};
  DexelStock stock = DexelStock::box(b, 0.1);
  StepPath p;
  p.start = {-40.0, 0.0, -depth};
  p.end = {0.0, 0.0, -depth};
  stock.remove(Sweep(ball, p, 0.1));
  const EdgeEngagement e =
      measureEngagement(stock, ball, {0.0, 0.0, -depth}, {1.0, 0.0}, true, depth);
  REQUIRE(e.any());
  double top = 0.0;
  for (const EdgeSlice& s : e.slices) {
    const double r = std::sqrt(s.z * (2 * R - s.z));
    CHECK(s.radius == Approx(r).epsilon(1e-6));
    // The numerical slope over a quarter slice: within 1e-3 rad of the sphere's normal.
    CHECK(s.kappa == Approx(std::asin(r / R)).margin(1e-3));
    top = std::max(top, s.z + 0.5 * s.dz);
  }
  CHECK(top == Approx(depth).margin(0.05));  // half a 0.1 mm ray spacing, rounded to a slice
}

TEST_CASE("the radial depth and the contact's angles on concave and convex arcs", "[physics]") {
  // tests/support/ContactCases.h: a full circle leaves a cylindrical wall, a three-quarter
  // arc beside it cuts a band of width ae (the closed-form contact there: arcAngles). Three
  // stepovers, both directions of travel, the arcs' centre off the grid.
  const Eigen::Vector3d centre(0.137, -0.261, 0.0);
  for (const char* model : {"dexel", "voxel"})
    for (const double cells : {20.0, 40.0})
      for (const bool concave : {true, false})
        for (const bool clockwise : {true, false})
          for (const double ae : {1.0, 2.5, 5.0}) {
            const double rho = 20.0, h = D / cells;
            CAPTURE(model, cells, concave, clockwise, ae);
            const EdgeEngagement e = test::arcContact(
                model, h, R, ap, rho, concave ? rho - ae : rho + ae, clockwise, centre);
            REQUIRE(e.any());
            // The bounds: the width within 2 %, the angles within 0.5 deg.
            CHECK(radialDepth(e) == Approx(ae).epsilon(0.02));
            const std::array<double, 2> want = test::arcAngles(R, rho, ae, concave, clockwise);
            CHECK(e.entry == Approx(want[0]).margin(0.5 * kPi / 180.0));
            CHECK(e.exit == Approx(want[1]).margin(0.5 * kPi / 180.0));
          }
}

TEST_CASE(
    "a ball end mill's side cut beside its previous pass: the stepover and each slice's "
    "entry",
    "[physics]") {
  // A 10 mm ball 2 mm deep, a pass at stepover s from the previous one (the stock on the
  // cutter's right: down milling under M3), the stock's top and the passes off the grid. At
  // height z above the tip the edge's radius is r(z) and the previous pass's wall lies at
  // s - r(z) across the path (above the cusp, r(z) > s / 2): the slice engages from
  // acos((s - r(z)) / r(z)) to pi, and the radial depth is s. Tolerances (D/20): the width
  // within 1 % (measured 0.9 %: the slice a cell thick nearest the cusp reads a little
  // wider), each slice's entry within 0.5 deg (measured 0.43 deg).
  const double h = 0.5, ap = 2.0;
  const AptCutter ball = AptCutter::ball(D, 20.0);
  for (const char* model : {"dexel", "voxel"})
    for (const double s : {1.0, 2.0}) {
      CAPTURE(model, s);
      Box3 b;
      b.min = {-30, -20, -20};
      b.max = {30, 20, 0.13};
      std::unique_ptr<Stock> st = test::boxStock(model, b, h);
      const double yc = 0.21, z = b.max.z() - ap;
      st->remove(Sweep(ball, test::line({-40, yc + s, z}, {40, yc + s, z}), h));
      const Eigen::Vector3d end(0.0, yc, z);
      st->remove(Sweep(ball, test::line(end - Eigen::Vector3d(40, 0, 0), end), h));
      const EdgeEngagement e = measureEngagement(*st, ball, end, {1.0, 0.0}, true, ap + h);
      REQUIRE(e.any());
      CHECK(radialDepth(e) == Approx(s).epsilon(0.01));
      int checked = 0;
      for (const EdgeSlice& slice : e.slices) {
        if (slice.radius <= s / 2) continue;
        REQUIRE(!slice.arcs.empty());
        CHECK(slice.arcs.front()[0] ==
              Approx(std::acos((s - slice.radius) / slice.radius)).margin(0.5 * kPi / 180));
        CHECK(slice.arcs.back()[1] == Approx(kPi).margin(0.5 * kPi / 180));
        ++checked;
      }
      CHECK(checked >= 3);
    }
}
