// Tests of engine/model/EngagementModel.h: Eq 6, 12-24 against hand values.
// Inch cases run with inch numbers in the mm slots (the model is linear in scale), except
// where units matter (force, acceleration), which use real mm.

#include "engine/model/EngagementModel.h"
#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;
using Catch::Matchers::Contains;

namespace {
constexpr double kRel = 1e-12;  // closed forms on both sides: only round-off differs
}  // namespace

TEST_CASE("linear MRR is area times feed (Eq 6)", "[model]") {
  const EngagementModel m(AptCutter::flat(1.0, 3.0), 0.5, 0.3);
  CHECK(m.mrr(100.0, {}) == Approx(15.0).epsilon(kRel));
  CHECK(m.mrrPaper(100.0, {}) == Approx(15.0).epsilon(kRel));
}

TEST_CASE("flat D 1 on a circle of tool-centre radius 1: exact and paper forms", "[model]") {
  // Area 0.15, centroid x = 0.25, z = 0.15.
  const EngagementModel m(AptCutter::flat(1.0, 3.0), 0.5, 0.3);
  const PathShape concave{PathSide::Concave, 1.0};
  const PathShape convex{PathSide::Convex, 1.0};
  // Exact (Pappus): 0.15 x 100 x (1 +- 0.25) / 1.
  CHECK(m.mrr(100.0, concave) == Approx(18.75).epsilon(kRel));
  CHECK(m.mrr(100.0, convex) == Approx(11.25).epsilon(kRel));
  // Paper: R = 1.5 (concave) / 0.5 (convex), m = sqrt(0.25^2 + 0.15^2) = 0.2915476.
  const double mm = std::sqrt(0.0625 + 0.0225);
  CHECK(m.paperCentroidDistance() == Approx(mm).epsilon(kRel));
  CHECK(m.mrrPaper(100.0, concave) == Approx(15.0 * (1.5 - mm) / (1.5 - 0.5)).epsilon(kRel));
  CHECK(m.mrrPaper(100.0, convex) == Approx(15.0 * (0.5 + mm) / (0.5 + 0.5)).epsilon(kRel));
}

TEST_CASE("Eq 6 with a cutter whose exact and paper areas differ: a 90 deg V-bit", "[model]") {
  // D 10, s 4, d 3: the cone's half width at height z is z (45 deg), the removed width
  // min(2z, s): area = int_0^2 2z dz + int_2^3 4 dz = 4 + 4 = 8 mm^2 (exact); Eq 3 says
  // s d = 12 mm^2. At 100 mm/min: 800 and 1200 mm^3/min.
  const EngagementModel m(AptCutter::chamfer(10.0, kPi / 2, 5.0), 4.0, 3.0);
  CHECK(m.mrr(100.0, {}) == Approx(800.0).epsilon(1e-9));
  CHECK(m.mrrPaper(100.0, {}) == Approx(1200.0).epsilon(kRel));
}

TEST_CASE("the paper's Eq 12/13 ratios by hand, and where they differ from the exact", "[model]") {
  // Flat D 1, s 0.5, d 0.3: centroid x = r - s/2 = 0.25 from the axis, 0.15 up; the paper's
  // m from the contact point (r, 0): sqrt(0.25^2 + 0.15^2) = 0.2915476.
  const EngagementModel m(AptCutter::flat(1.0, 3.0), 0.5, 0.3);
  const double mm = std::sqrt(0.25 * 0.25 + 0.15 * 0.15);
  // Concave, tool-centre radius 1: R = 1.5, Eq 12: (R - m) / (R - r) = 1.2084524.
  CHECK(m.centroidSpeedRatioPaper({PathSide::Concave, 1.0}) ==
        Approx((1.5 - mm) / (1.5 - 0.5)).epsilon(kRel));
  // Convex: R = 0.5, Eq 13: (R + m) / (R + r) = 0.7915476.
  CHECK(m.centroidSpeedRatioPaper({PathSide::Convex, 1.0}) ==
        Approx((0.5 + mm) / (0.5 + 0.5)).epsilon(kRel));
  // The exact (Pappus) ratios (rho +- x) / rho: 1.25 and 0.75, not the paper's.
  CHECK(m.centroidSpeedRatio({PathSide::Concave, 1.0}) == Approx(1.25).epsilon(kRel));
  CHECK(m.centroidSpeedRatio({PathSide::Convex, 1.0}) == Approx(0.75).epsilon(kRel));
}

TEST_CASE("with a horizontal m the paper's Eq 12/13 equal the exact ratio", "[model]") {
  // A cross-section whose centroid lies at the tip height would make the paper exact; check
  // the algebra instead: (R - (r - x)) / (R - r) with R = rho + r is (rho + x) / rho.
  const EngagementModel m(AptCutter::ball(1.0, 3.0), 0.5, 0.3);
  const double rho = 2.0;
  const double x = m.exact().centroidX;
  const double R = m.paperPathRadius({PathSide::Concave, rho});
  CHECK(R == Approx(2.5).epsilon(kRel));
  CHECK((R - (0.5 - x)) / (R - 0.5) ==
        Approx(m.centroidSpeedRatio({PathSide::Concave, rho})).epsilon(kRel));
}

