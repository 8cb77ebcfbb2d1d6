#include "engine/run/StockFiles.h"

#include "stock/DexelMesh.h"
#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <exception>
#include <functional>

namespace engage {

StockView::StockView(const RunResult& result, std::vector<std::size_t> budgets)
    : result_(result), budgets_(std::move(budgets)) {}
StockView::~StockView() = default;

const DexelStock* StockView::dexels() const {
  return dynamic_cast<const DexelStock*>(result_.stock.get());
}

const VoxelStock* StockView::voxels() const {
  if (const auto* voxels = dynamic_cast<const VoxelStock*>(result_.stock.get())) return voxels;
  const auto* dexels = dynamic_cast<const DexelStock*>(result_.stock.get());
  if (!dexels) return nullptr;
  std::call_once(convert_, [&] {
    converted_ = std::make_unique<VoxelStock>(VoxelStock::fromDexels(*dexels));
  });
  return converted_.get();
}

TriangleMesh StockView::surface(std::size_t maxTriangles, double* cell) const {
  if (const DexelStock* d = dexels()) {
    bool heightfield = true;  // (until the budgets' meshes find it is not)
    const auto asked = std::find(budgets_.begin(), budgets_.end(), maxTriangles);
    if (asked != budgets_.end()) {
      std::call_once(mesh_, [&] {
        meshes_ = heightfieldMeshes(*d, budgets_, &cells_);
        taken_.assign(budgets_.size(), false);
      });
      heightfield = meshes_.has_value();
      const auto n = static_cast<std::size_t>(asked - budgets_.begin());
      std::lock_guard<std::mutex> lock(take_);
      if (heightfield && !taken_[n]) {
        taken_[n] = true;
        if (cell) *cell = cells_[n];
        return std::move((*meshes_)[n]);
      }
    }
    if (heightfield)
      if (std::optional<TriangleMesh> mesh = heightfieldMesh(*d, maxTriangles, cell))
        return std::move(*mesh);
  }
  const VoxelStock* v = voxels();
  if (!v) return {};
  return v->viewMesh(maxTriangles, cell);
}

std::size_t writeStockFiles(const RunResult& result, const StockView& view,
                            const std::filesystem::path& dir,
                            const std::function<void()>& alongside) {
  // The files, and `alongside`, are independent of one another: each a task, run side by side
  // where there are cores for it (one core runs them one after another, as before). A task
  // keeps its own failure: one thrown into the group would cancel the group, and with it the
  // parallel loops inside the tasks still running, which would then go on with half-computed
  // results (a report's surface from a cancelled loop grew without end on a full disk). After
  // all have ended, the failure of the first task in this order is thrown: removed.vdb,
  // stock.vdb, stock.stl, alongside.
  tbb::task_group tasks;
  std::array<std::exception_ptr, 4> failed;
  auto run = [&](std::size_t slot, std::function<void()> task) {
    tasks.run([&failed, slot, task = std::move(task)] {
      try {
        task();
      } catch (...) {
        failed[slot] = std::current_exception();
      }
    });
  };
  auto finish = [&] {
    tasks.wait();
    for (const std::exception_ptr& e : failed)
      if (e) std::rethrow_exception(e);
  };
  // Nothing without a stock. A dexel stock's removal from its own record; its material as
  // voxel fractions (writeStockVdb), converted by whichever task asks first.
  if (!result.stock) return 0;
  if (const DexelStock* dexels = view.dexels())
    run(0, [&, dexels] { VoxelStock::writeRemovedVdb(*dexels, (dir / "removed.vdb").string()); });
  else
    run(0, [&] { view.voxels()->writeRemovedVdb((dir / "removed.vdb").string()); });
  run(1, [&] { writeStockVdb(view, dir); });
  std::size_t openEdges = 0;
  run(2, [&] {
    const TriangleMesh mesh = view.surface(result.job.stlTriangles);
    writeStl(mesh, (dir / "stock.stl").string());
    openEdges = boundaryEdgeCount(mesh);
  });
  if (alongside) run(3, alongside);
  finish();
  return openEdges;
}

void writeStockVdb(const StockView& view, const std::filesystem::path& dir) {
  // A dexel stock's grid too large for its surface at the rays' cell: straight from the rays.
  if (const DexelStock* dexels = view.dexels())
    if (const int factor = VoxelStock::dexelFileFactor(*dexels); factor > 1)
      return VoxelStock::writeDexelStockVdbAt(*dexels, (dir / "stock.vdb").string(), factor);
  if (const VoxelStock* shown = view.voxels())
    shown->writeStockVdb((dir / "stock.vdb").string(), view.dexels());
}

}  // namespace engage
