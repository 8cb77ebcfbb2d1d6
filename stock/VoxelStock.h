#pragma once
/// \file VoxelStock.h
/// The material, as a sparse grid of volume fractions on OpenVDB (kept out of this header).
///
/// Each voxel (cell-centred, size h) holds the fraction m in [0, 1] of its volume that is
/// still material, and a partial voxel also up to three planes that bound that material
/// (inside two planes, or a corner of floor and wall: inside either of two planes and inside
/// an outer one, the face the corner was cut into). Removing a step's swept solid S replaces
/// S's boundary in each voxel by the plane of its signed distance and gradient at the centre,
/// moved by the surface's mean sagitta over the voxel (its curvature), or on a flat bottom's
/// rim by the swept solid's supporting planes, and takes the exact share of the material
/// inside them (polyhedral clipping, stock/CubeClip.h); the voxel keeps the planes that bound
/// what is left. The planes matter where two surfaces cross one voxel (a side cut's front
/// meeting the previous pass's wall, a helix turn meeting the last turn's floor), where the
/// fraction alone, min(m, 1 - cut), cannot tell where the material lies.
///
/// Cost follows what changes: blocks of air are skipped without a look, material tiles are
/// split into voxels only where the step reaches, voxels already air are not evaluated, and
/// leaves the step cannot reach are rejected from one distance at their centre.
/// Results do not depend on the thread count: per-leaf results are combined in leaf order.

