#pragma once
/// \file Resolution.h
/// The default cell of a job (the voxel size or the dexel ray spacing; the step is 2.5 cells):
/// a twentieth of the diameter the program's tools engage at the depths they cut to, not of
/// their nominal diameter. A 60 deg V-bit of 3.175 mm engraving 0.07 mm deep engages 0.081 mm:
/// at a twentieth of 3.175 mm the groove is half a cell wide and its volume 74 % off; at a
/// twentieth of 0.081 mm it is within 0.1 %. The finer cell is bounded by what the stock may
/// hold (kStockBudgetBytes) and by the steps the run may take (kStepBudget), never coarser than
/// the nominal D/20, and the choice says which of these set it.

#include "cutters/AptCutter.h"
#include "engine/gcode/Toolpath.h"
#include "engine/sim/Simulation.h"
#include "engine/units/Quantity.h"

#include <optional>
#include <string>
#include <vector>

namespace engage {

/// What set a job's default cell.
enum class CellLimit {
  Engaged,  ///< a twentieth of the engaged diameter
  Nominal,  ///< a twentieth of the nominal diameter (no cut below the stock's top known)
  Memory,   ///< the finest cell whose stock fits kStockBudgetBytes
  Steps,    ///< the finest cell whose run fits kStepBudget steps
};

/// The engagement a job's grid follows: the tool that engages the narrowest at the program's
/// depths.
struct ProgramEngagement {
  int tool = 0;          ///< its number (-1: the --tool cutter of every move)
  double nominal = 0.0;  ///< its diameter D (2 r, the APT radius), mm
  double engaged = 0.0;  ///< the diameter it engages at `depth`, mm (nominal when unknown)
  double depth = 0.0;    ///< its cutting moves' depth below the stock's top (length median), mm
  bool known = false;    ///< a cut below the stock's top was found
};

struct CellChoice {
  double cell = 0.0;  ///< mm
  CellLimit limit = CellLimit::Nominal;
  ProgramEngagement engagement;
};

/// The stock memory (its model's memoryBound) the default cell may ask for: 2 GB, the same on
/// every machine so that a job gives the same numbers everywhere.
constexpr double kStockBudgetBytes = 2e9;
/// The steps (at 2.5 cells each) the default cell may make the program take.
constexpr double kStepBudget = 1e6;

/// The engagement of `path` in a stock whose top is `stockTop` (mm): for each tool, the depth
/// below the top of its feed moves' lowest tip points on the part (through the machine's
/// kinematics and a tilted work plane), the median weighted by their length, and the
/// diameter its profile reaches at that depth (AptCutter::maxRadiusBelow); the tool of the
/// smallest such diameter. Without a cut below the top: the smallest cutter, nominal.
ProgramEngagement programEngagement(const Toolpath& path, const CutterSet& cutters,
                                    std::optional<double> stockTop);

/// Boxes (mm) that hold everything the program's tools sweep below the top of `stock`, clipped
/// to it: each move in pieces no longer than the tool is wide there (arcs in pieces of at most
/// 10 deg), each piece's box widened by the tool's radius at the piece's depth and reaching up
/// to the stock's top. A sparse stock holds leaves only there (VoxelStock::memoryBound). On a
/// machine with rotary kinematics, the whole stock.
std::vector<Box3> programReach(const Toolpath& path, const CutterSet& cutters, const Box3& stock);

/// The stock models a job holds at once (its own, and the other one with --cross-check).
struct StockModels {
  bool voxel = false;
  bool dexel = false;
};

/// The default cell for a stock of bounds `box` (mm; none: unknown) held in `models`: a
/// twentieth of the engaged diameter, coarser only as far as the budgets need, never coarser
/// than a twentieth of the nominal one. `fixedStep` (mm, 0: the default 2.5 cells) leaves the
/// step count alone. `boxStock`: the stock is that box, whose voxels are held only where the
/// program cuts (VoxelStock::memoryBound over programReach); otherwise (a mesh or a .vdb, its
/// bounds) every voxel of the bounds counts, as their reading checks.
CellChoice defaultCell(const Toolpath& path, const CutterSet& cutters,
                       const std::optional<Box3>& box, StockModels models, double fixedStep,
                       bool boxStock = true);

/// One line for the user: the cell and why, e.g. "0.00404 mm: a twentieth of the 0.0808 mm
/// tool 1 engages at 0.07 mm deep (nominal 3.175 mm)", lengths in `units`.
std::string describeCell(const CellChoice& choice, UnitSystem units);

}  // namespace engage
