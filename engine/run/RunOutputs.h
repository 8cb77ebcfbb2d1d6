#pragma once
/// \file RunOutputs.h
/// All the files of a run in its output folder, each by its own writer: steps.csv
/// (StepsTable.h), summary.json (Summary.h), the re-fed program (RefedProgram.h), the plots
/// (engine/report/Plots.h, drawn by gnuplot from steps.csv) and the stock files
/// (StockFiles.h).

#include "engine/run/Pipeline.h"
#include "engine/run/Summary.h"

#include <filesystem>

namespace engage {

/// Write every output of `result` into `dir` (which exists). A plot that cannot be drawn is a
/// warning on stderr, not an error; any other failure throws Error naming the file.
WrittenOutputs writeRunOutputs(const RunResult& result, const std::filesystem::path& dir);

/// A run and the files it wrote.
struct CompletedRun {
  RunResult result;
  WrittenOutputs written;
};

/// The whole run of a job into its folder job.out: prepareRun (every input checked), the
/// folder made and checked before any work, executeRun with progress on a terminal (unless
/// job.quiet), writeRunOutputs. A run that fails removes the folders it made. Throws Error.
CompletedRun runIntoFolder(Job job);

}  // namespace engage
