#pragma once
/// \file StockFiles.h
/// The stock files of a run: removed.vdb (grids "removed", "step", "mrr": the material each
/// step took), stock.vdb (the final stock as volume fractions, a surface level set and the planes
/// of the partial voxels, which `--stock stock.vdb` goes on from) and stock.stl (its surface as a
/// mesh, mm). A dexel run writes the same files from its rays.

#include "engine/run/Pipeline.h"

#include "stock/TriangleMesh.h"

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace engage {

class DexelStock;
class VoxelStock;

/// A run's final stock as voxels, for the files and the report's 3D view that show it: the
/// voxel stock itself, or a dexel stock's rays as voxel fractions, converted on first use (by
/// whichever thread asks first) and once for all the files and the report.
class StockView {
 public:
  /// `budgets`: the surfaces (triangle budgets) that will be asked for, made together where
  /// they can be (a dexel heightfield's rays read once for all).
  explicit StockView(const RunResult& result, std::vector<std::size_t> budgets = {});
  ~StockView();
  StockView(const StockView&) = delete;
  StockView& operator=(const StockView&) = delete;
  /// nullptr without a stock.
  const VoxelStock* voxels() const;
  /// The run's dexel stock (nullptr: a voxel stock or none).
  const DexelStock* dexels() const;
  /// The stock's surface within about `maxTriangles` triangles (0: every cell), `cell` its
  /// vertices' spacing: a dexel stock's straight from its rays where it is a heightfield
  /// (stock/DexelMesh.h: a tenth of a second where meshing its voxels takes seconds), else
  /// the voxels' (VoxelStock::viewMesh; with 0 their full surface). Safe from several
  /// threads. The first call for one of the constructor's budgets makes them all, and each
  /// is handed out once (a second call for it makes it again).
  TriangleMesh surface(std::size_t maxTriangles, double* cell = nullptr) const;

 private:
  const RunResult& result_;
  const std::vector<std::size_t> budgets_;
  mutable std::unique_ptr<VoxelStock> converted_;
  mutable std::once_flag convert_;
  // The budgets' heightfield meshes (none: not a dexel heightfield) and their cells, until
  // taken.
  mutable std::optional<std::vector<TriangleMesh>> meshes_;
  mutable std::vector<double> cells_;
  mutable std::vector<bool> taken_;
  mutable std::once_flag mesh_;
  mutable std::mutex take_;
};

/// Write the three files into `dir`, side by side on the cores there are, with `alongside()`
/// as one more task when given (the report's 3D view); returns the open edges of stock.stl
/// (0: closed). Nothing is written without a stock. Throws Error naming a
/// file that cannot be written.
std::size_t writeStockFiles(const RunResult& result, const StockView& view,
                            const std::filesystem::path& dir,
                            const std::function<void()>& alongside = {});

/// Write stock.vdb alone into `dir` (a batch job whose stock a later job takes, with outputs
/// other than all). Nothing is written without a stock.
void writeStockVdb(const StockView& view, const std::filesystem::path& dir);

}  // namespace engage
