// Tests of stock/Stock.h's MaterialReader in both stock models against geometry known in
// closed form: a slot's walls at 30 degrees to the grid, a box's faces off the grid, and the
// material as it was after each step of a batch.

#include "stock/Stock.h"

#include "cutters/Numbers.h"
#include "cutters/Sweep.h"
#include "tests/stock/StockTestSupport.h"

#include <catch2/catch.hpp>

#include <memory>
#include <vector>

using namespace engage;
using namespace engage::test;

namespace {

/// Reads one point.
bool inMaterial(const Stock& s, const Eigen::Vector3d& p, std::size_t after = Stock::kLatest) {
  return s.materialReader(after)->read({p})[0] != 0;
}

}  // namespace

TEST_CASE("a material reader reads plane walls and faces to a hundredth of a cell", "[stock]") {
  // A box with its faces off the grid (cells from its corner; the faces at x1, y1, z1 a
  // fraction of a cell past a grid line), a slot 6 mm wide cut 2 mm deep along a line at 30
  // degrees to the grid. Points a hundredth of a cell either side of each plane read the side
  // they lie on (the stocks hold such planes exactly: the voxel stock as its voxels' planes,
  // the dexel stock as lines across its columns and intervals exact along z).
  const double h = 0.3, r = 3.0, depth = 2.0;
  const AptCutter flat = AptCutter::flat(2 * r, 18.0);
  for (const char* model : {"dexel", "voxel"}) {
    CAPTURE(model);
    Box3 b;
    b.min = {-30, -30, -10};
    b.max = {30 + 0.37 * h, 30 + 0.61 * h, 0.23 * h};
    std::unique_ptr<Stock> s = boxStock(model, b, h);
    const Eigen::Vector3d a(-20.0, -5.0, b.max.z() - depth);
    s->remove(Sweep(flat, line(a, a + 40.0 * kDir), h));
    const double e = 0.01 * h;
    int checked = 0;
    for (double t = 8.0; t <= 32.0; t += 1.37)
      for (const double z : {-0.5, -1.2, -1.9}) {
        const Eigen::Vector3d c = a + t * kDir + Eigen::Vector3d(0, 0, depth + z);
        for (const double side : {-1.0, 1.0}) {
          // The slot's wall at distance r from its line: air inside, material outside.
          CHECK_FALSE(inMaterial(*s, c + side * (r - e) * kSide));
          CHECK(inMaterial(*s, c + side * (r + e) * kSide));
          checked += 2;
        }
        // Its floor, exact along z in both.
        const Eigen::Vector3d floor = a + t * kDir;
        CHECK(inMaterial(*s, floor - Eigen::Vector3d(0, 0, e)));
        CHECK_FALSE(inMaterial(*s, floor + Eigen::Vector3d(0, 0, e)));
      }
    CHECK(checked > 50);
    // The box's faces off the grid, away from the slot.
    for (double y = -25.0; y <= 25.0; y += 3.3) {
      CHECK(inMaterial(*s, {b.max.x() - e, y, -5.0}));
      CHECK_FALSE(inMaterial(*s, {b.max.x() + e, y, -5.0}));
      CHECK(inMaterial(*s, {y, b.max.y() - e, -5.0}));
      CHECK_FALSE(inMaterial(*s, {y, b.max.y() + e, -5.0}));
      CHECK(inMaterial(*s, {25.0, y, b.max.z() - e}));
      CHECK_FALSE(inMaterial(*s, {25.0, y, b.max.z() + e}));
    }
  }
}

TEST_CASE("a dexel stock reads the material as it was after each step of a batch", "[stock]") {
  // Three steps of a slot taken in one removeSteps call: read as of step k, the stock holds
  // what a stock that removed only steps 0..k holds, at every point of a grid over the cut.
  Box3 b;
  b.min = {-20, -20, -10};
  b.max = {20, 20, 0};
  const double h = 0.4;
  const AptCutter flat = AptCutter::flat(6.0, 18.0);
  const std::vector<Sweep> sweeps = {Sweep(flat, line({-10, 0.3, -2}, {-7, 1.3, -2}), h),
                                     Sweep(flat, line({-7, 1.3, -2}, {-4, 1.3, -3}), h),
                                     Sweep(flat, line({-4, 1.3, -3}, {-1, -0.4, -3}), h)};
  std::unique_ptr<Stock> batch = boxStock("dexel", b, h);
  REQUIRE(batch->readsWithinBatch());
  std::vector<StepCut> cuts;
  for (std::size_t k = 0; k < sweeps.size(); ++k)
    cuts.push_back({&sweeps[k], static_cast<int>(k), 0.0, {}});
  batch->removeSteps(cuts);
  std::vector<Eigen::Vector3d> points;
  for (double x = -14; x <= 3; x += 0.23)
    for (double y = -5; y <= 6; y += 0.31)
      for (const double z : {-0.5, -2.5})
        points.emplace_back(x, y, z);
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    CAPTURE(k);
    std::unique_ptr<Stock> alone = boxStock("dexel", b, h);
    for (std::size_t q = 0; q <= k; ++q)
      alone->remove(sweeps[q]);
    const std::vector<std::uint8_t> want = alone->materialReader()->read(points);
    const std::vector<std::uint8_t> got = batch->materialReader(k)->read(points);
    CHECK(got == want);
  }
  // The latest material is that after the last step; the voxel stock reads only that.
  CHECK(batch->materialReader()->read(points) ==
        batch->materialReader(sweeps.size() - 1)->read(points));
  CHECK_FALSE(boxStock("voxel", b, h)->readsWithinBatch());
}

TEST_CASE("a rib between two cuts reads its two walls where each cell's neighbours hold both",
          "[stock]") {
  // A rib 1.6 cells wide left between two slots at 30 degrees to the grid: a column crossed by
  // one wall has the other among its 3 x 3 neighbours, and a line across it from the central
  // differences alone tilts (the dexel stock's one-sided differences keep it). Points 0.02
  // cells either side of each wall read the side they lie on.
  const double h = 0.3, r = 3.0, half = 0.8 * h;
  const AptCutter flat = AptCutter::flat(2 * r, 18.0);
  for (const char* model : {"dexel", "voxel"}) {
    CAPTURE(model);
    Box3 b;
    b.min = {-30, -30, -10};
    b.max = {30, 30, 0};
    std::unique_ptr<Stock> s = boxStock(model, b, h);
    const Eigen::Vector3d a(-20.0, -5.0, -2.0);
    for (const double side : {-1.0, 1.0})
      s->remove(Sweep(
          flat, line(a + side * (half + r) * kSide, a + side * (half + r) * kSide + 40.0 * kDir),
          h));
    const double e = 0.02 * h;
    for (double t = 8.0; t <= 32.0; t += 0.71) {
      const Eigen::Vector3d c = a + t * kDir + Eigen::Vector3d(0, 0, 1.0);
      for (const double side : {-1.0, 1.0}) {
        CHECK(inMaterial(*s, c + side * (half - e) * kSide));
        CHECK_FALSE(inMaterial(*s, c + side * (half + e) * kSide));
      }
    }
  }
}
