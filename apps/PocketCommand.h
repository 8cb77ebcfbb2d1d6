#pragma once
/// \file PocketCommand.h
/// `engage pocket BOUNDARY --diameter D --stepover S --depth D --feed F -o PROGRAM`: a
/// contour-parallel pocket program (engine/cam/Pocket.h) from a boundary given as G-code
/// (closed loops of G1/G2/G3 in XY; the first loop the pocket, loops inside it islands).

#include <CLI/CLI.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace engage::app {

/// The options of `engage pocket`, as typed.
struct PocketCommandOptions {
  std::string boundary;
  std::string output;
  std::string diameter;
  std::string stepover;
  std::string depth;
  std::string stepDown;
  std::string top = "0";
  std::string safeZ;
  std::string feed;
  std::string plungeFeed;
  std::string tolerance;
  std::string units;
  bool conventional = false;
};

/// A pocket program and what it holds.
struct PocketProgram {
  std::string text;
  std::vector<int> ringLines;  ///< 1-based line of each ring's first element, in cutting order
  std::size_t rings = 0, arcs = 0, lines = 0;
  int levels = 0;
  bool sharpCorners = false;
  bool cornerWarning = false;  ///< sharp corners with a stepover above r sqrt 2
};

/// Make the program of `engage pocket` (nothing is written). Throws Error.
PocketProgram makePocketProgram(const PocketCommandOptions& options);

/// Register the `pocket` subcommand; see AnalyzeCommand.h for `run`.
void addPocketCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
