#pragma once
/// \file PaperCommand.h
/// `engage paper --out DIR`: the paper's examples end to end (Kloypayan & Lee, Figs 8, 9,
/// 10-12, 13-14) from the bundled boundaries in data/paper: pocket programs made by `engage
/// pocket`, simulated in the voxel stock beside the analytic model, as CSV files and PNG/SVG
/// plots, and paper.json with each statement of the paper checked by a number.

#include <CLI/CLI.hpp>

#include <functional>

namespace engage::app {

/// Register the `paper` subcommand; see AnalyzeCommand.h for `run`.
void addPaperCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
