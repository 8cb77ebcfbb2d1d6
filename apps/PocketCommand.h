#pragma once
/// \file PocketCommand.h
/// `engage pocket BOUNDARY --diameter D --stepover S --depth D --feed F -o PROGRAM`: a
/// contour-parallel pocket program (engine/cam/Pocket.h) from a boundary given as G-code
/// (closed loops of G1/G2/G3 in XY; the first loop the pocket, loops inside it islands).

#include <CLI/CLI.hpp>

#include <functional>

namespace engage::app {

/// Register the `pocket` subcommand; see AnalyzeCommand.h for `run`.
void addPocketCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
