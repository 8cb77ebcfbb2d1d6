#pragma once
/// \file SimulateCommand.h
/// `engage simulate PROGRAM --tool ... --stock ...`: steps.csv, summary.json, removed.vdb,
/// stock.vdb and stock.stl in --out.

#include <CLI/CLI.hpp>

#include <functional>

namespace engage::app {

/// Register the `simulate` subcommand; see AnalyzeCommand.h for `run`.
void addSimulateCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
