// Tests of engine/sim/SteadyCut.h against hand closed forms of a flat end mill's side cut.

#include "engine/sim/SteadyCut.h"

#include "cutters/Error.h"

#include <catch2/catch.hpp>

using namespace engage;

namespace {
// The paper's Fig 8 set-up in mm: D = 1 in, s = 0.5 in, d = 0.3 in, 100 ipm.
constexpr double D = 25.4, r = 12.7, s = 12.7, d = 7.62, F = 2540.0;
}  // namespace

TEST_CASE("steady cut of a flat end mill: straight, concave and convex side cuts", "[sim]") {
  const AptCutter flat = AptCutter::flat(D, 3 * D);
  // Hand closed forms: the removed band is s wide and d deep, its centroid halfway across the
  // band; on an arc of tool-centre radius rho the band's centroid runs at (rho +- (r - s/2)) /
  // rho times the tip feed (concave: the stock outside, band at [rho + r - s, rho + r]).
  // Tolerance 0.5 %: the voxel stock's side-cut error at D/20 is 0.78 % per step worst case
  // (docs/accuracy.md), here D/40 and the mean over about 30 steps.
  SECTION("straight") {
    const SteadyCut c = measureSteadyCut(flat, s, d, {}, F);
    CHECK(c.steps >= 20);
    CHECK(c.mrr == Approx(s * d * F).epsilon(0.005));
  }
  SECTION("concave, rho = 2 D") {
    const double rho = 2 * D;
    const SteadyCut c = measureSteadyCut(flat, s, d, {PathSide::Concave, rho}, F);
    CHECK(c.mrr == Approx(s * d * F * (rho + r - s / 2) / rho).epsilon(0.005));
  }
  SECTION("convex, rho = D") {
    const double rho = D;
    const SteadyCut c = measureSteadyCut(flat, s, d, {PathSide::Convex, rho}, F);
    CHECK(c.mrr == Approx(s * d * F * (rho - r + s / 2) / rho).epsilon(0.005));
  }
}

TEST_CASE("steady cut: a path tighter than the cutter is refused", "[sim]") {
  const AptCutter flat = AptCutter::flat(D, 3 * D);
  CHECK_THROWS_AS(measureSteadyCut(flat, s, d, {PathSide::Concave, 0.25 * D}, F), ParameterError);
  CHECK_THROWS_AS(measureSteadyCut(flat, -1.0, d, {}, F), ParameterError);
}
