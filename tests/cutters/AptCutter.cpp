// Tests of cutters/AptCutter.h: construction, validation, W(z), signed distance, bounds.
// Expected values are hand-computed from the profile geometry written beside each case.

#include "cutters/AptCutter.h"
#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

using Catch::Matchers::Contains;
using engage::AptCutter;
using engage::AptParameters;
using engage::kPi;
using engage::ParameterError;

namespace {
double deg(double d) {
  return d * kPi / 180.0;
}
// Closed-form values below are exact to double round-off; 1e-12 mm is that round-off for
// lengths of order 10 mm (a few ulp after trigonometry).
constexpr double kExact = 1e-12;
/// A general APT cutter: delta 10 deg, r_tc 2, r 5 (e 3), h 20.
AptCutter generalApt() {
  AptParameters p;
  p.radius = 5.0;
  p.cornerRadius = 2.0;
  p.cornerCenterRadial = 3.0;
  p.bottomAngleRad = deg(10.0);
  p.height = 20.0;
  return AptCutter::fromApt(p);
}
}  // namespace

TEST_CASE("named cutters set the APT parameters of paper Fig 3", "[cutters]") {
  const AptCutter flat = AptCutter::flat(10.0, 30.0);
  CHECK(flat.parameters().radius == 5.0);
  CHECK(flat.parameters().cornerRadius == 0.0);
  CHECK(flat.parameters().cornerCenterRadial == 5.0);
  CHECK(flat.parameters().cornerCenterHeight == 0.0);

  const AptCutter ball = AptCutter::ball(10.0, 30.0);
  CHECK(ball.parameters().cornerRadius == 5.0);
  CHECK(ball.parameters().cornerCenterRadial == 0.0);
  CHECK(ball.parameters().cornerCenterHeight == 5.0);

  const AptCutter bull = AptCutter::bull(10.0, 2.0, 30.0, 4);
  CHECK(bull.parameters().cornerCenterRadial == 3.0);
  CHECK(bull.parameters().cornerCenterHeight == 2.0);
  CHECK(bull.fluteCount() == 4);

  // V-bit with a 90 deg included angle: delta = 45 deg, cone top at h_tc = e tan 45 = 5.
  const AptCutter vbit = AptCutter::chamfer(10.0, deg(90.0), 20.0);
  CHECK(vbit.parameters().bottomAngleRad == Approx(deg(45.0)).margin(kExact));
  CHECK(vbit.parameters().cornerCenterHeight == Approx(5.0).margin(kExact));
}

TEST_CASE("silhouette radius W(z) of every named cutter", "[cutters]") {
  SECTION("flat D 10: W = 5 on [0, h], 0 outside") {
    const AptCutter c = AptCutter::flat(10.0, 20.0);
    CHECK(c.radiusAt(0.0) == Approx(5.0).margin(kExact));
    CHECK(c.radiusAt(3.0) == Approx(5.0).margin(kExact));
    CHECK(c.radiusAt(20.0) == Approx(5.0).margin(kExact));
    CHECK(c.radiusAt(20.5) == 0.0);
    CHECK(c.radiusAt(-0.1) == 0.0);
  }
  SECTION("ball D 10: W = sqrt(25 - (z - 5)^2) below the equator, 5 above") {
    const AptCutter c = AptCutter::ball(10.0, 20.0);
    CHECK(c.radiusAt(0.0) == Approx(0.0).margin(kExact));
    CHECK(c.radiusAt(1.0) == Approx(3.0).margin(kExact));  // sqrt(25 - 16)
    CHECK(c.radiusAt(5.0) == Approx(5.0).margin(kExact));
    CHECK(c.radiusAt(8.0) == Approx(5.0).margin(kExact));
  }
  SECTION("bull D 10, r_tc 2: W = 3 + sqrt(4 - (z - 2)^2) on the corner") {
    const AptCutter c = AptCutter::bull(10.0, 2.0, 20.0);
    CHECK(c.radiusAt(0.0) == Approx(3.0).margin(kExact));
    CHECK(c.radiusAt(1.0) == Approx(3.0 + std::sqrt(3.0)).margin(kExact));
    CHECK(c.radiusAt(2.0) == Approx(5.0).margin(kExact));
    CHECK(c.radiusAt(7.0) == Approx(5.0).margin(kExact));
  }
  SECTION("taper tip D 10, beta 30 deg: W = 5 + z tan 30") {
    const AptCutter c = AptCutter::taper(10.0, deg(30.0), 20.0);
    CHECK(c.radiusAt(0.0) == Approx(5.0).margin(kExact));
    CHECK(c.radiusAt(6.0) == Approx(5.0 + 6.0 * std::tan(deg(30.0))).margin(kExact));
    CHECK(c.maxRadius() == Approx(5.0 + 20.0 * std::tan(deg(30.0))).margin(kExact));
  }
  SECTION("tapered ball D 10, beta 30 deg: ball up to the tangent at 30 deg below the equator") {
    // Tangent point: centre (0, 5) + 5 (cos 30, -sin 30) = (4.330127, 2.5).
    const AptCutter c = AptCutter::taperedBall(10.0, deg(30.0), 20.0);
    CHECK(c.radiusAt(1.0) == Approx(3.0).margin(kExact));
    const double tangentRho = 5.0 * std::cos(deg(30.0));
    CHECK(c.radiusAt(2.5) == Approx(tangentRho).margin(kExact));
    CHECK(c.radiusAt(10.0) == Approx(tangentRho + 7.5 * std::tan(deg(30.0))).margin(kExact));
  }
  SECTION("chamfer D 10, 90 deg: cone W = z up to z = 5, cylinder above") {
    const AptCutter c = AptCutter::chamfer(10.0, deg(90.0), 20.0);
    CHECK(c.radiusAt(0.0) == Approx(0.0).margin(kExact));
    CHECK(c.radiusAt(2.0) == Approx(2.0).margin(kExact));
    CHECK(c.radiusAt(7.0) == Approx(5.0).margin(kExact));
  }
  SECTION("general APT: delta 10 deg, r_tc 2, r 5 (e 3)") {
    const AptCutter c = generalApt();
    // h_tc = (r_tc + e sin delta) / cos delta = (2 + 3 sin 10) / cos 10.
    const double htc = (2.0 + 3.0 * std::sin(deg(10.0))) / std::cos(deg(10.0));
    CHECK(c.parameters().cornerCenterHeight == Approx(htc).margin(kExact));
    // On the lower line W = z / tan(delta); the tangent point is at z = h_tc - r_tc cos 10.
    CHECK(c.radiusAt(0.3) == Approx(0.3 / std::tan(deg(10.0))).margin(kExact));
    const double z = htc;  // corner equator
    CHECK(c.radiusAt(z) == Approx(5.0).margin(kExact));
  }
}

