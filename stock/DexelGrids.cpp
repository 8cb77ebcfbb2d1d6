// A dexel stock's rays in stock.vdb, exactly: written as grids (VoxelStock::writeStockVdb)
// and read back ray for ray (VoxelStock::dexelsFromVdb), in either layout; and a dexel run's
// stock.vdb whose fractions are coarser than its rays (VoxelStock::writeDexelStockVdb).

#include "cutters/Error.h"
#include "stock/DexelStock.h"
#include "stock/VoxelGrid.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
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
/// eight intervals, an eighth of it used, 194 MB a grid for 3 million rays). Layout 3 (since
/// 2026-12-08): layout 2's places, and a leaf of first intervals all alike may be one tile (an
/// uncut board's leaves: 12 million rays' grids went from 288 MB to a few).
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
  const DexelLayout layout(3, d.raysY());
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
  auto write = [&](int i, int j) {
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
  };
  // The rays of one leaf of the first intervals (8 x 64 of them) that are all alike (one
  // interval over the same heights, whole columns, no line: a stock's uncut or flat-floored
  // areas, most of a fine grid) are one tile of each grid instead of a leaf of 512 values.
  const int nx = d.raysX(), ny = d.raysY();
  auto alike = [&](int i0, int j0) {
    const auto& first = d.ray(i0, j0);
    if (first.size() != 1) return false;
    for (int j = j0; j < j0 + 64; ++j)
      for (int i = i0; i < i0 + 8; ++i) {
        const auto& ray = d.ray(i, j);
        if (ray.size() != 1 || ray[0].z0 != first[0].z0 || ray[0].z1 != first[0].z1 ||
            ray[0].f != first[0].f || ray[0].mx != 0.0f || ray[0].my != 0.0f ||
            d.weight(i, j) != 1.0)
          return false;
      }
    return true;
  };
  for (int j0 = 0; j0 < ny; j0 += 64)
    for (int i0 = 0; i0 < nx; i0 += 8) {
      // (A leaf wholly of first intervals: its 8 rows of j / 8 below ny8.)
      if (i0 + 8 <= nx && j0 + 64 <= ny && j0 / 8 + 8 <= layout.ny8 && alike(i0, j0)) {
        const auto& ray = d.ray(i0, j0);
        const Coord origin = layout.at(i0, j0, 0);
        g[0]->tree().addTile(1, origin, ray[0].z0, true);
        g[1]->tree().addTile(1, origin, ray[0].z1, true);
        g[2]->tree().addTile(1, origin, ray[0].f, true);
        continue;
      }
      for (int j = j0; j < std::min(ny, j0 + 64); ++j)
        for (int i = i0; i < std::min(nx, i0 + 8); ++i)
          write(i, j);
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
  if (version && version->value() != 2 && version->value() != 3)
    return std::nullopt;  // (a layout of a later build)
  const DexelLayout layout(version ? version->value() : 1, ny->value());
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
    // (A tile, layout 3: a leaf's rays alike, each of its voxels a ray's interval.)
    const openvdb::CoordBBox box =
        it.isVoxelValue() ? openvdb::CoordBBox(it.getCoord(), it.getCoord()) : it.getBoundingBox();
    if (!it.isVoxelValue() && (layout.version != 3 || box.volume() != Leaf::SIZE))
      return std::nullopt;
    for (auto c = box.beginXYZ(); c; ++c) {
      if (!at(*c)) return std::nullopt;
      auto& ray = rayAt();
      if (ray.size() <= static_cast<std::size_t>(n)) ray.resize(static_cast<std::size_t>(n) + 1);
      ray[static_cast<std::size_t>(n)] = {*it, z1.getValue(*c), f.getValue(*c)};
    }
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

namespace engage {
using namespace voxel;
namespace {

/// The highest and lowest material of a dexel stock's rays, mm (lo > hi: none).
void rayHeights(const DexelStock& d, double& lo, double& hi) {
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  for (int j = 0; j < d.raysY(); ++j)
    for (int i = 0; i < d.raysX(); ++i) {
      const auto& ray = d.ray(i, j);
      if (ray.empty()) continue;
      lo = std::min(lo, ray.front().z0);
      hi = std::max(hi, ray.back().z1);
    }
}

/// A dexel stock's material as fractions on voxels `factor` (2, 4 or 8) times its spacing h,
/// on the grid boxFiltered makes of its fractions at h (coarse voxel I over voxels factor I ..
/// factor I + factor - 1): each interval's material added to the coarse voxels its column's
/// footprint and heights overlap, one coarse row at a time, without the voxels at h.
FloatGrid::Ptr coarseDexelFractions(const DexelStock& d, int factor) {
  const double h = d.resolution();
  const int shift = factor == 2 ? 1 : factor == 4 ? 2 : 3;
  FloatGrid::Ptr grid = FloatGrid::create(0.0f);
  openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(factor * h);
  xf->postTranslate(openvdb::Vec3d(0.5 * (factor - 1) * h));
  grid->setTransform(xf);
  grid->setName("stock");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  double zLow = 0.0, zHigh = 0.0;
  rayHeights(d, zLow, zHigh);
  if (!(zLow < zHigh)) return grid;
  const ColumnFootprint corner(d);
  const int nx = d.raysX(), ny = d.raysY();
  // Heights in voxels at h: t = z / h + 1/2 (voxel k over [k, k + 1)); coarse K over
  // [K factor, (K + 1) factor).
  auto coarse = [&](double t) { return static_cast<int>(std::floor(t / factor)); };
  const int k0 = coarse(zLow / h + 0.5), k1 = coarse(zHigh / h + 0.5);
  const int a0 = corner.cx >> shift, a1 = (corner.cx + nx) >> shift;
  const int b0 = corner.cy >> shift, b1 = (corner.cy + ny) >> shift;
  const int na = a1 - a0 + 1, nb = b1 - b0 + 1, nk = k1 - k0 + 2;
  // One coarse row's columns: the material of each coarse voxel (in voxels at h), and the
  // changes of a level that covers whole coarse voxels.
  std::vector<double> sum(static_cast<std::size_t>(na) * static_cast<std::size_t>(nk));
  std::vector<double> level(sum.size());
  auto at = [&](int a, int k) {
    return static_cast<std::size_t>(a) * static_cast<std::size_t>(nk) + static_cast<std::size_t>(k);
  };
  // Material w per voxel height over heights [t0, t1] of coarse column a.
  auto add = [&](int a, double t0, double t1, double w) {
    const int q0 = coarse(t0) - k0, q1 = coarse(t1) - k0;
    if (q0 == q1) {
      sum[at(a, q0)] += w * (t1 - t0);
      return;
    }
    sum[at(a, q0)] += w * ((q0 + k0 + 1) * factor - t0);
    sum[at(a, q1)] += w * (t1 - (q1 + k0) * factor);
    if (q1 > q0 + 1) {
      level[at(a, q0 + 1)] += w * factor;
      level[at(a, q1)] -= w * factor;
    }
  };
  std::vector<FullRun> full(static_cast<std::size_t>(na) * static_cast<std::size_t>(nb));
  auto acc = grid->getAccessor();
  const double cell = static_cast<double>(factor) * factor * factor;
  for (int b = b0; b <= b1; ++b) {
    std::fill(sum.begin(), sum.end(), 0.0);
    std::fill(level.begin(), level.end(), 0.0);
    // The rays whose columns (at voxel rows cy + j and cy + j + 1) reach coarse row b.
    const int jLow = std::max(0, b * factor - corner.cy - 1);
    const int jHigh = std::min(ny - 1, b * factor + factor - 1 - corner.cy);
    for (int j = jLow; j <= jHigh; ++j) {
      double rowShare = 0.0;
      if ((corner.cy + j) >> shift == b) rowShare += corner.wy;
      if ((corner.cy + j + 1) >> shift == b) rowShare += 1.0 - corner.wy;
      if (!(rowShare > 0.0)) continue;
      for (int i = 0; i < nx; ++i) {
        const auto& ray = d.ray(i, j);
        const double w = rowShare * d.weight(i, j);
        if (ray.empty() || !(w > 0.0)) continue;
        const int first = ((corner.cx + i) >> shift) - a0;
        const int second = ((corner.cx + i + 1) >> shift) - a0;
        for (const DexelStock::Interval& iv : ray) {
          const double t0 = iv.z0 / h + 0.5, t1 = iv.z1 / h + 0.5;
          if (first == second) {
            add(first, t0, t1, w * iv.f);
          } else {
            add(first, t0, t1, w * iv.f * corner.wx);
            add(second, t0, t1, w * iv.f * (1.0 - corner.wx));
          }
        }
      }
    }
    for (int a = 0; a < na; ++a) {
      FullRun& run = full[static_cast<std::size_t>(b - b0) * static_cast<std::size_t>(na) +
                          static_cast<std::size_t>(a)];
      double whole = 0.0;
      for (int q = 0; q < nk; ++q) {
        whole += level[at(a, q)];
        const auto v = static_cast<float>(std::min(1.0, (whole + sum[at(a, q)]) / cell));
        if (!(v > 0.0f)) continue;
        // (A column's first run of whole voxels as a run: boxes of 8 x 8 columns.)
        if (v == 1.0f && (run.k0 > run.k1 || run.k1 == k0 + q - 1)) {
          if (run.k0 > run.k1) run.k0 = k0 + q;
          run.k1 = k0 + q;
          continue;
        }
        acc.setValue(Coord(a0 + a, b, k0 + q), v);
      }
    }
  }
  acc.clear();
  fillFullRuns(*grid, full, na, nb, a0, b0);
  grid->tree().prune();
  return grid;
}

}  // namespace

namespace {

/// The least factor of 1, 2, 4, 8 that brings `band` voxels at the rays' cell within `budget`.
int factorOfBand(double band, double budget) {
  int c = 1;
  while (c < 8 && band / (c * c) > budget)
    c *= 2;
  return c;
}

}  // namespace

int VoxelStock::dexelFileFactor(const DexelStock& d, double bandVoxels) {
  const double h = d.resolution();
  double zLow = 0.0, zHigh = 0.0;
  rayHeights(d, zLow, zHigh);
  if (!(zLow < zHigh)) return 1;
  const double x = d.raysX() + 1.0, y = d.raysY() + 1.0, z = (zHigh - zLow) / h + 1.0;
  double partial = 0.0;
  for (int j = 0; j < d.raysY(); ++j)
    for (int i = 0; i < d.raysX(); ++i) {
      const auto& ray = d.ray(i, j);
      for (const DexelStock::Interval& iv : ray)
        partial += 2.0 + (iv.f < 1.0 ? (iv.z1 - iv.z0) / h : 0.0);
      if (!ray.empty() && d.weight(i, j) < 1.0) partial += (ray.back().z1 - ray.front().z0) / h;
    }
  return factorOfBand(7.0 * (2.0 * (x * y + y * z + z * x) + partial), bandVoxels);
}

int VoxelStock::dexelFileFactor(const Box3& box, double spacing, double bandVoxels) {
  // The uncut box's rays: each one interval (two partial voxels), its faces.
  const Eigen::Vector3d n = (box.max - box.min) / spacing;
  const double x = std::ceil(n.x()) + 1.0, y = std::ceil(n.y()) + 1.0, z = n.z() + 1.0;
  return factorOfBand(7.0 * (2.0 * (x * y + y * z + z * x) + 2.0 * (x - 1.0) * (y - 1.0)),
                      bandVoxels);
}

void VoxelStock::writeDexelStockVdb(const DexelStock& rays, const std::string& path,
                                    double bandVoxels) {
  writeDexelStockVdbAt(rays, path, dexelFileFactor(rays, bandVoxels));
}

void VoxelStock::writeDexelStockVdbAt(const DexelStock& rays, const std::string& path, int factor) {
  if (factor == 1) {
    fromDexels(rays).writeStockVdb(path, &rays);
    return;
  }
  initVdb();
  const double h = rays.resolution();
  const FloatGrid::Ptr fractions = coarseDexelFractions(rays, factor);
  const FloatGrid::Ptr surface = surfaceLevelSet(*fractions, factor * h, 3);
  // The box the voxels at h would cover (fileBounds), the fractions' factor.
  const ColumnFootprint corner(rays);
  int iLow = rays.raysX(), iHigh = -1, jLow = rays.raysY(), jHigh = -1;
  for (int j = 0; j < rays.raysY(); ++j)
    for (int i = 0; i < rays.raysX(); ++i)
      if (!rays.ray(i, j).empty() && rays.weight(i, j) > 0.0) {
        iLow = std::min(iLow, i);
        iHigh = std::max(iHigh, i);
        jLow = std::min(jLow, j);
        jHigh = std::max(jHigh, j);
      }
  double zLow = 0.0, zHigh = 0.0;
  rayHeights(rays, zLow, zHigh);
  auto voxel = [&](double z) { return std::floor(z / h + 0.5); };
  const openvdb::Vec3d lo((corner.cx + iLow + (corner.wx > 0.0 ? 0 : 1) - 0.5) * h,
                          (corner.cy + jLow + (corner.wy > 0.0 ? 0 : 1) - 0.5) * h,
                          (voxel(zLow) - 0.5) * h);
  const openvdb::Vec3d hi((corner.cx + iHigh + (corner.wx < 1.0 ? 1 : 0) + 0.5) * h,
                          (corner.cy + jHigh + (corner.wy < 1.0 ? 1 : 0) + 0.5) * h,
                          (voxel(zHigh) + 0.5) * h);
  fractions->insertMeta("dexel_coarser", openvdb::Int32Metadata(factor));
  fractions->insertMeta("material_min", openvdb::Vec3DMetadata(lo));
  fractions->insertMeta("material_max", openvdb::Vec3DMetadata(hi));
  openvdb::GridPtrVec grids{fractions, surface};
  for (int i = 0; i < 3; ++i) {  // (none: a dexel stock's voxels keep no planes)
    openvdb::Vec3SGrid::Ptr planes = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    planes->setTransform(fractions->transform().copy());
    planes->setName("planes_" + std::to_string(i));
    planes->setGridClass(openvdb::GRID_UNKNOWN);
    grids.push_back(planes);
  }
  for (const openvdb::GridBase::Ptr& g :
       dexelGrids(rays, *openvdb::math::Transform::createLinearTransform(h)))
    grids.push_back(g);
  writeVdb(path, grids);
}

}  // namespace engage
