#pragma once
/// \file DexelStock.h
/// The material as Z-dexels: a grid of vertical rays (spacing h), each holding the sorted
/// intervals of z where its h x h column holds material, so undercuts and several levels are
/// kept. Computed in a different way from the voxel stock: exact along the tool axis (each
/// removal cuts a ray's intervals at the swept solid's surface, to 1e-4 mm), sampled across
/// it. Each interval carries the share f of its column's cross-section still material, and the
/// line across the column that bounds it, which is where sub-ray accuracy pays (a plain
/// heightfield removes all or nothing and errs by 6-17 % per step on a slot): where the
/// cutter's outline crosses a column it covers the share c of the column on the inner side of
/// the outline (the square's area, from the ray's distance and direction to the outline and its
/// curvature), and the column keeps what lies inside its own line and outside the cutter's
/// (min(f, 1 - c) where the two lines run within 15 deg of each other: one curve cut again).
/// A box stock's last row and column hold their share of the box, bounded by its face.
///
/// A step's swept solid meets a ray in an interval. For cutters whose radius never shrinks
/// upwards: steps that keep their height (lines and arcs in XY) and vertical ones (plunges,
/// retracts) in closed form, from the distance of the ray to the step's path and the
/// profile's radius over height; steps that change height (ramps, helix pieces, and the line
/// pieces of arcs out of XY and splines) from one-dimensional minima along the step (convex
/// along a line): the lowest height the cutter reaches near the ray, and the cover of the band
/// where its outline crosses the column from the ray's distance to the swept solid's slice
/// there. Every other step (inward-leaning sides), all or nothing, by marching the sweep's
/// signed distance up the ray (steps of the distance itself, which never cross the surface)
/// and bisecting its sign changes.

#include "cutters/AptCutter.h"
#include "cutters/Sweep.h"
#include "stock/Stock.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace engage {

/// Z-dexel stock.
class DexelStock : public Stock {
 public:
  /// A box of material (mm). Throws ParameterError for an empty box, a non-positive spacing
  /// or a ray count that would not fit in this machine's memory.
  static DexelStock box(const Box3& box, double spacing);
  /// Bytes a ray holds before it is cut: a vector (24), a weight (8) and one interval (32,
  /// 48 with the allocator's header): 80; measured 84.5 (a 97 x 60 mm box at 0.015 mm, 25.9
  /// million rays, 2.13 GB resident).
  static constexpr double kBytesPerRay = 80.0;
  /// Bytes of a box stock's rays, uncut (cuts add intervals and the removal log): what box()
  /// checks, and a lower bound a batch reserves for the job (engine/run/Batch.h).
  static double memoryBound(const Box3& box, double spacing);
  /// Material inside a closed triangle mesh (STL, OBJ, PLY), by casting every ray through it
  /// (even-odd). Throws as VoxelStock::fromMesh.
  static DexelStock fromMesh(const std::string& path, double spacing);

  double resolution() const override { return h_; }
  double volume() const override;
  Box3 bounds() const override;
  Removal remove(const Sweep& sweep, int step = 0, double dtSeconds = 0.0) override;
  /// The steps tile by tile (16 x 16 columns), the tiles side by side where there are cores and
  /// work enough, each applying the steps that reach it in their order: the removals of
  /// remove() one step after another, to the bit, whatever the thread count.
  std::vector<Removal> removeSteps(const std::vector<StepCut>& steps) override;
  double materialInside(const Sweep& sweep, double top) const override;
  /// The material as it was after step `afterStep` of the last removeSteps call, from what
  /// the rays held before each later step of it changed them.
  std::unique_ptr<MaterialReader> materialReader(std::size_t afterStep = kLatest) const override;
  bool readsWithinBatch() const override { return true; }
  /// A column's line comes from its 3 x 3 neighbours: a surface within one and a half diagonals
  /// (2.12 spacings) tilts it.
  double readingReach() const override { return 2.5; }

  /// Rays in x and y, their spacing, and the grid's corner (mm).
  int raysX() const { return nx_; }
  int raysY() const { return ny_; }
  double originX() const { return x0_; }
  double originY() const { return y0_; }
  /// A material interval of a ray: heights (mm), the share of the column still material, and
  /// the line that bounds it across the column: its outward normal (towards the air; zero where
  /// it is not known: a whole column, or one read from a mesh), the line leaving share f of the
  /// column on its inner side. In a piece of a step's swept solid (DexelSolid.h): the share the
  /// cutter covers and the cutter's outward normal.
  struct Interval {
    double z0, z1;
    double f;
    float mx = 0.0f, my = 0.0f;
  };
  /// The material intervals of ray (i, j), bottom up; and its column's share of the stock.
  const std::vector<Interval>& ray(int i, int j) const { return rays_[index(i, j)]; }
  double weight(int i, int j) const { return weight_[index(i, j)]; }
  /// Columns of `spacing` from (x0, y0): nx x ny rays (row by row, x fastest) with their
  /// material intervals, bottom up, each column whole (weight 1) unless `weights` gives each
  /// column's share. For stocks built elsewhere (VoxelStock::dexelsFromVdb). Throws
  /// ParameterError when no ray holds material.
  static DexelStock fromColumns(double x0, double y0, double spacing, int nx, int ny,
                                std::vector<std::vector<Interval>> rays,
                                std::vector<double> weights = {});

