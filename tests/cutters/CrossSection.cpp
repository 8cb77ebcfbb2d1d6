// Tests of cutters/CrossSection.h against hand-worked closed forms (written beside each case).
// The geometry is scale-free, so the paper's inch cases are run with the inch numbers as mm.
// Tolerance: the library integrates in closed form, so results agree with the hand formulas to
// round-off; 1e-10 (relative) leaves room for asin/acos near +-1.

#include "cutters/CrossSection.h"
#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <catch2/catch.hpp>

#include <cmath>

using Catch::Matchers::Contains;
using engage::AptCutter;
using engage::exactCrossSection;
using engage::kPi;
using engage::paperCrossSection;

namespace {
constexpr double kRel = 1e-10;
double deg(double d) {
  return d * kPi / 180.0;
}
// Antiderivative of sqrt(R^2 - t^2).
double F(double R, double t) {
  return (t * std::sqrt(R * R - t * t) + R * R * std::asin(t / R)) / 2.0;
}
}  // namespace

TEST_CASE("flat endmill: y_f = s d (Eq 4), centroid at r - s/2 and d/2", "[cutters]") {
  const AptCutter c = AptCutter::flat(1.0, 3.0);
  const auto x = exactCrossSection(c, 0.5, 0.3);
  CHECK(x.area == Approx(0.15).epsilon(kRel));
  CHECK(x.centroidX == Approx(0.25).epsilon(kRel));
  CHECK(x.centroidZ == Approx(0.15).epsilon(kRel));
  CHECK(x.cuspHeight == 0.0);
  const auto p = paperCrossSection(c, 0.5, 0.3);
  CHECK(p.applies);
  CHECK(p.area == Approx(0.15).epsilon(kRel));
}

TEST_CASE("ball D 1, s 0.5, d 0.3: 0.139153 (Eq 5 and exact agree)", "[cutters]") {
  const AptCutter c = AptCutter::ball(1.0, 3.0);
  const auto x = exactCrossSection(c, 0.5, 0.3);
  const auto p = paperCrossSection(c, 0.5, 0.3);
  // Eq 5 by hand: phi = acos(0.5) = 60 deg,
  // y_b = (0.25 (pi - 2 pi/3) + 2 0.25 sin60 cos60 + 2 0.5 (0.3 - 0.5)) / 2 = 0.1391527.
  CHECK(p.applies);
  CHECK(p.area == Approx(0.139153).epsilon(1e-6));  // the six-digit figure
  CHECK(x.area == Approx(p.area).epsilon(kRel));
  // Centroid by hand. Cusp height z* = 0.5 - sqrt(0.25 - 0.0625) = 0.0669873; above it the
  // strip [W - s, W] has centre W - s/2, so M_x = s (int W dz) - s^2/2 (d - z*), with
  // int_{z*}^{d} W dz = F(-0.2) - F(-0.4330127) for t = z - 0.5.
  const double zs = 0.5 - std::sqrt(0.1875);
  CHECK(x.cuspHeight == Approx(zs).epsilon(kRel));
  const double intW = F(0.5, 0.3 - 0.5) - F(0.5, zs - 0.5);
  const double mx = 0.5 * intW - 0.125 * (0.3 - zs);
  CHECK(x.centroidX == Approx(mx / x.area).epsilon(kRel));
  // M_z: below z*, int 2W z dz with W = sqrt(0.25 - t^2): 2 [-(R^2-t^2)^1.5/3 + 0.5 F(t)];
  // above, s (d^2 - z*^2) / 2.
  auto G = [](double t) { return -std::pow(0.25 - t * t, 1.5) / 3.0; };
  const double mzLow = 2.0 * (G(zs - 0.5) - G(-0.5) + 0.5 * (F(0.5, zs - 0.5) - F(0.5, -0.5)));
  const double mz = mzLow + 0.5 * (0.09 - zs * zs) / 2.0;
  CHECK(x.centroidZ == Approx(mz / x.area).epsilon(kRel));
}

