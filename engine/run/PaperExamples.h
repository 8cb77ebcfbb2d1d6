#pragma once
/// \file PaperExamples.h
/// `engage paper`: every example of the paper (Figs 8, 9, 10-12, 13-14) rebuilt from the
/// boundaries in data/paper/ and measured in the voxel stock beside the analytic model:
/// paper.json (every statement as a number), the figures' CSV files and plots, the programs,
/// and each simulation's own outputs, all in inches.

#include <string>

namespace engage {

/// The options of `engage paper`, as typed.
struct PaperOptions {
  std::string out = "out/paper";
  std::string data;  ///< the data/ folder with paper/
  std::string voxel = "0.025in";
  std::string steadyVoxel = "0.05in";
  bool quiet = false;
};

/// Run every example into options.out; returns the lines to print (one per figure, then what
/// was written). Progress on a terminal unless quiet. Throws Error.
std::string runPaper(const PaperOptions& options);

}  // namespace engage
