#pragma once
/// \file PartCheck.h
/// Did the program make the part (--part): the final stock against the part's surface
/// (stock/Part.h), gathered into regions of neighbouring samples: gouges (the part's material
/// removed deeper than --tolerance) and leftovers (material left thicker than --allowance),
/// each with its depth or thickness, area and volume, and for a gouge the steps (and so the
/// lines) whose swept surface made its floor (engine/report/SurfaceSteps.h). Written as
/// gouges.csv and leftovers.csv (largest volume first) and the deviation grid (deviation.vdb).

#include "cutters/Sweep.h"
#include "engine/gcode/Toolpath.h"
#include "engine/sim/Simulation.h"
#include "engine/units/Quantity.h"
#include "stock/Part.h"

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace engage {

/// What --part asks: the part, and the deviations that count.
struct PartSpec {
  std::string file;        ///< as given ("" for none)
  double tolerance = 0.0;  ///< a gouge counts beyond this depth, mm
  double allowance = 0.0;  ///< a leftover counts beyond this thickness, mm
  bool given() const { return !file.empty(); }
};

/// Neighbouring samples of one kind beyond the tolerance or the allowance.
struct DeviationRegion {
  bool gouge = false;
  double extreme = 0.0;         ///< mm: a gouge's depth, a leftover's thickness
  double area = 0.0;            ///< of the part's surface, mm^2
  double volume = 0.0;          ///< mm^3
  Eigen::Vector3d at{0, 0, 0};  ///< the part's surface point of the extreme
  Box3 box;                     ///< of its samples
  /// Gouges: the steps whose swept surface made its floor, with the area of the floor each
  /// made (mm^2), largest first.
  std::vector<std::pair<std::size_t, double>> steps;
};

/// The final stock against the part.
struct PartCheck {
  bool done = false;
  PartSpec spec;
  double spacing = 0.0;  ///< the samples' size, mm
  std::size_t samples = 0;
  double area = 0.0;                       ///< the part's surface, mm^2
  double partVolume = 0.0;                 ///< mm^3
  std::vector<DeviationRegion> gouges;     ///< largest volume first
  std::vector<DeviationRegion> leftovers;  ///< largest volume first
  /// The part's material that no step removed and the stock does not hold (a stock smaller
  /// than the part, or the stock's reading at its own uncut edges): not gouges.
  std::vector<DeviationRegion> missing;
  /// The stock's surface where the samples met it within their share, and the deviation there
  /// (mm, SampleDeviation): deviation.vdb.
  std::vector<Eigen::Vector3f> stockPoints;
  std::vector<float> deviation;
  double seconds = 0.0;
  /// The deepest gouge, mm (0 without one).
  double deepestGouge() const;
  /// The thickest leftover, mm (0 without one).
  double thickestLeftover() const;
};

/// Most samples a check takes: the spacing grows beyond the stock's cell to keep within it
/// (about 100 bytes each while measured).
constexpr std::size_t kMaxPartSamples = 4'000'000;

/// The final `stock` of a run (`path`, `steps`, `cutters`) against `part`, read at samples of
/// the stock's cell; `holds`: the box stock's box (measureDeviation). Throws Interrupted when
/// a stop was asked for.
PartCheck checkPart(const Part& part, const PartSpec& spec, const Stock& stock,
                    const Toolpath& path, const std::vector<StepRecord>& steps,
                    const CutterSet& cutters, const Box3* holds = nullptr);

/// A line that cut a gouge's floor: its file (an index into Toolpath::files), its line, the
/// floor area its steps cut (mm^2) and those steps.
struct GougeLine {
  int file = 0;
  int line = 0;
  double area = 0.0;
  std::vector<std::size_t> steps;
};

/// The lines of a gouge's steps, by the floor area they cut, largest first.
std::vector<GougeLine> gougeLines(const DeviationRegion& gouge, const Toolpath& path,
                                  const std::vector<StepRecord>& steps);

/// gouges.csv or leftovers.csv: one row per region, largest volume first, in `units` (the unit
/// in each column name); gouges name the lines that cut their floor ("file:line", by the area
/// they cut, largest first).
std::string regionTable(const PartCheck& check, bool gouges, const Toolpath& path,
                        const std::vector<StepRecord>& steps, UnitSystem units);

}  // namespace engage