TEST_CASE("depth below the cusp height: Eq 5 subtracts cusp material that is not there",
          "[cutters]") {
  // Ball D 1, s 0.5, d 0.05 < z* = 0.0669873: nothing overlaps, the width is 2W everywhere.
  // Exact: 2 int_0^0.05 sqrt(0.25 - (z - 0.5)^2) dz = 2 (F(-0.45) - F(-0.5)) = 0.0146815.
  // Eq 5: (0.2617994 + 0.2165064 + 2 0.5 (0.05 - 0.5)) / 2 = 0.0141529 (3.6 % low).
  const AptCutter c = AptCutter::ball(1.0, 3.0);
  const auto x = exactCrossSection(c, 0.5, 0.05);
  const auto p = paperCrossSection(c, 0.5, 0.05);
  CHECK(x.area == Approx(2.0 * (F(0.5, -0.45) - F(0.5, -0.5))).epsilon(kRel));
  CHECK(x.area == Approx(0.0146815).epsilon(1e-5));
  CHECK(x.centroidX == Approx(0.0).margin(1e-15));
  CHECK(x.cuspHeight == Approx(0.05).epsilon(kRel));
  CHECK_FALSE(p.applies);
  CHECK_THAT(p.reason, Contains("cusp height"));
  CHECK(p.area == Approx(0.0141529).epsilon(1e-5));
}

TEST_CASE("stepover wider than the cutter: the full width 2W, Eq 2 undefined", "[cutters]") {
  // Flat D 10, s 15, d 2: a slot 10 x 2 = 20, centred on the axis.
  const AptCutter c = AptCutter::flat(10.0, 30.0);
  const auto x = exactCrossSection(c, 15.0, 2.0);
  CHECK(x.area == Approx(20.0).epsilon(kRel));
  CHECK(x.centroidX == Approx(0.0).margin(1e-15));
  CHECK(x.centroidZ == Approx(1.0).epsilon(kRel));
  const auto p = paperCrossSection(c, 15.0, 2.0);
  CHECK_FALSE(p.applies);
  CHECK(std::isnan(p.area));
  CHECK_THAT(p.reason, Contains("exceeds the diameter"));
}

TEST_CASE("conical bottom (90 deg V-bit): Eq 3 says s d, the exact area is smaller", "[cutters]") {
  // D 10, delta 45: W(z) = z up to z = 5. s = 4, d = 3. 2W = s at z = 2.
  // Area = int_0^2 2z dz + 4 (3 - 2) = 4 + 4 = 8 (Eq 3 would give s d = 12).
  // M_x = int_2^3 4 (z - 2) dz = 2 -> x = 0.25.  M_z = int_0^2 2 z^2 dz + int_2^3 4 z dz
  // = 16/3 + 10 -> z = (46/3) / 8 = 1.9166667.
  const AptCutter c = AptCutter::chamfer(10.0, deg(90.0), 20.0);
  const auto x = exactCrossSection(c, 4.0, 3.0);
  CHECK(x.area == Approx(8.0).epsilon(kRel));
  CHECK(x.centroidX == Approx(0.25).epsilon(kRel));
  CHECK(x.centroidZ == Approx(46.0 / 3.0 / 8.0).epsilon(kRel));
  CHECK(x.cuspHeight == Approx(2.0).epsilon(kRel));
  const auto p = paperCrossSection(c, 4.0, 3.0);
  CHECK_FALSE(p.applies);
  CHECK(p.area == Approx(12.0).epsilon(kRel));
  CHECK_THAT(p.reason, Contains("conical bottom"));
}

TEST_CASE("bull endmills: Eq 3 when s <= 2e, Eq 2 when the stepover meets the corner",
          "[cutters]") {
  SECTION("D 1, r_tc 0.125 (e 0.375), s 0.5 <= 2e: y = s d = 0.15") {
    const AptCutter c = AptCutter::bull(1.0, 0.125, 3.0);
    const auto x = exactCrossSection(c, 0.5, 0.3);
    const auto p = paperCrossSection(c, 0.5, 0.3);
    CHECK(p.applies);
    CHECK(x.area == Approx(0.15).epsilon(kRel));
    CHECK(p.area == Approx(0.15).epsilon(kRel));
  }
  SECTION("D 1, r_tc 0.25 (e 0.25), s 0.6 > 2e: Eq 2 by hand = 0.1798323") {
    // cos phi = (0.6 - 0.5) / 0.5 = 0.2, sin phi = sqrt(0.96);
    // y = (0.0625 (pi - 2 phi) + 2 0.0625 sin cos + 4 0.25 0.25 + 2 0.6 (0.3 - 0.25)) / 2.
    const double phi = std::acos(0.2);
    const double hand =
        (0.0625 * (kPi - 2.0 * phi) + 2.0 * 0.0625 * std::sqrt(0.96) * 0.2 + 0.25 + 1.2 * 0.05) /
        2.0;
    CHECK(hand == Approx(0.1798323).epsilon(1e-6));
    const AptCutter c = AptCutter::bull(1.0, 0.25, 3.0);
    const auto x = exactCrossSection(c, 0.6, 0.3);
    const auto p = paperCrossSection(c, 0.6, 0.3);
    CHECK(p.applies);
    CHECK(p.area == Approx(hand).epsilon(kRel));
    CHECK(x.area == Approx(hand).epsilon(kRel));
    // Cusp height r_tc (1 - sin phi).
    CHECK(x.cuspHeight == Approx(0.25 * (1.0 - std::sqrt(0.96))).epsilon(kRel));
  }
}