  /// Record, for every removal, where each column lost material and which step removed it
  /// (for removed.vdb, written by VoxelStock::writeRemovedVdb).
  void captureRemoved(bool on) {
    capture_ = on;
    if (on && lostIndex_.empty()) lostIndex_.assign(rays_.size(), kNoColumn);
  }
  /// What a column lost at one voxel height (the heights [(k - 1/2) h, (k + 1/2) h], h the
  /// spacing, as the voxels of VoxelStock::fromDexels) over the captured removals: the share
  /// of the h x h x h cell (times the column's weight), and the first step that took some
  /// (-1: none).
  struct Lost {
    float share = 0.0f;
    std::int32_t step = -1;
  };
  /// A column's losses: cells[n] at voxel height top - n.
  struct LostColumn {
    int top = 0;
    std::vector<Lost> cells;
  };
  /// The losses of column (i, j); nullptr where it lost nothing or nothing was captured.
  const LostColumn* removedColumn(int i, int j) const {
    if (lostIndex_.empty()) return nullptr;
    const std::uint32_t n = lostIndex_[index(i, j)];
    return n == kNoColumn ? nullptr : &lost_[n];
  }
  /// fn(k, z) for the voxel heights k that [z0, z1] overlaps, z the share of the height it
  /// fills, for cells of size h.
  template <typename Fn>
  static void voxelHeights(double h, double z0, double z1, Fn&& fn) {
    const int k0 = static_cast<int>(std::floor(z0 / h + 0.5));
    const int k1 = static_cast<int>(std::floor(z1 / h + 0.5));
    for (int k = k0; k <= k1; ++k) {
      const double z = std::max(0.0, std::min(z1, (k + 0.5) * h) - std::max(z0, (k - 0.5) * h)) / h;
      if (z > 0.0) fn(k, z);
    }
  }
  /// MRR of each captured step, mm^3/min (removed volume over its time).
  const std::vector<double>& stepMrr() const { return stepMrr_; }

  /// Material intervals in all rays (a measure of memory and of the stock's complexity).
  std::size_t segments() const;
  /// Bytes used by the rays.
  std::size_t memoryBytes() const override;

 private:
  DexelStock(const Box3& box, double spacing);
  /// The columns materialInside asks for a swept solid (i0..i1, j0..j1; empty when i1 < i0).
  struct ColumnBox {
    int i0, i1, j0, j1;
  };
  ColumnBox insideBox(const Sweep& sweep) const;
  /// The material of column (i, j) inside `sweep` below `top`, added to `sum` (mm, of the
  /// column's length times its share and weight: times h^2 a volume).
  void addInside(const Sweep& sweep, double top, int i, int j, double& sum) const;
  /// The same for a tool part and its slim one, which lies within it (asked only inside it).
  void addInside(const PartSweep& part, int i, int j, double& slim, double& full) const;
  /// fn(p, v) for the pieces of column (i, j)'s material in [zLow, zHigh], each about h long
  /// and in or out by its middle p: v its material (length times share and weight, mm).
  template <typename Fn>
  void forPieces(int i, int j, double zLow, double zHigh, Fn&& fn) const {
    const double x = x0_ + (i + 0.5) * h_, y = y0_ + (j + 0.5) * h_;
    for (const Interval& piece : rays_[index(i, j)]) {
      const double a = std::max(piece.z0, zLow), b = std::min(piece.z1, zHigh);
      const int n = static_cast<int>(std::ceil((b - a) / h_));
      for (int k = 0; k < n; ++k) {
        const double z0 = a + (b - a) * k / n, z1 = a + (b - a) * (k + 1) / n;
        fn(Eigen::Vector3d(x, y, 0.5 * (z0 + z1)), piece.f * weight_[index(i, j)] * (z1 - z0));
      }
    }
  }
  friend class DexelReader;
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(i);
  }

  double h_ = 0.0, x0_ = 0.0, y0_ = 0.0;
  int nx_ = 0, ny_ = 0;
  std::vector<double> weight_;
  std::vector<std::vector<Interval>> rays_;
  bool capture_ = false;
  /// Per ray, its losses' place in lost_ (kNoColumn: none yet); 4 bytes a ray.
  static constexpr std::uint32_t kNoColumn = 0xFFFFFFFFu;
  std::vector<std::uint32_t> lostIndex_;
  std::vector<LostColumn> lost_;
  /// What the last removeSteps call changed: per ray (by index) and step (in that call), in
  /// that order, the ray's intervals before the step changed it.
  struct Before {
    std::size_t ray, step;
    std::size_t from, count;  ///< its intervals in beforeIntervals_
  };
  std::vector<Before> before_;
  std::vector<Interval> beforeIntervals_;
  std::unordered_map<std::size_t, std::size_t> beforeOf_;  ///< a ray's first in before_
  std::vector<double> stepMrr_;
};

}  // namespace engage
