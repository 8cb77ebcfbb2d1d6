#include "engine/run/StockFiles.h"

#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

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
                            const std::filesystem::path& dir) {
  const VoxelStock* shown = view.voxels();
  if (!shown) return 0;
  // A dexel stock: its removal from its own record, its material as voxel fractions, for the
  // same viewers.
  if (const auto* dexels = dynamic_cast<const DexelStock*>(result.stock.get()))
    VoxelStock::writeRemovedVdb(*dexels, (dir / "removed.vdb").string());
  else
    shown->writeRemovedVdb((dir / "removed.vdb").string());
  shown->writeStockVdb((dir / "stock.vdb").string());
  return shown->writeStl((dir / "stock.stl").string(), result.job.stlTriangles);
}

void writeStockVdb(const StockView& view, const std::filesystem::path& dir) {
  if (const VoxelStock* shown = view.voxels()) shown->writeStockVdb((dir / "stock.vdb").string());
}

}  // namespace engage
