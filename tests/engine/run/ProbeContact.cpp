// Tests of engine/run/ProbeContact.h: where a probe of a radius first touches a box, against
// contact points worked out by hand.

#include "engine/run/ProbeContact.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;

namespace {

// The search ends within 1e-13 of the move; 1e-9 is far above it and far below a micron.
constexpr double kTol = 1e-9;

Box3 block() {
  Box3 b;
  b.min = {0, 0, -20};
  b.max = {50, 30, -2.3};
  return b;
}

}  // namespace

TEST_CASE("a probe stops on the stock's top, its side or its edge's rounded outline", "[probe]") {
  const Box3 b = block();
  // Down onto the top at (10, 10) from Z20 to Z-10: the tip meets Z-2.3, 22.3 of 30 mm down.
  CHECK(probeContact(b, 3.0, {10, 10, 20}, {10, 10, -10}) == Approx(22.3 / 30.0).margin(kTol));
  // Along +X at Z-5 from X-10 to X60: a 3 mm radius touches the face X0 with its centre at X-3.
  CHECK(probeContact(b, 3.0, {-10, 10, -5}, {60, 10, -5}) == Approx(0.1).margin(kTol));
  // Along Y-2, 2 mm off the face Y0: the rounded outline at the corner (0, 0), where the centre
  // is 3 from it: X = -sqrt(9 - 4).
  CHECK(probeContact(b, 3.0, {-10, -2, -5}, {60, -2, -5}) ==
        Approx((10.0 - std::sqrt(5.0)) / 70.0).margin(kTol));
  // Down beside the block, 4 mm off its side: never within 3 mm.
  CHECK(probeContact(b, 3.0, {-4, 10, 20}, {-4, 10, -30}) > 1.0);
  // Down onto the top's edge from outside: inside the radius from the start, below the top at
  // Z-2.3: 22.3 of 30 mm down as on the top itself.
  CHECK(probeContact(b, 3.0, {-2, 10, 20}, {-2, 10, -10}) == Approx(22.3 / 30.0).margin(kTol));
  // Above the top all the way: nothing.
  CHECK(probeContact(b, 3.0, {-10, 10, 0}, {60, 10, 0}) > 1.0);
  // Starting in contact: at once.
  CHECK(probeContact(b, 3.0, {10, 10, -5}, {10, 10, 10}) == 0.0);
  // A point probe (radius 0) along a diagonal into the side X50 at Z-3: from (60, 40) to
  // (40, 20) it enters at (50, 30), half way.
  CHECK(probeContact(b, 0.0, {60, 40, -3}, {40, 20, -3}) == Approx(0.5).margin(kTol));
}
