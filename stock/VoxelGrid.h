#pragma once
/// \file VoxelGrid.h
/// What the voxel stock's source files share (private to stock/, never included outside it:
/// it includes OpenVDB): the grid types, the leaf key, the stock's state (VoxelStock::Impl),
/// and the helpers that construction (VoxelStock.cpp), the files (VoxelStockFiles.cpp) and the
/// surface (VoxelSurface.cpp) each use.

#include "cutters/AptCutter.h"
#include "stock/DexelStock.h"
#include "stock/TriangleMesh.h"
#include "stock/VoxelPlanes.h"
#include "stock/VoxelStock.h"

#include <openvdb/openvdb.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace engage::voxel {

using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::FloatGrid;
using openvdb::Int32Grid;
using Leaf = FloatGrid::TreeType::LeafNodeType;
static_assert(Leaf::SIZE == kLeafVoxels, "VoxelPlanes.h counts the voxels of OpenVDB's leaf");
constexpr int kLeafDim = static_cast<int>(Leaf::DIM);  // 8

/// OpenVDB's initialize(), once per process.
void initVdb();

/// Refuse, before allocating, a grid that could not be held where the cuts reach `reach`
/// (VoxelStock::memoryBound against three quarters of the physical memory). Throws
/// ParameterError naming the voxel size.
void checkMemory(const Box3& box, double h, const std::vector<Box3>* reach = nullptr);

/// Voxels of a grid of size h over `box`, with a voxel's margin on each side.
double voxelCount(const Box3& box, double h);

/// The key of the leaf holding voxel ijk (its coordinates divided by the leaf's 8, floored).
inline std::uint64_t leafKey(const Coord& origin) {
  auto part = [](int v) { return static_cast<std::uint64_t>(v >> 3) & 0x1FFFFFu; };
  return part(origin.x()) | part(origin.y()) << 21 | part(origin.z()) << 42;
}

/// The `isovalue` surface of a grid (0.5 of a fraction grid, 0 of a level set) as a triangle
/// mesh with outward normals; OpenVDB's `adaptivity` (0: none) merges cells where the surface
/// is nearly flat.
TriangleMesh isoSurface(const FloatGrid& grid, double adaptivity, double isovalue = 0.5);

/// Write grids to a .vdb through PATH.part, checked at every stage, renamed when complete.
void writeVdb(const std::string& path, const openvdb::GridPtrVec& grids);

/// The stock's surface as a narrow-band level set (negative inside, within `halfWidth` voxels
/// of it) of the fractions' 0.5 iso-surface (VoxelSurface.cpp).
FloatGrid::Ptr surfaceLevelSet(const FloatGrid& grid, double h, int halfWidth);

/// The voxels of the grid's leaves whose fraction is strictly between 0 and 1.
std::size_t partialVoxels(const FloatGrid& grid);

/// Most voxels stock.vdb's level set may have (VoxelStock::kFileBandVoxels).
constexpr double kFileBandVoxels = VoxelStock::kFileBandVoxels;

/// The factor (1, 2, 4 or 8) by which stock.vdb's level set is coarser than the grid: the
/// least that keeps its band, about 7 layers over the surface's area (the grid's bounds' faces
/// and a voxel's face for each partial voxel), within kFileBandVoxels.
int fileSurfaceFactor(const FloatGrid& grid);

/// A dexel stock's rays as grids for stock.vdb (DexelGrids.cpp): dexel_z0, dexel_z1, dexel_f,
/// dexel_weight (double) and dexel_line (vec3s), the rays' origin, spacing, counts and layout
/// as metadata of dexel_z0.
openvdb::GridPtrVec dexelGrids(const DexelStock& d, const openvdb::math::Transform& xf);

/// The rays a dexel run wrote into `path` (dexelGrids, either layout), when they are there at
/// spacing h; nullopt otherwise.
std::optional<DexelStock> exactDexels(const std::string& path, double h);

/// The fractions averaged over blocks of factor^3 voxels (factor 2, 4 or 8) on a grid that
/// many times coarser (VoxelSurface.cpp); the volume is kept.
FloatGrid::Ptr boxFiltered(const FloatGrid& grid, double h, int factor);