#include "cutters/AptCutter.h"
#include "cutters/Sweep.h"
#include "stock/Stock.h"
#include "stock/TriangleMesh.h"

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace engage {

class DexelStock;

/// Sparse-voxel stock of volume fractions.
class VoxelStock : public Stock {
 public:
  /// A box of material (mm). Voxels that the box covers partly get their covered fraction.
  /// Throws ParameterError for an empty box, a non-positive voxel size, or a voxel size whose
  /// grid would not fit in this machine's memory where the cuts may reach (`reach`, as for
  /// memoryBound; checked before anything is allocated).
  static VoxelStock box(const Box3& box, double voxelSize,
                        const std::vector<Box3>* reach = nullptr);
  /// Bytes a box stock may come to hold at most when the cuts stay within the boxes `reach`
  /// (mm; null: anywhere in the box): the leaves of the box's partly covered faces, and every
  /// voxel of the leaves the cuts reach with its capture grids and planes. A sparse grid holds
  /// only these: a V-bit's groove across a 91 x 54 mm plate needs the faces' leaves, not the
  /// plate's 10^10 voxels. What box() checks against this machine's memory, what a batch
  /// reserves for the job (engine/run/Batch.h) and what the default cell is held to
  /// (engine/run/Resolution.h). Counting stops once the bytes exceed `stopAbove`.
  static double memoryBound(const Box3& box, double voxelSize,
                            const std::vector<Box3>* reach = nullptr,
                            double stopAbove = std::numeric_limits<double>::infinity());
  /// Material inside a closed triangle mesh (STL, OBJ, PLY; read with OpenMesh). Throws
  /// Error for a missing or unreadable file, ParameterError for an open mesh (naming the
  /// number of boundary edges) or a voxel size that would not fit in memory.
  static VoxelStock fromMesh(const std::string& path, double voxelSize);
  /// The stock of an earlier run: grid "stock" (material fractions) of a stock.vdb, on voxels
  /// of size h. A grid of another voxel size or offset is resampled by overlap (each old voxel's
  /// material shared among the new voxels it overlaps: the volume is kept). Partial voxels get
  /// the plane normal to the fractions' gradient that holds their fraction (the planes of the
  /// earlier run are not in the file). Throws Error for a missing or unreadable file,
  /// ParameterError for a file without a float grid "stock" of fractions 0 to 1 on a uniform,
  /// unrotated grid, or a voxel size that would not fit in memory.
  static VoxelStock fromVdb(const std::string& path, double voxelSize);
  /// The box (mm) of the material of a stock.vdb's grid "stock", from the file's metadata
  /// (the active voxels' bounds OpenVDB writes with each grid) without reading the grid;
  /// nullopt when the file or that metadata cannot be read (fromVdb then says why).
  static std::optional<Box3> fileBounds(const std::string& path);
  /// The material grid "stock" of a stock.vdb holds as written: its fractions' sum times its
  /// voxels' volume, mm^3, at its own cell (a dexel run's coarser fractions as they are, not
  /// its rays); of another fraction grid with `grid` (removed.vdb's "removed"). Throws Error
  /// for a file that cannot be read or has no such float grid.
  static double fileVolume(const std::string& path, const std::string& grid = "stock");
  /// The same stock as dexels of spacing h: a dexel run's own rays where the file holds them
  /// at this spacing (writeStockVdb), exactly; else each column of the resampled voxels
  /// becomes a ray: a partial voxel whose fractions change mostly along z is a shorter piece
  /// of the column (a floor or a top), otherwise the whole piece with its fraction as the
  /// column's share.
  static DexelStock dexelsFromVdb(const std::string& path, double spacing);
  /// The material of a dexel stock as volume fractions on voxels of its ray spacing (for
  /// stock.vdb and stock.stl of dexel runs): each voxel gets the share of the columns it
  /// overlaps. The volume is kept exactly (up to 32-bit floats).
  static VoxelStock fromDexels(const DexelStock& dexels);
  /// Write a dexel run's removed.vdb (grids "removed", "step", "mrr" as writeRemovedVdb) from
  /// its capture log (DexelStock::captureRemoved(true) before the removals). Where its voxels'
  /// three values would exceed `values` (removedFileFactor), the voxels are 2, 4 or 8 times
  /// the rays' spacing (a fine tool over a whole board): each the mean of the removal it
  /// covers, the first step of its voxels and that step's MRR, metadata `coarser` the factor.
  static void writeRemovedVdb(const DexelStock& dexels, const std::string& path,
                              double values = kFileBandVoxels);
  /// The factor (1, 2, 4 or 8) by which a removed.vdb of `voxels` voxels at its stock's cell is
  /// made coarser so that its three values a voxel stay within `values`.
  static int removedFileFactor(double voxels, double values = kFileBandVoxels);

  VoxelStock(VoxelStock&&) noexcept;
  VoxelStock& operator=(VoxelStock&&) noexcept;
  ~VoxelStock() override;

  /// Voxel size h, mm.
  double voxelSize() const;
  double resolution() const override { return voxelSize(); }
  bool followsTiltedTools() const override { return true; }
  /// Material volume: sum of fractions times h^3, mm^3.
  double volume() const override;
  /// Material fraction of the voxel centred at (i, j, k) h.
  double fraction(int i, int j, int k) const;
  /// Bounds of the material, mm (empty box when no material is left).
  Box3 bounds() const override;
  /// Bytes used by the grids (the stock and, when captured, the removed-volume grids).
  std::size_t memoryBytes() const override;

  /// Record, for every voxel that loses material, how much it lost, the index of the first
  /// step that removed material from it, and that step's MRR (for removed.vdb).
  void captureRemoved(bool on);

  /// Remove one step's swept solid. With capture on, `step` and the step's MRR (removed
  /// volume over `dtSeconds`, mm^3/min; 0 when dtSeconds is 0) go to the capture grids.
  Removal remove(const Sweep& sweep, int step = 0, double dtSeconds = 0.0) override;
  double materialInside(const Sweep& sweep, double top) const override;
  /// (The material as it is now: afterStep is not looked at.)
  std::unique_ptr<MaterialReader> materialReader(std::size_t afterStep = kLatest) const override;
  /// A voxel holds a wall and a cut across it as two planes; a third surface in the voxel (one
  /// within its diagonal, 1.73 sizes, of the point) is approximated.
  double readingReach() const override { return 2.0; }

  /// Write stock.vdb: grid "stock" (material fraction), grid "surface" (the stock's surface
  /// as a narrow-band level set, negative inside, 3 voxels each side) and grids "planes_0",
  /// "planes_1" (each partial voxel's planes, which fromVdb reads back). With `rays` (a
  /// dexel run, whose voxels these are: fromDexels), also its rays exactly: grids
  /// "dexel_z0", "dexel_z1", "dexel_f" (double; the n-th interval of ray (i, j), dexelGrids)
  /// and "dexel_weight" (columns covered in part), with the rays' origin, spacing and counts
  /// as metadata, which dexelsFromVdb reads back at the same spacing. Written to a temporary
  /// name and renamed when complete. Throws Error on I/O failure.
  void writeStockVdb(const std::string& path, const DexelStock* rays = nullptr) const;
  /// Write a dexel run's stock.vdb: fromDexels(rays).writeStockVdb(path, &rays), unless the
  /// surface's band at the rays' spacing would exceed `bandVoxels` (a fine tool's grid over a
  /// whole board: dexelFileFactor > 1). Then grid "stock" holds the fractions averaged over
  /// blocks of that factor^3 voxels (metadata "dexel_coarser": the factor; "material_min" and
  /// "material_max": the box fromDexels' voxels would cover, mm), made from the rays without
  /// the voxels at their spacing, and "surface" is made from it; the rays are written exactly
  /// as always, and a run from the file (fromVdb, dexelsFromVdb, fileBounds) reads them.
  static void writeDexelStockVdb(const DexelStock& rays, const std::string& path,
                                 double bandVoxels = kFileBandVoxels);
  /// writeDexelStockVdb at a factor already known (dexelFileFactor: 1, 2, 4 or 8).
  static void writeDexelStockVdbAt(const DexelStock& rays, const std::string& path, int factor);
  /// The factor (1, 2, 4 or 8) by which writeDexelStockVdb's fractions and surface are coarser
  /// than the rays: the least that keeps the surface's band, about 7 layers over the rays'
  /// box's faces and a voxel's face for each partial voxel (two for each interval, one for
  /// each cell height of a partly covered column), within bandVoxels.
  static int dexelFileFactor(const DexelStock& rays, double bandVoxels = kFileBandVoxels);
  /// dexelFileFactor of a box's uncut rays of `spacing` (the least a dexel run's stock.vdb of
  /// that box can have: its cuts only add to the band).
  static int dexelFileFactor(const Box3& box, double spacing, double bandVoxels = kFileBandVoxels);
  /// Most voxels stock.vdb's level set may have (about 10 bytes each while it is made, 4 in the
  /// file): about 3 layers on each side of a surface of 330 mm^2 at 0.01 mm.
  static constexpr double kFileBandVoxels = 2e7;
  /// The signed distance (mm, negative inside) to the stock's surface, the 0.5 iso-surface of
  /// the fractions, at each voxel centre within 3 voxels of it: stock.vdb's grid "surface".
  std::vector<std::pair<Eigen::Vector3d, double>> surfaceBand() const;
  /// Write removed.vdb: grids "removed" (fraction removed), "step" (int32, first step) and
  /// "mrr" (mm^3/min of that step). Requires captureRemoved(true) before the removals. Where
  /// the removed voxels' three values exceed `values` (removedFileFactor), 2, 4 or 8 times
  /// coarser, as the dexel run's.
  void writeRemovedVdb(const std::string& path, double values = kFileBandVoxels) const;
  /// Voxels the removal's capture holds (removed.vdb's at the stock's cell; 0 without it).
  std::size_t removedVoxels() const;
  /// The stock's surface (the 0.5 iso-surface of the fractions, outward normals) with at most
  /// about `maxTriangles` triangles: when the stock's own grid would give more, the fractions
  /// are averaged over blocks of 2, 4 or 8 voxels a side (at most 8: beyond that the budget is
  /// exceeded); nearly flat cells are merged (OpenVDB's adaptive meshing). `maxTriangles` 0:
  /// every voxel's surface, nothing merged. `cellSize` gets the cell of the grid meshed, mm:
  /// the mesh lies within about one such cell of the stock's surface.
  TriangleMesh viewMesh(std::size_t maxTriangles, double* cellSize = nullptr) const;

 private:
  struct Impl;
  friend class VoxelReader;
  explicit VoxelStock(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace engage