TEST_CASE("the widest the cutter reaches within a height of its tip", "[cutters]") {
  // Closed forms of the profiles above: the widest point below z is W(z) where the profile
  // widens upward all the way (every named cutter), the bottom's radius at z <= 0.
  SECTION("flat D 10: 5 at any height") {
    const AptCutter c = AptCutter::flat(10.0, 20.0);
    CHECK(c.maxRadiusBelow(-1.0) == Approx(5.0).margin(kExact));
    CHECK(c.maxRadiusBelow(0.0) == Approx(5.0).margin(kExact));
    CHECK(c.maxRadiusBelow(3.0) == Approx(5.0).margin(kExact));
  }
  SECTION("ball D 10: sqrt(10 z - z^2) below the equator") {
    const AptCutter c = AptCutter::ball(10.0, 20.0);
    CHECK(c.maxRadiusBelow(0.0) == Approx(0.0).margin(kExact));
    CHECK(c.maxRadiusBelow(0.1) == Approx(std::sqrt(1.0 - 0.01)).margin(kExact));
    CHECK(c.maxRadiusBelow(1.0) == Approx(3.0).margin(kExact));
    CHECK(c.maxRadiusBelow(9.0) == Approx(5.0).margin(kExact));
  }
  SECTION("bull D 10, r_tc 2: 3 + sqrt(4 - (z - 2)^2) on the corner") {
    const AptCutter c = AptCutter::bull(10.0, 2.0, 20.0);
    CHECK(c.maxRadiusBelow(0.0) == Approx(3.0).margin(kExact));
    CHECK(c.maxRadiusBelow(0.5) == Approx(3.0 + std::sqrt(4.0 - 2.25)).margin(kExact));
    CHECK(c.maxRadiusBelow(4.0) == Approx(5.0).margin(kExact));
  }
  SECTION("60 deg V-bit D 3.175: z tan 30 up to its full radius") {
    const AptCutter c = AptCutter::chamfer(3.175, deg(60.0), 10.0);
    CHECK(c.maxRadiusBelow(0.07) == Approx(0.07 * std::tan(deg(30.0))).margin(kExact));
    CHECK(c.maxRadiusBelow(5.0) == Approx(1.5875).margin(kExact));
    CHECK(c.maxRadiusBelow(25.0) == Approx(c.maxRadius()).margin(kExact));
  }
  SECTION("taper tip D 2, beta 10 deg: 1 + z tan 10") {
    const AptCutter c = AptCutter::taper(2.0, deg(10.0), 20.0);
    CHECK(c.maxRadiusBelow(0.3) == Approx(1.0 + 0.3 * std::tan(deg(10.0))).margin(kExact));
  }
  SECTION("general APT, delta 10 deg, r_tc 2, e 3: the corner's equator is the widest") {
    const AptCutter c = generalApt();
    CHECK(c.maxRadiusBelow(0.3) == Approx(0.3 / std::tan(deg(10.0))).margin(kExact));
    CHECK(c.maxRadiusBelow(c.parameters().cornerCenterHeight + 1.0) == Approx(5.0).margin(kExact));
  }
}