TEST_CASE("taper endmills: constant width s, the centroid moves out with the taper", "[cutters]") {
  SECTION("tip r 0.5, beta 30 deg, s 0.5, d 0.5: area s d, x = 0.25 + tan30 d / 2") {
    // Removed strip at height z: [W - s, W], centre W - s/2 = 0.25 + z tan30.
    const AptCutter c = AptCutter::taper(1.0, deg(30.0), 3.0);
    const auto x = exactCrossSection(c, 0.5, 0.5);
    CHECK(x.area == Approx(0.25).epsilon(kRel));
    CHECK(x.centroidX == Approx(0.25 + std::tan(deg(30.0)) * 0.25).epsilon(kRel));
    CHECK(x.centroidZ == Approx(0.25).epsilon(kRel));
    CHECK(paperCrossSection(c, 0.5, 0.5).applies);
  }
  SECTION("tip r 0.25, beta 30 deg, s 0.8 > 2r: width 2W until 2W = s at z* = 0.3 / (2 tan30)") {
    // Area = int_0^z* (0.5 + 2 z tan30) dz + 0.8 (0.5 - z*).
    const double t = std::tan(deg(30.0));
    const double zs = 0.3 / (2.0 * t);
    const double hand = 0.5 * zs + t * zs * zs + 0.8 * (0.5 - zs);
    CHECK(hand == Approx(0.361029).epsilon(1e-5));
    const AptCutter c = AptCutter::taper(0.5, deg(30.0), 3.0);
    const auto x = exactCrossSection(c, 0.8, 0.5);
    CHECK(x.area == Approx(hand).epsilon(kRel));
    CHECK(x.cuspHeight == Approx(zs).epsilon(kRel));
    const auto p = paperCrossSection(c, 0.8, 0.5);
    CHECK_FALSE(p.applies);
    CHECK(std::isnan(p.area));
  }
  SECTION("tapered ball D 1, beta 10 deg, s 0.9: the stepover meets the side, not the arc") {
    // Tangent point at 10 deg below the equator: rho = 0.5 cos10 = 0.4924 > s/2 = 0.45, so
    // the crossing is on the arc, at phi = acos(0.9) = 25.8 deg >= beta.
    const AptCutter c = AptCutter::taperedBall(1.0, deg(10.0), 3.0);
    const auto p = paperCrossSection(c, 0.9, 0.4);
    CHECK(p.applies);
    CHECK(exactCrossSection(c, 0.9, 0.4).area == Approx(p.area).epsilon(kRel));
    // s = 0.99: phi = acos(0.99) = 8.1 deg < beta = 10 deg: the crossing is on the side line.
    const auto q = paperCrossSection(c, 0.99, 0.4);
    CHECK_FALSE(q.applies);
    CHECK_THAT(q.reason, Contains("taper side"));
  }
}

TEST_CASE("cross-section arguments are checked", "[cutters]") {
  const AptCutter c = AptCutter::flat(10.0, 20.0);
  CHECK_THROWS_WITH(exactCrossSection(c, 0.0, 1.0), Contains("stepover s = 0 mm"));
  CHECK_THROWS_WITH(exactCrossSection(c, 1.0, -1.0), Contains("depth of cut d = -1 mm"));
  CHECK_THROWS_WITH(paperCrossSection(c, 1.0, 25.0), Contains("exceeds the cutting height"));
}
