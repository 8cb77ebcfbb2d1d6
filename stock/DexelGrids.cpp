// A dexel stock's rays in stock.vdb, exactly: written as grids (VoxelStock::writeStockVdb)
// and read back ray for ray (VoxelStock::dexelsFromVdb), in either layout.

#include "cutters/Error.h"
#include "stock/DexelStock.h"
#include "stock/VoxelGrid.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace engage::voxel {
namespace {

/// Where the n-th interval of ray (i, j) lies in the dexel grids. Layout 2 (written since
/// 2026-11-28, metadata dexel_layout): x = i, y = j / 8 + n ny8, z = j % 8 (ny8 = ny / 8 rounded
/// up), so that each 8^3 leaf holds 8 x 64 rays' n-th intervals, full where they have one (a
/// fine grid's rays hold one interval or two: at (i, j, n), layout 1, a leaf held 64 rays'
/// eight intervals, an eighth of it used, 194 MB a grid for 3 million rays).
struct DexelLayout {
  int version = 2, ny8 = 0;
  DexelLayout(int v, int ny) : version(v), ny8((ny + 7) / 8) {}
  Coord at(int i, int j, int n) const {
    return version == 1 ? Coord(i, j, n) : Coord(i, j / 8 + n * ny8, j % 8);
  }
  /// (i, j, n) of a coordinate; false where no ray's interval lies there.
  bool ray(const Coord& c, int& i, int& j, int& n) const {
    i = c.x();
    if (version == 1) {
      j = c.y();
      n = c.z();
    } else {
      if (c.y() < 0 || c.z() < 0 || c.z() > 7) return false;
      n = c.y() / ny8;
      j = (c.y() % ny8) * 8 + c.z();
    }
    return i >= 0 && j >= 0 && n >= 0;
  }
};

}  // namespace

openvdb::GridPtrVec dexelGrids(const DexelStock& d, const openvdb::math::Transform& xf) {
  const DexelLayout layout(2, d.raysY());
  openvdb::DoubleGrid::Ptr g[4];
  const char* names[4] = {"dexel_z0", "dexel_z1", "dexel_f", "dexel_weight"};
  for (int k = 0; k < 4; ++k) {
    g[k] = openvdb::DoubleGrid::create(0.0);
    g[k]->setTransform(xf.copy());
    g[k]->setName(names[k]);
    g[k]->setGridClass(openvdb::GRID_UNKNOWN);
  }
  auto z0 = g[0]->getAccessor();
  auto z1 = g[1]->getAccessor();
  auto f = g[2]->getAccessor();
  auto w = g[3]->getAccessor();
  // The partial intervals' lines (DexelStock::Interval), where they have one.
  openvdb::Vec3SGrid::Ptr lines = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  lines->setTransform(xf.copy());
  lines->setName("dexel_line");
  auto line = lines->getAccessor();
  for (int j = 0; j < d.raysY(); ++j)
    for (int i = 0; i < d.raysX(); ++i) {
      const auto& ray = d.ray(i, j);
      for (std::size_t n = 0; n < ray.size(); ++n) {
        const Coord c = layout.at(i, j, static_cast<int>(n));
        z0.setValue(c, ray[n].z0);
        z1.setValue(c, ray[n].z1);
        f.setValue(c, ray[n].f);
        if (ray[n].mx != 0.0f || ray[n].my != 0.0f)
          line.setValue(c, openvdb::Vec3s(ray[n].mx, ray[n].my, 0.0f));
      }
      if (d.weight(i, j) != 1.0) w.setValue(layout.at(i, j, 0), d.weight(i, j));
    }
  g[0]->insertMeta("dexel_x0", openvdb::DoubleMetadata(d.originX()));
  g[0]->insertMeta("dexel_y0", openvdb::DoubleMetadata(d.originY()));
  g[0]->insertMeta("dexel_spacing", openvdb::DoubleMetadata(d.resolution()));
  g[0]->insertMeta("dexel_nx", openvdb::Int32Metadata(d.raysX()));
  g[0]->insertMeta("dexel_ny", openvdb::Int32Metadata(d.raysY()));
  g[0]->insertMeta("dexel_layout", openvdb::Int32Metadata(layout.version));
  return {g[0], g[1], g[2], g[3], lines};
}