TEST_CASE("impossible cutters throw with the parameter's name and value", "[cutters]") {
  AptParameters p;
  p.radius = 6.0;
  p.cornerRadius = 7.0;
  p.height = 20.0;
  CHECK_THROWS_WITH(AptCutter::fromApt(p), Contains("r_tc = 7 mm") && Contains("radius r = 6"));

  p.cornerRadius = 2.0;
  p.cornerCenterRadial = 3.0;  // r - r_tc = 4
  CHECK_THROWS_WITH(AptCutter::fromApt(p), Contains("e = 3 mm") && Contains("r - r_tc = 4"));

  p.cornerCenterRadial = 4.0;
  p.cornerCenterHeight = 3.0;  // implied h_tc = 2 for delta = 0
  CHECK_THROWS_WITH(AptCutter::fromApt(p), Contains("h_tc = 3 mm") && Contains("h_tc = 2 mm"));

  CHECK_THROWS_WITH(AptCutter::taper(10.0, deg(90.0), 20.0), Contains("beta = 90 deg"));
  CHECK_THROWS_WITH(AptCutter::taper(10.0, deg(-95.0), 20.0), Contains("beta = -95 deg"));
  CHECK_THROWS_WITH(AptCutter::flat(-1.0, 20.0), Contains("diameter D = -1 mm"));
  CHECK_THROWS_WITH(AptCutter::flat(0.0, 20.0), Contains("diameter D = 0 mm"));
  CHECK_THROWS_WITH(AptCutter::flat(std::numeric_limits<double>::quiet_NaN(), 20.0),
                    Contains("diameter D = nan"));
  CHECK_THROWS_WITH(AptCutter::flat(10.0, 0.0), Contains("cutting height h = 0 mm"));
  CHECK_THROWS_WITH(AptCutter::flat(10.0, 20.0, 0), Contains("flute count = 0"));
  CHECK_THROWS_WITH(AptCutter::bull(10.0, 0.0, 20.0), Contains("r_tc = 0 mm"));
  CHECK_THROWS_WITH(AptCutter::chamfer(10.0, deg(180.0), 20.0), Contains("180 deg"));
  // A V-bit whose flutes stop below the cone top (h_tc = 5 for 90 deg) is not that V-bit.
  CHECK_THROWS_WITH(AptCutter::chamfer(10.0, deg(90.0), 4.0), Contains("h = 4 mm"));

  AptParameters q;
  q.radius = 5.0;
  q.cornerCenterRadial = 5.0;
  q.bottomAngleRad = deg(95.0);
  q.height = 20.0;
  CHECK_THROWS_WITH(AptCutter::fromApt(q), Contains("delta = 95 deg"));
  q.bottomAngleRad = deg(60.0);
  q.taperAngleRad = deg(40.0);
  CHECK_THROWS_WITH(AptCutter::fromApt(q), Contains("beta + delta"));

  // Negative taper D 2: W = 1 - z tan 30 closes at z = 1 / tan 30 = 1.73205 < h = 10.
  CHECK_THROWS_WITH(AptCutter::taper(2.0, deg(-30.0), 10.0), Contains("z = 1.73205 mm"));
}

