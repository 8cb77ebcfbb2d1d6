#pragma once
/// \file SimulateCommand.h
/// `engage simulate PROGRAM --tool ... --stock ...`: steps.csv, summary.json, removed.vdb,
/// stock.vdb and stock.stl in --out.

#include "apps/ToolOptions.h"
#include "engine/gcode/Toolpath.h"
#include "engine/schedule/FeedScheduler.h"
#include "engine/sim/Simulation.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace engage::app {

/// The options of one simulate or schedule run, as typed (quantities with their units).
struct SimulateOptions {
  std::string program;
  ToolOptions tool;
  std::string stock;
  std::string voxel;
  std::string step;
  std::string stepover;
  std::string depth;
  std::string out = "out";
  std::string units;
  std::string toolTable;
  bool quiet = false;
  // schedule only
  bool schedule = false;
  std::string targetMrr = "auto";
  std::string feedMin;
  std::string feedMax;
  std::string airFeed;
  std::string accel;
  std::string jerk;
  std::string rapidFeed;
  std::string minChange = "0.05";
  std::string minSegment;
  std::string forceLimit;
  std::string specificEnergy;
  std::string spindle;
  std::string model = "measured";
  /// Without a stock: the side of the path the stock is on, "right" (climb with M3) or "left".
  std::string materialSide;
  std::string stockModel = "voxel";  ///< "voxel" or "dexel"
  bool crossCheck = false;           ///< also run the other stock model and compare per step
  double crossTolerance = 0.03;      ///< relative per-step difference the cross-check allows
  /// Prefix of the progress line on a terminal.
  std::string progressLabel = "simulate";
};

/// What a run made, besides the files in its --out folder.
struct SimulateOutcome {
  Toolpath path;
  SimulationResult sim;
  Schedule plan;  ///< empty unless scheduling
  UnitSystem units = UnitSystem::Metric;
  AptCutter cutter = AptCutter::flat(1.0, 1.0);
  std::string report;  ///< the lines `engage simulate` prints
};

/// Run one simulation (and schedule, when `o.schedule`), writing its outputs into `o.out`.
/// Everything is checked before any output is written. Throws Error.
SimulateOutcome runSimulateJob(const SimulateOptions& o);

/// Register the `simulate` subcommand; see AnalyzeCommand.h for `run`.
void addSimulateCommand(CLI::App& app, std::function<int()>& run);

}  // namespace engage::app
