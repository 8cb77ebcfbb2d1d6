// Tests of stock/Part.h: the deviation of a cut stock from a part, against closed forms, on
// both stock models: a slot 0.1 mm too deep (a gouge over the slot's floor), a slot wall left
// 0.2 mm thick (a leftover), both along the grid and at 30 degrees to it, and the scallops of
// a ball-end finish against the scallop height R - sqrt(R^2 - s^2 / 4).
//
// Bounds: depths and thicknesses within a tenth of a cell (the stock is read to a fraction of
// one: a dexel column's top is flat across it, so a surface sloping by m is read up to
// m h / 2 off); volumes and areas within 1 %, but for the scallops' layer, thinner than a
// tenth of a cell (within 0.0015 of a cell's thickness).

#include "stock/Part.h"

#include "cutters/Error.h"
#include "tests/stock/StockTestSupport.h"
#include "tests/support/PartMeshes.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

using namespace engage;
using namespace engage::test;

namespace {

constexpr double kH = 0.25;  // the cell, mm

/// The box from `low` to `high`.
Box3 boxOf(const Eigen::Vector3d& low, const Eigen::Vector3d& high) {
  Box3 b;
  b.min = low;
  b.max = high;
  return b;
}

/// Cut a straight pass from a to b in steps of 2.5 cells.
void pass(Stock& stock, const AptCutter& c, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const int n = static_cast<int>(std::ceil((b - a).norm() / (2.5 * kH)));
  for (int k = 0; k < n; ++k)
    stock.remove(Sweep(c, line(a + (b - a) * k / n, a + (b - a) * (k + 1) / n), kH));
}

/// Sums over the samples for which `keep` holds.
struct Sums {
  double area = 0.0, volume = 0.0, deepest = 0.0, thickest = 0.0;
  std::size_t count = 0;
};
Sums sums(const std::vector<PartSample>& samples, const std::vector<SampleDeviation>& dev,
          const std::function<bool(const PartSample&, const SampleDeviation&)>& keep) {
  Sums s;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!keep(samples[i], dev[i])) continue;
    ++s.count;
    s.area += samples[i].area;
    s.volume += samples[i].area * std::abs(dev[i].deviation);
    s.deepest = std::max(s.deepest, static_cast<double>(-dev[i].deviation));
    s.thickest = std::max(s.thickest, static_cast<double>(dev[i].deviation));
  }
  return s;
}

/// Rotate a mesh by `angle` about the vertical through (cx, cy).
TriangleMesh rotated(TriangleMesh m, double angle, double cx, double cy) {
  const double c = std::cos(angle), s = std::sin(angle);
  for (auto& p : m.points) {
    const double x = p[0] - cx, y = p[1] - cy;
    p[0] = static_cast<float>(cx + c * x - s * y);
    p[1] = static_cast<float>(cy + s * x + c * y);
  }
  return m;
}

}  // namespace

TEST_CASE("part: a closed mesh's area and volume and its signed distance and open meshes refused",
          "[part]") {
  const Part p(block(0, 0, -10, 40, 20, 0));
  CHECK(p.area() == Approx(2 * (40 * 20 + 40 * 10 + 20 * 10)).epsilon(1e-12));
  CHECK(p.signedDistance({10, 10, -1}) == Approx(-1.0).epsilon(1e-12));
  CHECK(p.signedDistance({10, 10, 3}) == Approx(3.0).epsilon(1e-12));
  CHECK(p.signedDistance({43, 24, 0}) == Approx(5.0).epsilon(1e-12));  // from the edge
  // A mesh wound inside out is turned over: its samples' normals point out.
  TriangleMesh inverted = block(0, 0, -10, 40, 20, 0);
  for (auto& t : inverted.triangles)
    std::swap(t[1], t[2]);
  for (const PartSample& s : Part(inverted).samples(5.0))
    CHECK(p.signedDistance((s.point + s.normal).cast<double>()) > 0.0);
  // The samples cover the surface: their areas sum to it, none is wider than the spacing.
  double area = 0.0;
  const std::vector<PartSample> samples = p.samples(1.0);
  for (const PartSample& s : samples)
    area += s.area;
  CHECK(area == Approx(p.area()).epsilon(1e-6));
  CHECK(samples.size() == p.sampleCount(1.0));
  TriangleMesh open = block(0, 0, -10, 40, 20, 0);
  open.triangles.pop_back();
  CHECK_THROWS_AS(Part(open), ParameterError);
  CHECK_THROWS_AS(Part(TriangleMesh{}), ParameterError);
}

TEST_CASE("part: a slot cut 0.1 mm too deep gouges its floor by 0.1 mm", "[part]") {
  // The slot y in [17, 23] down to Z-5, cut by a 6 mm flat end mill at Z-5.1 along Y20: the
  // floor (40 x 6 mm) is gone 0.1 mm deep, 24 mm^3; the walls are where the part has them.
  const Part part(slottedBlock(0, 0, -10, 40, 40, 0, 17, 23, -5));
  for (const std::string model : {"dexel", "voxel"}) {
    INFO(model);
    const auto stock = boxStock(model, boxOf({0, 0, -10}, {40, 40, 0}), kH);
    pass(*stock, AptCutter::flat(6, 20), {-5, 20, -5.1}, {45, 20, -5.1});
    const std::vector<PartSample> samples = part.samples(std::sqrt(2.0) * kH);
    const std::vector<SampleDeviation> dev = measureDeviation(part, samples, *stock);
    const Sums gouge = sums(samples, dev, [](const PartSample&, const SampleDeviation& d) {
      return d.deviation < -0.05;
    });
    CHECK(gouge.deepest == Approx(0.1).margin(0.1 * kH));
    CHECK(gouge.area == Approx(240.0).epsilon(0.01));
    CHECK(gouge.volume == Approx(24.0).epsilon(0.01));
    const Sums left = sums(samples, dev, [](const PartSample&, const SampleDeviation& d) {
      return d.deviation > 0.05;
    });
    CHECK(left.count == 0);
  }
}

