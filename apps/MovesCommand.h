#pragma once
/// \file MovesCommand.h
/// `engage moves PROGRAM`: the interpreted moves as CSV
/// (line,kind,x,y,z,cx,cy,cz,plane,turns,feed_mm_min; mm, machine coordinates).

#include <CLI/CLI.hpp>

#include <functional>

namespace engage::app {

/// Register the `moves` subcommand; see AnalyzeCommand.h for `run`.
void addMovesCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
