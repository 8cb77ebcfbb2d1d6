// Tests of stock/DexelMesh.h: a dexel stock's surface straight from its rays, closed, within
// its triangle budget, enclosing the stock's volume (closed forms below).

#include "stock/DexelMesh.h"

#include "stock/DexelStock.h"
#include "tests/stock/StockTestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace engage;
using namespace engage::test;

namespace {

/// Columns of 0.5 mm over [0, 10] x [0, 8] (20 x 16 rays, every column whole), material from
/// z = -3 up to height(x, y) of the column's centre.
template <typename Height>
DexelStock columns(Height&& height) {
  constexpr double h = 0.5;
  std::vector<std::vector<DexelStock::Interval>> rays;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 20; ++i)
      rays.push_back({{-3.0, height((i + 0.5) * h, (j + 0.5) * h), 1.0}});
  return DexelStock::fromColumns(0.0, 0.0, h, 20, 16, std::move(rays));
}

}  // namespace

TEST_CASE("dexel mesh: an uncut box is its box, closed, in a few triangles", "[stock]") {
  // Faces off the rays' grid: the far columns hold their share of the box, and the mesh's far
  // walls stand on the box's faces.
  Box3 b;
  b.min = {0.03, -1.07, -3.33};
  b.max = {10.11, 5.5, 0.0};
  const DexelStock s = DexelStock::box(b, 0.25);
  double cell = 0.0;
  const auto m = heightfieldMesh(s, 2000, &cell);
  REQUIRE(m);
  CHECK(cell == 0.25);
  CHECK(boundaryEdgeCount(*m) == 0);
  // The box's volume to the float rounding of its corners (1e-7 relative each).
  CHECK(meshVolume(*m) == Approx(10.08 * 6.57 * 3.33).epsilon(1e-5));
  // The flat top merges into a few blocks; walls and floor follow the rim's used vertices.
  CHECK(m->triangles.size() < 200);
  float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
  for (const auto& p : m->points)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[static_cast<std::size_t>(a)]);
      hi[a] = std::max(hi[a], p[static_cast<std::size_t>(a)]);
    }
  CHECK(lo[0] == Approx(0.03));
  CHECK(hi[0] == Approx(10.11));
  CHECK(lo[1] == Approx(-1.07));
  CHECK(hi[1] == Approx(5.5));
  CHECK(lo[2] == Approx(-3.33));
  CHECK(hi[2] == Approx(0.0).margin(1e-6));
}

TEST_CASE("dexel mesh: a pocket's volume to its four corners' interpolation", "[stock]") {
  // A pocket 1 mm deep over x in [2, 6], y in [2, 5]: its walls on the columns' edges, halfway
  // between two rays, where the straight line between the rays' heights leaves the column's
  // volume exact. At each of the pocket's 4 corners a quad of 0.25 mm^2 holds three rays at
  // one height and one at the other: either diagonal puts (3 a + b) / 4 x 0.25 off by
  // |a - b| x 0.25 / 12, 1/48 mm^3.
  const DexelStock s = columns(
      [](double x, double y) { return x > 2.0 && x < 6.0 && y > 2.0 && y < 5.0 ? -1.0 : 0.0; });
  const double exact = 10.0 * 8.0 * 3.0 - 4.0 * 3.0 * 1.0;
  CHECK(s.volume() == Approx(exact).epsilon(1e-12));
  for (std::size_t budget : {std::size_t{0}, std::size_t{2000}}) {
    INFO("budget " << budget);
    const auto m = heightfieldMesh(s, budget);
    REQUIRE(m);
    CHECK(boundaryEdgeCount(*m) == 0);
    CHECK(std::abs(meshVolume(*m) - exact) <= 4.0 / 48.0 + 1e-4);
    // Every ray a vertex of the top (20 x 16), the floor's blocks and the pocket's merged.
    CHECK(m->triangles.size() < 2 * 19 * 15);
  }
}