std::optional<DexelStock> exactDexels(const std::string& path, double h) {
  initVdb();
  openvdb::GridBase::Ptr g[4];
  openvdb::Vec3SGrid::Ptr lines;  // (files written before the lines: none)
  try {
    openvdb::io::File file(path);
    file.open(false);
    const char* names[4] = {"dexel_z0", "dexel_z1", "dexel_f", "dexel_weight"};
    for (int k = 0; k < 4; ++k) {
      if (!file.hasGrid(names[k])) return std::nullopt;
      g[k] = file.readGrid(names[k]);
    }
    if (file.hasGrid("dexel_line"))
      lines = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid("dexel_line"));
    file.close();
  } catch (const openvdb::Exception&) {
    return std::nullopt;
  }
  openvdb::DoubleGrid::Ptr d[4];
  for (int k = 0; k < 4; ++k)
    if (!(d[k] = openvdb::gridPtrCast<openvdb::DoubleGrid>(g[k]))) return std::nullopt;
  const auto x0 = d[0]->getMetadata<openvdb::DoubleMetadata>("dexel_x0");
  const auto y0 = d[0]->getMetadata<openvdb::DoubleMetadata>("dexel_y0");
  const auto spacing = d[0]->getMetadata<openvdb::DoubleMetadata>("dexel_spacing");
  const auto nx = d[0]->getMetadata<openvdb::Int32Metadata>("dexel_nx");
  const auto ny = d[0]->getMetadata<openvdb::Int32Metadata>("dexel_ny");
  if (!x0 || !y0 || !spacing || !nx || !ny || nx->value() <= 0 || ny->value() <= 0 ||
      !(std::abs(spacing->value() - h) <= 1e-12 * h))
    return std::nullopt;
  const auto version = d[0]->getMetadata<openvdb::Int32Metadata>("dexel_layout");
  if (version && version->value() != 2) return std::nullopt;  // (a layout of a later build)
  const DexelLayout layout(version ? 2 : 1, ny->value());
  const std::size_t count =
      static_cast<std::size_t>(nx->value()) * static_cast<std::size_t>(ny->value());
  std::vector<std::vector<DexelStock::Interval>> rays(count);
  // The ray (i, j) and interval n at c; false outside the rays.
  int i = 0, j = 0, n = 0;
  auto at = [&](const Coord& c) {
    return layout.ray(c, i, j, n) && i < nx->value() && j < ny->value();
  };
  auto rayAt = [&]() -> std::vector<DexelStock::Interval>& {
    return rays[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx->value()) +
                static_cast<std::size_t>(i)];
  };
  std::vector<double> weights(count, 1.0);
  auto z1 = d[1]->getConstAccessor();
  auto f = d[2]->getConstAccessor();
  for (auto it = d[0]->cbeginValueOn(); it; ++it) {
    const Coord c = it.getCoord();
    if (!at(c)) return std::nullopt;
    auto& ray = rayAt();
    if (ray.size() <= static_cast<std::size_t>(n)) ray.resize(static_cast<std::size_t>(n) + 1);
    ray[static_cast<std::size_t>(n)] = {*it, z1.getValue(c), f.getValue(c)};
  }
  if (lines)
    for (auto it = lines->cbeginValueOn(); it; ++it) {
      if (!at(it.getCoord())) return std::nullopt;
      auto& ray = rayAt();
      if (static_cast<std::size_t>(n) >= ray.size()) return std::nullopt;
      ray[static_cast<std::size_t>(n)].mx = (*it).x();
      ray[static_cast<std::size_t>(n)].my = (*it).y();
    }
  for (auto it = d[3]->cbeginValueOn(); it; ++it) {
    if (!at(it.getCoord()) || n != 0) return std::nullopt;
    weights[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx->value()) +
            static_cast<std::size_t>(i)] = *it;
  }
  for (const auto& ray : rays)
    for (std::size_t k = 0; k < ray.size(); ++k)
      if (!(ray[k].z1 > ray[k].z0) || (k > 0 && ray[k].z0 < ray[k - 1].z1))
        return std::nullopt;  // (a hole in the intervals: not what a run wrote)
  return DexelStock::fromColumns(x0->value(), y0->value(), h, nx->value(), ny->value(),
                                 std::move(rays), std::move(weights));
}

}  // namespace engage::voxel
