#pragma once
/// \file Analysis.h
/// `engage analyze`: the analytic model of a steady-state pass (paper Eq 1-24) as a table or
/// JSON, and the sweep of Fig 8 (MRR against path radius and corner radius) as CSV.

#include "engine/run/CutterOptions.h"

#include <string>

namespace engage {

/// The options of an analysis, as typed.
struct AnalyzeOptions {
  ToolOptions tool;
  std::string stepover;
  std::string depth;
  std::string feed;
  std::string pathRadius;
  std::string side;
  std::string targetMrr;
  std::string specificEnergy;
  std::string spindle;
  std::string transition;
  std::string units;
  bool json = false;
  bool sweep = false;
};

/// The report of one analysis: a table, JSON (o.json) or the Fig 8 sweep as CSV (o.sweep).
/// Throws Error naming the bad option.
std::string analyzeReport(const AnalyzeOptions& options);

}  // namespace engage
