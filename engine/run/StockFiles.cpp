#include "engine/run/StockFiles.h"

#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

#include <tbb/task_group.h>

namespace engage {

StockView::StockView(const RunResult& result) : result_(result) {}
StockView::~StockView() = default;

const VoxelStock* StockView::voxels() const {
  if (const auto* voxels = dynamic_cast<const VoxelStock*>(result_.stock.get())) return voxels;
  const auto* dexels = dynamic_cast<const DexelStock*>(result_.stock.get());
  if (!dexels) return nullptr;
  if (!converted_) converted_ = std::make_unique<VoxelStock>(VoxelStock::fromDexels(*dexels));
  return converted_.get();
}

std::size_t writeStockFiles(const RunResult& result, const StockView& view,
                            const std::filesystem::path& dir,
                            const std::function<void(const VoxelStock&)>& alongside) {
  // The files, and `alongside`, are independent of one another: each a task, run side by side
  // where there are cores for it (one core runs them one after another, as before).
  tbb::task_group tasks;
  // A dexel stock: its removal from its own record, its material as voxel fractions, for the
  // same viewers.
  const auto* dexels = dynamic_cast<const DexelStock*>(result.stock.get());
  if (dexels)
    tasks.run([&] { VoxelStock::writeRemovedVdb(*dexels, (dir / "removed.vdb").string()); });
  const VoxelStock* shown = nullptr;
  try {
    shown = view.voxels();  // (a dexel stock converted while its removed.vdb is written)
  } catch (...) {
    tasks.wait();  // (removed.vdb's own failure, if it failed too, is the one thrown)
    throw;
  }
  if (!shown) {
    tasks.wait();
    return 0;
  }
  if (!dexels) tasks.run([&] { shown->writeRemovedVdb((dir / "removed.vdb").string()); });
  tasks.run([&] { shown->writeStockVdb((dir / "stock.vdb").string()); });
  std::size_t openEdges = 0;
  tasks.run(
      [&] { openEdges = shown->writeStl((dir / "stock.stl").string(), result.job.stlTriangles); });
  if (alongside) tasks.run([&] { alongside(*shown); });
  tasks.wait();
  return openEdges;
}

void writeStockVdb(const StockView& view, const std::filesystem::path& dir) {
  if (const VoxelStock* shown = view.voxels()) shown->writeStockVdb((dir / "stock.vdb").string());
}

}  // namespace engage
