#pragma once
/// \file SimulateCommand.h
/// `engage simulate PROGRAM --tool ... --stock ...` and `engage schedule ...`: the options of
/// OptionTable.h mapped onto a job, run by the pipeline (engine/run/Pipeline.h), its files
/// written by engine/run/RunOutputs.h into --out.

#include <CLI/CLI.hpp>

#include <functional>

namespace engage::app {

/// Register the `simulate` and `schedule` subcommands; see AnalyzeCommand.h for `run`.
void addSimulateCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
