#pragma once
/// \file StockFiles.h
/// The stock files of a run: removed.vdb (grids "removed", "step", "mrr": the material each
/// step took), stock.vdb (the final stock as volume fractions and a surface level set) and
/// stock.stl (its surface as a mesh, mm). A dexel run writes the same files from its rays.

#include "engine/run/Pipeline.h"

#include <cstddef>
#include <filesystem>

namespace engage {

/// Write the three files into `dir`; returns the open edges of stock.stl (0: closed). Nothing
/// is written without a stock. Throws Error naming a file that cannot be written.
std::size_t writeStockFiles(const RunResult& result, const std::filesystem::path& dir);

}  // namespace engage