TEST_CASE("part: a slot wall left 0.2 mm thick, along the grid and at 30 deg to it", "[part]") {
  // A 5.8 mm end mill along Y20.1 at Z-5 cuts y in [17.2, 23]: the wall at Y17 keeps 0.2 mm
  // over 40 x 5 mm, 40 mm^3 (the samples of the wall and of the floor beside it share it at
  // their bisector); nothing is gouged. At 30 deg the part and the pass turn about (20, 20);
  // the samples looked at are those of the slot's faces (within 3.5 mm of its middle line,
  // away from the stock's sides).
  for (const double angle : {0.0, kPi / 6}) {
    const Part part(rotated(slottedBlock(0, 0, -10, 40, 40, 0, 17, 23, -5), angle, 20, 20));
    const Eigen::Vector3d along(std::cos(angle), std::sin(angle), 0),
        across(-along.y(), along.x(), 0);
    const Eigen::Vector3d middle(20, 20, 0);
    auto inSlot = [&](const PartSample& s) {
      const Eigen::Vector3d p = s.point.cast<double>() - middle;
      return std::abs(p.dot(across)) < 3.5 && std::abs(p.dot(along)) < 15.0 && p.z() > -5.5;
    };
    for (const std::string model : {"dexel", "voxel"}) {
      INFO(model << " at " << angle * 180 / kPi << " deg");
      const auto stock = boxStock(model, boxOf({-10, -10, -10}, {50, 50, 0}), kH);
      const Eigen::Vector3d a = middle - 25 * along + 0.1 * across - Eigen::Vector3d(0, 0, 5);
      pass(*stock, AptCutter::flat(5.8, 20), a, a + 50 * along);
      const std::vector<PartSample> samples = part.samples(std::sqrt(2.0) * kH);
      const std::vector<SampleDeviation> dev = measureDeviation(part, samples, *stock);
      const Sums left = sums(samples, dev, [&](const PartSample& s, const SampleDeviation& d) {
        return inSlot(s) && d.deviation > 0.0;
      });
      CHECK(left.thickest == Approx(0.2).margin(0.1 * kH));
      CHECK(left.volume == Approx(30 * 5 * 0.2).epsilon(0.01));
      const Sums gouge = sums(samples, dev, [&](const PartSample& s, const SampleDeviation& d) {
        return inSlot(s) && d.deviation < -0.1 * kH;
      });
      CHECK(gouge.count == 0);
    }
  }
}

TEST_CASE("part: a ball finish's scallops are as high as R - sqrt(R^2 - s^2 / 4)", "[part]") {
  // A 6 mm ball end mill in passes along X, 1 mm apart, the tip on the part's top Z0, through
  // 1 mm of stock above it: the cusps stand 3 - sqrt(8.75) = 0.041960 mm; each pass leaves
  // s R - (s/2) sqrt(R^2 - s^2/4) - R^2 asin(s / 2R) = 0.0139452 mm^2 of cross-section, so a
  // 30 x 30 mm window of the top (30 passes) holds 0.0139452 x 30 x 30 mm^3.
  const double R = 3.0, s = 1.0;
  const double cusp = R - std::sqrt(R * R - s * s / 4);
  const double section =
      s * R - (s / 2) * std::sqrt(R * R - s * s / 4) - R * R * std::asin(s / (2 * R));
  const Part part(block(0, 0, -10, 40, 40, 0));
  for (const std::string model : {"dexel", "voxel"}) {
    INFO(model);
    const auto stock = boxStock(model, boxOf({0, 0, -10}, {40, 40, 1}), kH);
    for (double y = -3.7; y < 44; y += s)  // the passes at y = 0.3 + k: cusps off the grid
      pass(*stock, AptCutter::ball(2 * R, 20), {-5, y, 0}, {45, y, 0});
    const std::vector<PartSample> samples = part.samples(std::sqrt(2.0) * kH);
    const std::vector<SampleDeviation> dev = measureDeviation(part, samples, *stock);
    const Sums top = sums(samples, dev, [](const PartSample& p, const SampleDeviation&) {
      return p.normal.z() > 0.9f && p.point.x() > 5 && p.point.x() < 35 && p.point.y() > 5 &&
             p.point.y() < 35;
    });
    CHECK(top.thickest == Approx(cusp).margin(0.1 * kH));
    // The layer averages 0.014 mm, an eighteenth of a cell: held to 0.0015 of a cell's
    // thickness over the window (0.4 micron here), 3 % of its volume.
    CHECK(top.volume == Approx(section * 30 * 30).margin(0.0015 * kH * 30 * 30));
    CHECK(top.deepest <= 0.1 * kH);
  }
}