TEST_CASE("dexel mesh: within its budget, coarser where it must be", "[stock]") {
  // Heights at random: nothing merges at full resolution (2 x 19 x 15 top triangles, 3 x 68
  // for the walls and floor), so a budget of 300 takes every second ray (10 x 8 + the last).
  std::mt19937 random(7);
  std::uniform_real_distribution<double> z(-1.0, 0.0);
  const DexelStock s = columns([&](double, double) { return z(random); });
  double cell = 0.0;
  const auto full = heightfieldMesh(s, 0, &cell);
  REQUIRE(full);
  CHECK(cell == 0.5);
  CHECK(full->triangles.size() == 2u * 19u * 15u + 3u * 68u);
  CHECK(std::abs(meshVolume(*full) - s.volume()) < 0.05 * s.volume());
  const auto coarse = heightfieldMesh(s, 300, &cell);
  REQUIRE(coarse);
  CHECK(cell == 1.0);
  CHECK(coarse->triangles.size() <= 300);
  CHECK(boundaryEdgeCount(*coarse) == 0);
  CHECK(meshVolume(*coarse) > 0.0);
  // Several budgets at once (stock.stl's and the report's from one reading of the rays): each
  // the mesh and spacing that budget alone gives, whatever their order.
  std::vector<double> cells;
  const auto both = heightfieldMeshes(s, {300, 0, 100000, 30}, &cells);
  REQUIRE(both);
  REQUIRE(both->size() == 4u);
  const std::size_t budgets[4] = {300, 0, 100000, 30};
  for (std::size_t n = 0; n < 4; ++n) {
    double alone = 0.0;
    const auto one = heightfieldMesh(s, budgets[n], &alone);
    REQUIRE(one);
    INFO("budget " << budgets[n]);
    CHECK(cells[n] == alone);
    CHECK((*both)[n].triangles == one->triangles);
    CHECK((*both)[n].points == one->points);
  }
  CHECK(cells[1] == 0.5);
  CHECK(cells[0] == 1.0);
}

TEST_CASE("dexel mesh: a slot cut at 30 deg encloses the stock's volume", "[stock]") {
  // A 4 mm flat end mill 1.5 mm deep across a 40 x 30 x 5 mm box at 0.2 mm: the walls cross
  // the columns at 30 deg to the grid, each crossed column's height its share of the slot.
  // Between two rays the top is straight where the wall's profile is a step: per mm of wall,
  // an error of at most depth x h / 8 (the largest gap between a step and the line through
  // the mean heights of its two columns), 2 walls x 46 mm x 1.5 x 0.2 / 8 = 3.5 mm^3.
  Box3 b;
  b.min = {0.0, 0.0, -5.0};
  b.max = {40.0, 30.0, 0.0};
  DexelStock s = DexelStock::box(b, 0.2);
  const Eigen::Vector3d a(0.0, 5.0, -1.5);
  s.remove(Sweep(AptCutter::flat(4.0, 12.0), line(a - 5.0 * kDir, a + 46.0 * kDir), 0.2));
  const auto m = heightfieldMesh(s, 0);
  REQUIRE(m);
  CHECK(boundaryEdgeCount(*m) == 0);
  INFO("mesh " << meshVolume(*m) << " stock " << s.volume());
  CHECK(std::abs(meshVolume(*m) - s.volume()) <= 3.5);
}

TEST_CASE("dexel mesh: not a heightfield, no mesh", "[stock]") {
  // Material over air (an undercut) and a column cut through: the voxels mesh those.
  const DexelStock over = [] {
    std::vector<std::vector<DexelStock::Interval>> rays(4, {{-3.0, 0.0, 1.0}});
    rays[1] = {{-3.0, -2.0, 1.0}, {-1.0, 0.0, 1.0}};
    return DexelStock::fromColumns(0.0, 0.0, 1.0, 2, 2, std::move(rays));
  }();
  CHECK_FALSE(heightfieldMesh(over, 0));
  const DexelStock through = [] {
    std::vector<std::vector<DexelStock::Interval>> rays(4, {{-3.0, 0.0, 1.0}});
    rays[2].clear();
    return DexelStock::fromColumns(0.0, 0.0, 1.0, 2, 2, std::move(rays));
  }();
  CHECK_FALSE(heightfieldMesh(through, 0));
  // The box's far column holds 0.3 of its column (the face 0.3 mm into it); a cut left a
  // sliver over a gap there: a heightfield, its far wall on the box's face.
  const DexelStock rim = [] {
    std::vector<std::vector<DexelStock::Interval>> rays(4, {{-3.0, 0.0, 1.0}});
    rays[1] = {{-3.0, 0.0, 0.3}};
    rays[3] = {{-3.0, -1.0, 0.3}, {-0.99, -0.98, 0.2}};
    return DexelStock::fromColumns(0.0, 0.0, 1.0, 2, 2, std::move(rays));
  }();
  const auto m = heightfieldMesh(rim, 0);
  REQUIRE(m);
  CHECK(boundaryEdgeCount(*m) == 0);
  float far = 0.0f;
  for (const auto& p : m->points)
    far = std::max(far, p[0]);
  CHECK(far == Approx(1.3));
  // A thin share of material over air counts as the column's height (a crossing wall's
  // sliver): still a heightfield.
  const DexelStock sliver = [] {
    std::vector<std::vector<DexelStock::Interval>> rays(4, {{-3.0, 0.0, 1.0}});
    rays[1] = {{-3.0, -2.0, 1.0}, {-1.0, 0.0, 0.2}};
    return DexelStock::fromColumns(0.0, 0.0, 1.0, 2, 2, std::move(rays));
  }();
  CHECK(heightfieldMesh(sliver, 0));
}
