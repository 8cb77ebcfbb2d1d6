#include "engine/run/StockFiles.h"

#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

namespace engage {

std::size_t writeStockFiles(const RunResult& result, const std::filesystem::path& dir) {
  if (const auto* voxels = dynamic_cast<const VoxelStock*>(result.stock.get())) {
    voxels->writeRemovedVdb((dir / "removed.vdb").string());
    voxels->writeStockVdb((dir / "stock.vdb").string());
    return voxels->writeStl((dir / "stock.stl").string(), result.job.stlTriangles);
  }
  if (const auto* dexels = dynamic_cast<const DexelStock*>(result.stock.get())) {
    // A dexel stock: its removal and its material as voxel fractions, for the same viewers.
    VoxelStock::writeRemovedVdb(*dexels, (dir / "removed.vdb").string());
    const VoxelStock shown = VoxelStock::fromDexels(*dexels);
    shown.writeStockVdb((dir / "stock.vdb").string());
    return shown.writeStl((dir / "stock.stl").string(), result.job.stlTriangles);
  }
  return 0;
}

void writeStockVdb(const RunResult& result, const std::filesystem::path& dir) {
  const std::string path = (dir / "stock.vdb").string();
  if (const auto* voxels = dynamic_cast<const VoxelStock*>(result.stock.get()))
    voxels->writeStockVdb(path);
  else if (const auto* dexels = dynamic_cast<const DexelStock*>(result.stock.get()))
    VoxelStock::fromDexels(*dexels).writeStockVdb(path);
}

}  // namespace engage