TEST_CASE("curved MRR for R/D from 1 to 50: concave > linear > convex, converging", "[model]") {
  for (const AptCutter& c : {AptCutter::flat(1.0, 3.0), AptCutter::bull(1.0, 0.2, 3.0),
                             AptCutter::ball(1.0, 3.0), AptCutter::taper(1.0, 0.5235987756, 3.0)}) {
    const EngagementModel m(c, 0.5, 0.3);
    const double linear = m.mrr(100.0, {});
    double previousGap = 1e300;
    for (double q : {1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0}) {
      const double concave = m.mrr(100.0, {PathSide::Concave, q});
      const double convex = m.mrr(100.0, {PathSide::Convex, q});
      CHECK(concave > linear);
      CHECK(linear > convex);
      // The gap is exactly x_bar / rho of the linear MRR: it shrinks as 1/R.
      const double gap = concave / linear - 1.0;
      CHECK(gap == Approx(m.exact().centroidX / q).epsilon(1e-10));
      CHECK(gap < previousGap);
      previousGap = gap;
      const double concavePaper = m.mrrPaper(100.0, {PathSide::Concave, q});
      const double convexPaper = m.mrrPaper(100.0, {PathSide::Convex, q});
      CHECK(concavePaper > m.mrrPaper(100.0, {}));
      CHECK(convexPaper < m.mrrPaper(100.0, {}));
    }
    // At R/D = 50 within 1 % of linear (gap = x_bar / 50 <= 0.5 / 50).
    CHECK(m.mrr(100.0, {PathSide::Concave, 50.0}) == Approx(linear).epsilon(0.01));
  }
}

TEST_CASE("adaptive feed holds the target MRR (Eq 21-23)", "[model]") {
  const EngagementModel m(AptCutter::bull(1.0, 0.25, 3.0), 0.6, 0.3);
  for (const PathShape& path :
       {PathShape{}, PathShape{PathSide::Concave, 1.5}, PathShape{PathSide::Convex, 1.5}}) {
    CHECK(m.mrr(m.adaptiveFeed(12.0, path), path) == Approx(12.0).epsilon(kRel));
    CHECK(m.mrrPaper(m.adaptiveFeedPaper(12.0, path), path) == Approx(12.0).epsilon(kRel));
  }
  // Concave: slower than linear; convex: faster.
  CHECK(m.adaptiveFeed(12.0, {PathSide::Concave, 1.5}) < m.adaptiveFeed(12.0, {}));
  CHECK(m.adaptiveFeed(12.0, {PathSide::Convex, 1.5}) > m.adaptiveFeed(12.0, {}));
}

TEST_CASE("arcs tighter than the cutter have no steady state", "[model]") {
  const EngagementModel m(AptCutter::flat(10.0, 30.0), 5.0, 3.0);
  CHECK_THROWS_WITH(m.mrr(1000.0, {PathSide::Concave, 4.0}), Contains("path radius = 4 mm"));
  CHECK_THROWS_WITH(m.mrr(1000.0, {PathSide::Convex, -1.0}), Contains("must be positive"));
  CHECK_NOTHROW(m.mrr(1000.0, {PathSide::Convex, 5.0}));
}

TEST_CASE("force from specific energy and spindle speed (Eq 17-18)", "[model]") {
  // 1 in^3/min = 16387.064 mm^3/min = 273.1177 W at E = 1 J/mm^3; D 25.4 mm at 1000 rpm:
  // v = pi 25.4 1000 mm/min = 1.3299409 m/s; F = P / v = 205.3608 N.
  const double v = cuttingSpeed(25.4, 1000.0);
  CHECK(v == Approx(kPi * 25400.0).epsilon(kRel));
  const double watts = 16387.064 / 60.0;
  CHECK(tangentialForce(16387.064, 1.0, v) == Approx(watts / (v / 60000.0)).epsilon(kRel));
  CHECK(tangentialForce(16387.064, 1.0, v) == Approx(205.3608).epsilon(1e-6));
  CHECK_THROWS_AS(tangentialForce(1.0, 1.0, 0.0), ParameterError);
}

TEST_CASE("tangential acceleration between successive feeds (Eq 24)", "[model]") {
  // 60 -> 120 mm/min (1 -> 2 mm/s) over 1.5 mm: a = (4 - 1) / 3 = 1 mm/s^2, dt = 3 / 3 = 1 s.
  CHECK(tangentialAcceleration(60.0, 120.0, 1.5) == Approx(1.0).epsilon(kRel));
  CHECK(transitionTime(60.0, 120.0, 1.5) == Approx(1.0).epsilon(kRel));
  CHECK(tangentialAcceleration(120.0, 60.0, 1.5) == Approx(-1.0).epsilon(kRel));
  CHECK_THROWS_AS(tangentialAcceleration(60.0, 120.0, 0.0), ParameterError);
}
