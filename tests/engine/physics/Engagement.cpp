// Tests of engine/physics/Engagement.h: the contact measured in a real stock after a straight
// pass, against the closed forms of a flat end mill's immersion (Altintas, ch. 2.4):
// up milling engages phi in [0, acos(1 - 2 ae / D)], down milling [pi - acos(1 - 2 ae / D), pi],
// a slot [0, pi]; the engaged height is the axial depth.

#include "engine/physics/Engagement.h"

#include "cutters/Numbers.h"
#include "cutters/Sweep.h"
#include "stock/DexelStock.h"
#include "tests/stock/StockTestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>

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
    // Tolerances: a boundary is found where the material 0.1 cell outside the surface reads
    // 1/2, which lies 0.1 h / (d gap / d phi) beyond the true one: for ae = 1 mm,
    // d gap / d phi = R^2 sin(phi_ex) / (R - ae) = 3.75 mm/rad -> 0.3 deg; the stock's own
    // boundary is within a few hundredths of a cell (voxel fractions) or up to half a ray
    // spacing (dexel: columns straddling a wall) -> 0.5 deg voxel, 2.5 deg dexel. The engaged
    // height is the depth to half a slice (h / 4) at each end.
    const double angleTol = (voxel ? 0.5 : 2.5) * kPi / 180.0;
    SECTION("a slot engages the whole front half over the depth") {
      auto stock = cutBlock(voxel, 0.0);
      const EdgeEngagement e =
          measureEngagement(*stock, flat, {0.0, 0.0, -ap}, {1.0, 0.0}, true, 3.0);
      REQUIRE(e.any());
      CHECK(e.entry == Approx(0.0).margin(angleTol));
      CHECK(e.exit == Approx(kPi).margin(angleTol));
      CHECK(engagedHeight(e) == Approx(ap).margin(0.5 * h));
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
      CHECK(engagedHeight(e) == Approx(ap).margin(0.5 * h));
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
      // The entry is where the block's own side face crosses the cut's front: within a cell
      // of that corner a voxel's interpolated share is no distance; a cell along the arc,
      // h / R = 2.3 deg (measured 0.94 deg).
      CHECK(e.entry == Approx(kPi / 2).margin(voxel ? h / R : angleTol));
      CHECK(e.exit == Approx(kPi).margin(angleTol));
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
