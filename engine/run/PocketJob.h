#pragma once
/// \file PocketJob.h
/// `engage pocket`'s job: a contour-parallel pocket program (engine/cam/Pocket.h) from a
/// boundary given as G-code (closed loops of G1/G2/G3 in XY; the first loop the pocket, loops
/// inside it islands), with the options as typed.

#include <cstddef>
#include <string>
#include <vector>

namespace engage {

/// The options of `engage pocket`, as typed.
struct PocketJobOptions {
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
PocketProgram makePocketProgram(const PocketJobOptions& options);

/// Write the program to options.output (its folder made when missing; nothing is left if
/// writing fails) and return the lines to print. Throws Error.
std::string writePocketJob(const PocketJobOptions& options);

}  // namespace engage
