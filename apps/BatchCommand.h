#pragma once
/// \file BatchCommand.h
/// `engage batch MANIFEST --out DIR [--shard i/N] [--workers W]`: many simulate/schedule jobs
/// from a JSON manifest, side by side on one machine, or one shard of them per node of a
/// cluster job array; each job in its own folder DIR/jobs/NAME with its record job.json,
/// written last (a rerun skips jobs whose record is there and whose options are unchanged).
/// `engage merge MANIFEST --out DIR` joins the records into DIR/batch.csv and batch.json.

#include <CLI/CLI.hpp>

#include <functional>

namespace engage::app {

/// Register the `batch` and `merge` subcommands; see AnalyzeCommand.h for `run`.
void addBatchCommands(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
