#pragma once
/// \file Plots.h
/// Plots of a run, drawn by gnuplot (Debian gnuplot-nox) from the run's steps.csv, as PNG and
/// SVG: the MRR along the path (measured, analytic exact and paper, and after scheduling), the
/// programmed and scheduled feeds, the tangential acceleration with its limit (paper Fig 14c),
/// a top view of the path coloured by MRR, and with the cutting physics the chip thickness,
/// peak force and spindle power along the path.

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace engage {

/// The pictures' width in pixels (their height is half of it).
inline constexpr std::size_t kPlotWidth = 1400;

/// What to plot, in the run's units.
struct PlotSpec {
  std::string folder;  ///< where steps.csv is and the plots go
  /// The table the plots read, in `folder`: steps.csv, or for a long run the steps the
  /// report plots (every bucket's extremes: RunReport.h's reportSteps), so that gnuplot does
  /// not draw half a million points into a 1400-pixel-wide picture.
  std::string data = "steps.csv";
  /// The table the top view reads (a long run's can be longer than `data`).
  std::string topData = "steps.csv";
  std::string length;  ///< column tag of lengths, e.g. "mm"
  std::string feed;    ///< e.g. "mm_min"
  std::string rate;    ///< e.g. "mm3_min"
  std::string lengthLabel, feedLabel, rateLabel, accelerationLabel;  ///< axis units
  std::string accelerationTag;                                       ///< e.g. "mm_s2"
  bool schedule = false;         ///< steps.csv has the scheduled columns
  std::string model = "voxels";  ///< the stock model that measured: voxels or dexels
  double accelerationLimit = 0;  ///< in the plot's units; 0: none drawn
  /// Tool changes: arc length (the plot's units) where each tool starts, and its label ("T2"),
  /// drawn as dashed vertical lines on the plots along the path.
  std::vector<std::pair<double, std::string>> toolChanges;
  /// Cutting physics (steps.csv has h_max, f_peak, power columns): chip.png, force.png,
  /// power.png along the path, before and after scheduling, with the schedule's limits (in
  /// the plot's units; 0: none drawn).
  bool physics = false;
  std::string forceTag, powerTag, forceLabel, powerLabel;
  double maxChip = 0.0, maxForce = 0.0, maxPower = 0.0;
};

/// Draw the plots; returns the files written (without the folder). Throws Error when gnuplot
/// is missing or fails, naming it.
std::vector<std::string> writePlots(const PlotSpec& spec);

/// One curve of a chart: columns `x` and `y` (header names) of a CSV file in the folder.
struct Series {
  std::string file;
  std::string x, y;
  std::string title;
  std::string style = "lines lw 1.5";  ///< gnuplot style, e.g. "lines lw 1 dt 2 lc 1"
};

/// A chart of curves from CSV files, with optional horizontal lines (value, title).
struct Chart {
  std::string name;  ///< file stem: name.png and name.svg
  std::string title, xlabel, ylabel;
  std::vector<Series> series;
  std::vector<std::pair<double, std::string>> lines;
  bool logX = false;
};

/// Draw charts from CSV files in `folder` as PNG and SVG (script `script` kept beside them);
/// returns the files written. Throws Error when gnuplot is missing or fails.
std::vector<std::string> drawCharts(const std::string& folder, const std::vector<Chart>& charts,
                                    const std::string& script);

}  // namespace engage
