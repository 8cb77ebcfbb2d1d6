#pragma once
/// \file StockFiles.h
/// The stock files of a run: removed.vdb (grids "removed", "step", "mrr": the material each
/// step took), stock.vdb (the final stock as volume fractions, a surface level set and the planes
/// of the partial voxels, which `--stock stock.vdb` goes on from) and stock.stl (its surface as a
/// mesh, mm). A dexel run writes the same files from its rays.

#include "engine/run/Pipeline.h"

#include <cstddef>
#include <filesystem>

namespace engage {

/// Write the three files into `dir`; returns the open edges of stock.stl (0: closed). Nothing
/// is written without a stock. Throws Error naming a file that cannot be written.
std::size_t writeStockFiles(const RunResult& result, const std::filesystem::path& dir);

/// Write stock.vdb alone into `dir` (a batch job whose stock a later job takes, with outputs
/// other than all). Nothing is written without a stock.
void writeStockVdb(const RunResult& result, const std::filesystem::path& dir);

}  // namespace engage
