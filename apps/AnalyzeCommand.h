#pragma once
/// \file AnalyzeCommand.h
/// `engage analyze`: the analytic engagement model (paper Eq 1-24) from the command line,
/// and `--sweep-radius`, the paper's Fig 8 table as CSV.

#include <CLI/CLI.hpp>

#include <functional>

namespace engage::app {

/// Register the `analyze` subcommand; its run function is stored in `run` and called by main
/// after parsing (so that errors are reported in one place).
void addAnalyzeCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