/// How a dexel stock's columns lie on voxel columns of the same spacing h: dexel column (i, j)
/// covers [x0 + i h, x0 + (i + 1) h] (and likewise in y), voxel c covers [(c - 1/2) h,
/// (c + 1/2) h], so each dexel column overlaps four voxel columns and each voxel column
/// (cx + a, cy + b) the dexel columns a - 1 .. a, b - 1 .. b.
struct ColumnFootprint {
  int cx = 0, cy = 0;         // the first voxel column of dexel column (0, 0); the others + 1
  double wx = 0.0, wy = 0.0;  // the share of a dexel column in its first voxel column's x (y)

  explicit ColumnFootprint(const DexelStock& d) {
    const double h = d.resolution();
    auto first = [&](double a0, int& c0, double& w0) {  // the voxels over [a0, a0 + h]
      c0 = static_cast<int>(std::floor(a0 / h + 0.5));
      w0 = ((c0 + 0.5) * h - a0) / h;
    };
    first(d.originX(), cx, wx);
    first(d.originY(), cy, wy);
  }
  /// The share of a dexel column in the voxel column (a, b) of its four, a and b 0 or 1.
  double share(int a, int b) const { return (a ? 1.0 - wx : wx) * (b ? 1.0 - wy : wy); }
  /// fn(i, j, share) for each dexel column of `d` that voxel column (cx + a, cy + b) overlaps,
  /// with the share of that dexel column in it, where it is above 0.
  template <typename Fn>
  void columnsOf(const DexelStock& d, int a, int b, Fn&& fn) const {
    for (int di = 0; di < 2; ++di)
      for (int dj = 0; dj < 2; ++dj) {
        const int i = a - di, j = b - dj;
        if (i < 0 || i >= d.raysX() || j < 0 || j >= d.raysY()) continue;
        const double s = share(di, dj);
        if (s > 0.0) fn(i, j, s);
      }
  }
};

/// A dexel stock's material as fractions on voxels of its ray spacing (VoxelStock::fromDexels).
FloatGrid::Ptr dexelFractions(const DexelStock& d);

/// A column's whole voxels: heights [k0, k1] (none when k0 > k1).
struct FullRun {
  int k0 = 1, k1 = 0;
};
/// Set the whole voxels of columns (cx + a, cy + b), a < ax, b < by, runs[b ax + a], to 1:
/// the heights all columns of each block of 8 x 8 share as one box (tiles where it covers
/// whole nodes), the rest voxel by voxel.
void fillFullRuns(FloatGrid& grid, const std::vector<FullRun>& runs, int ax, int by, int cx,
                  int cy);

}  // namespace engage::voxel

namespace engage {

struct VoxelStock::Impl {
  double h = 1.0;
  voxel::FloatGrid::Ptr grid;
  bool capture = false;
  voxel::FloatGrid::Ptr removed;
  voxel::Int32Grid::Ptr step;
  voxel::FloatGrid::Ptr mrr;
  /// Planes of the partial voxels, per leaf (by leafKey of its origin).
  std::unordered_map<std::uint64_t, voxel::LeafPlanes> planes;
  /// The box the stock was made from, if it was: its shell voxels' planes are its faces.
  std::optional<Box3> box;
  /// Removals so far: the serial number of the planes a removal makes.
  int removals = 0;
  /// The fractions' 0.5 iso-surface as last meshed, after `surfaceAt` removals: stock.vdb's
  /// level set and stock.stl share it, so that the stock is meshed once for both. Made
  /// once when the files are written side by side (a run's outputs, on several cores).
  std::shared_ptr<const TriangleMesh> surface;
  int surfaceAt = -1;
  std::mutex surfaceMutex;

  std::shared_ptr<const TriangleMesh> surfaceMesh() {
    const std::lock_guard<std::mutex> lock(surfaceMutex);
    if (!surface || surfaceAt != removals) {
      surface = std::make_shared<const TriangleMesh>(voxel::isoSurface(*grid, 0.0));
      surfaceAt = removals;
    }
    return surface;
  }

  voxel::Coord index(const Eigen::Vector3d& p) const {
    return voxel::Coord(static_cast<int>(std::floor(p.x() / h + 0.5)),
                        static_cast<int>(std::floor(p.y() / h + 0.5)),
                        static_cast<int>(std::floor(p.z() / h + 0.5)));
  }
};

}  // namespace engage