TEST_CASE("signed distance to the solid of revolution", "[cutters]") {
  SECTION("flat D 10, h 20") {
    const AptCutter c = AptCutter::flat(10.0, 20.0);
    CHECK(c.signedDistance({0.0, 0.0, 10.0}) == Approx(-5.0).margin(kExact));  // to the side
    CHECK(c.signedDistance({0.0, 0.0, 1.0}) == Approx(-1.0).margin(kExact));   // to the bottom
    CHECK(c.signedDistance({8.0, 0.0, 5.0}) == Approx(3.0).margin(kExact));
    CHECK(c.signedDistance({0.0, 0.0, -2.0}) == Approx(2.0).margin(kExact));
    CHECK(c.signedDistance({0.0, 8.0, -3.0}) == Approx(std::sqrt(18.0)).margin(kExact));
    CHECK(c.signedDistance({6.0, 8.0, 10.0}) == Approx(5.0).margin(kExact));  // rho = 10
    CHECK(c.signedDistance({3.0, 4.0, 25.0}) == Approx(5.0).margin(kExact));  // above the cap
  }
  SECTION("ball D 10") {
    const AptCutter c = AptCutter::ball(10.0, 20.0);
    CHECK(c.signedDistance({0.0, 0.0, 5.0}) == Approx(-5.0).margin(kExact));
    CHECK(c.signedDistance({3.0, 0.0, 1.0}) == Approx(0.0).margin(kExact));  // on the sphere
    CHECK(c.signedDistance({0.0, 0.0, -1.0}) == Approx(1.0).margin(kExact));
    CHECK(c.signedDistance({0.0, 6.0, 5.0}) == Approx(1.0).margin(kExact));
    // Below the centre, outside: distance to the sphere |p - (0,0,5)| - 5.
    CHECK(c.signedDistance({4.0, 4.0, 0.0}) ==
          Approx(std::sqrt(16.0 + 16.0 + 25.0) - 5.0).margin(kExact));
  }
  SECTION("points on the silhouette are at distance 0, inside negative, outside positive") {
    for (const AptCutter& c :
         {AptCutter::bull(10.0, 2.0, 20.0), AptCutter::taper(6.0, deg(15.0), 20.0),
          AptCutter::taperedBall(6.0, deg(10.0), 20.0),
          AptCutter::chamfer(10.0, deg(60.0), 20.0)}) {
      for (double z = 0.25; z < 19.9; z += 0.5) {
        const double w = c.radiusAt(z);
        CHECK(c.profileSignedDistance(w, z) == Approx(0.0).margin(1e-9));
        CHECK(c.profileSignedDistance(0.9 * w, z) < 0.0);
        CHECK(c.profileSignedDistance(1.1 * w + 1e-3, z) > 0.0);
      }
    }
  }
  SECTION("taper: distance off the side is measured along its normal") {
    // Taper tip D 10, beta 30: side line rho = 5 + z tan 30. The point at distance 2 along the
    // outward normal (cos 30, -sin 30) from the side point at z = 10.
    const AptCutter c = AptCutter::taper(10.0, deg(30.0), 20.0);
    const double rho = 5.0 + 10.0 * std::tan(deg(30.0)) + 2.0 * std::cos(deg(30.0));
    const double z = 10.0 - 2.0 * std::sin(deg(30.0));
    CHECK(c.profileSignedDistance(rho, z) == Approx(2.0).margin(kExact));
  }
}

TEST_CASE("signed distance agrees with a brute-force distance to the sampled profile",
          "[cutters]") {
  // Independent check: the profile boundary sampled every 1e-4 mm (W(z) up the side, the
  // flat bottom, the top cap), the minimum distance to the samples, the sign from W(z).
  // Tolerance 1e-4 mm: the sampling step bounds the brute force's error.
  for (const AptCutter& c :
       {AptCutter::flat(6.0, 12.0), AptCutter::ball(6.0, 12.0), AptCutter::bull(6.0, 1.5, 12.0),
        AptCutter::taper(6.0, deg(10.0), 12.0), AptCutter::chamfer(6.0, deg(90.0), 12.0)}) {
    std::vector<Eigen::Vector2d> boundary;
    for (double z = 0.0; z <= 12.0; z += 1e-4)
      boundary.emplace_back(c.radiusAt(z), z);
    for (double r = 0.0; r <= c.radiusAt(0.0); r += 1e-4)
      boundary.emplace_back(r, 0.0);
    for (double r = 0.0; r <= c.radiusAt(12.0); r += 1e-4)
      boundary.emplace_back(r, 12.0);
    unsigned seed = 12345;
    auto next = [&seed]() {
      seed = seed * 1103515245u + 12345u;
      return static_cast<double>((seed >> 8) & 0xFFFF) / 65535.0;
    };
    for (int k = 0; k < 40; ++k) {
      const double rho = 5.0 * next();
      const double z = -1.0 + 14.0 * next();
      double best = 1e300;
      for (const Eigen::Vector2d& b : boundary)
        best = std::min(best, (b - Eigen::Vector2d(rho, z)).norm());
      const bool inside = z >= 0.0 && z <= 12.0 && rho <= c.radiusAt(z);
      INFO(shapeName(c.shape()) << " at rho " << rho << ", z " << z);
      CHECK(c.profileSignedDistance(rho, z) == Approx(inside ? -best : best).margin(1e-4));
    }
  }
}

TEST_CASE("bounding box in the tool frame", "[cutters]") {
  const AptCutter c = AptCutter::taper(10.0, deg(30.0), 20.0);
  const double w = 5.0 + 20.0 * std::tan(deg(30.0));
  CHECK(c.bounds().min.x() == Approx(-w).margin(kExact));
  CHECK(c.bounds().max.y() == Approx(w).margin(kExact));
  CHECK(c.bounds().min.z() == 0.0);
  CHECK(c.bounds().max.z() == 20.0);
  // Negative taper: the widest point is the corner equator, r = 5.
  const AptCutter narrowing = AptCutter::taper(10.0, deg(-10.0), 20.0);
  CHECK(narrowing.maxRadius() == Approx(5.0).margin(kExact));
}
