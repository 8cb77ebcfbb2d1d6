#pragma once
/// \file Simulation.h
/// The simulation loop: a tool path cut into steps (no longer than L; arcs as arc pieces),
/// each step's swept cutter removed from the stock, and per step the measured removal and
/// engagement beside the analytic model of the same step (paper form and exact form).

#include "cutters/AptCutter.h"
#include "engine/gcode/Toolpath.h"
#include "engine/model/EngagementModel.h"
#include "engine/physics/CuttingForces.h"
#include "engine/physics/Material.h"
#include "engine/sim/ToolPoses.h"
#include "stock/Stock.h"

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace engage {

/// Cutting physics per step (engine/physics): what the material and the teeth are.
struct PhysicsOptions {
  Material material;
  double helix = 0.5235987755982988;  ///< the flutes' helix angle, rad (30 deg)
  /// Spindle speed, rpm, for moves where the program's spindle is stopped or has no S (+: M3).
  double spindleRpm = 0.0;
};

/// Settings of one simulation.
struct SimulationOptions {
  /// Step length L, mm (0: 2.5 voxels).
  double stepLength = 0.0;
  /// Stepover and depth for the analytic model; unset: the step's measured width and depth.
  std::optional<double> stepover;
  std::optional<double> depth;
  /// Called now and then with (steps done, steps in all).
  std::function<void(std::size_t, std::size_t)> progress;
  /// The most steps a run may make (each record takes about 150 bytes): more is refused up
  /// front, naming the longest move (a move of 1e9 mm, a helix of 100000 turns).
  std::size_t maxSteps = 5'000'000;
  /// Record each step's removal time in SimulationResult::stepSeconds (benchmarks; kept out
  /// of the reports, which must not change from run to run).
  bool timeSteps = false;
  /// Measure each cutting step's edge contact and compute its chip, forces, torque and
  /// power (SimulationResult::loads).
  std::optional<PhysicsOptions> physics;
};

/// The cutters of a run: the cutter of each tool number the moves name (Move::tool), and the
/// one for numbers not listed (the single cutter of a one-tool run).
/// A part of a tool above its flutes that must never meet material: the shank, a segment of
/// the holder. Its shape is a cutter profile whose tip sits `zOffset` above the tool's tip.
struct ToolPart {
  std::string name;  ///< "shank" or "holder"
  AptCutter shape;
  double zOffset = 0.0;  ///< mm
};

struct CutterSet {
  std::map<int, AptCutter> byTool;
  std::optional<AptCutter> fallback;
  /// The non-cutting parts of each tool (none when the library does not describe them), and
  /// those of the fallback cutter (--tool's --stickout, --shank-diameter, --holder).
  std::map<int, std::vector<ToolPart>> partsByTool;
  std::vector<ToolPart> fallbackParts;
  /// The parts of tool `tool`: its own, else (no cutter of its own) the fallback's.
  const std::vector<ToolPart>& partsOf(int tool) const;
  /// The cutter of tool `tool`. Throws ParameterError when there is none.
  const AptCutter& of(int tool) const;
  /// The smallest radius among them, mm.
  double smallestRadius() const;
};

/// One step's record. Lengths mm, feeds mm/min, volumes mm^3, rates mm^3/min, times s.
/// (The doubles first, the small fields together at the end: no padding between them. One
/// record per step is held for the whole run.)
struct StepRecord {
  std::size_t move = 0;       ///< index of the move in the tool path
  double t0 = 0.0, t1 = 1.0;  ///< the step's piece of its move (fractions; stepPath)
  double arcLength = 0.0;     ///< cumulative path length at the step's end
  double length = 0.0;        ///< step length
  Eigen::Vector3d end{0.0, 0.0, 0.0};
  double feed = 0.0;  ///< programmed feed (0 for rapids)
  double dt = 0.0;    ///< length / feed (0 for rapids)
  double removed = 0.0;
  double mrr = 0.0;  ///< removed / dt (0 for rapids)
  /// From the step's contact (engine/physics/Engagement.h): the radial depth of cut a_e, mm
  /// (on an arc the stepover beside the wall; a plunge: the diameter engaged at its depth);
  /// the axial depth a_p, mm; the engaged angle, exit minus entry, rad.
  double width = 0.0;
  double depth = 0.0;
  double engagementRad = 0.0;
  double curvature = 0.0;  ///< signed, 1/mm: + turning left (counter-clockwise seen from +Z)
  double mrrExact = 0.0;   ///< analytic, exact form; NaN where the model has no steady state
  double mrrPaper = 0.0;   ///< analytic, the paper's Eq 6/15/16
  int line = 0;            ///< source line
  int tool = 0;            ///< the tool in the spindle (its number; 0 before any change)
  /// Cells (voxels, or rays) that lost material (a step's count fits: 2^31 cells of the
  /// finest grid would take more memory than a machine has).
  std::int32_t voxelsChanged = 0;
  MoveKind kind = MoveKind::Line;
  PathSide side = PathSide::Straight;
};

/// A step is in steady state when its rate (MRR, or another load) differs from both its
/// neighbours' on the same move by at most this share.
constexpr double kSteadyChange = 0.02;

/// Whether a step of rate `at` (> 0) between neighbours of rates `before` and `after` (on the
/// same move) is in steady state. The agreement of measured and analytic MRR and the schedule's
/// automatic target both take their steps by this test.
inline bool steadyBetween(double before, double at, double after) {
  return std::abs(before / at - 1.0) <= kSteadyChange &&
         std::abs(after / at - 1.0) <= kSteadyChange;
}

/// Measured against analytic on one class of steady-state steps.
struct Agreement {
  std::size_t steps = 0;
  double meanRelative = 0.0;  ///< mean of |measured / analytic - 1|
  double maxRelative = 0.0;
};

/// A place where measurement and model differ.
struct Difference {
  std::size_t step = 0;
  int line = 0;
  double measured = 0.0;
  double analytic = 0.0;
  double relative = 0.0;  ///< measured / analytic - 1
};

/// The whole run.
/// Material met by what must not cut, over consecutive steps of one move: a rapid, or a
/// tool's shank or holder (ToolPart). Volumes mm^3.
struct Collision {
  std::size_t move = 0;
  int line = 0;
  int tool = 0;
  std::string part;  ///< "rapid", "shank", "holder"
  std::size_t firstStep = 0, lastStep = 0;
  /// Material met: what a rapid removed over the steps; for a shank or holder, the most
  /// inside its sweep at one step (sampled at voxel / ray centres: to a layer of voxels).
  double volume = 0.0;
};

struct SimulationResult {
  std::vector<StepRecord> steps;
  std::vector<Collision> collisions;  ///< in step order
  double volumeBefore = 0.0;
  double volumeAfter = 0.0;
  double removed = 0.0;
  double seconds = 0.0;      ///< wall time of the removal loop
  double cuttingTime = 0.0;  ///< sum of dt over feed moves, s (no acceleration)
  long voxelsChanged = 0;
  double rapidRemoved = 0.0;            ///< material hit by rapids, mm^3 (a crash in real life);
                                        ///< steps below half a voxel are not counted (rounding)
  Agreement straight, concave, convex;  ///< exact form
  Agreement straightPaper, concavePaper, convexPaper;
  std::vector<Difference> largest;  ///< the steady-state steps that differ most (exact form)
  std::vector<double> stepSeconds;  ///< per step, when SimulationOptions::timeSteps
  /// Per step, with SimulationOptions::physics: the load at the programmed feed (zero for
  /// rapids and air; NaN where the model does not apply: plunges, which load the end face,
  /// and cuts with the spindle stopped).
  std::vector<StepLoad> loads;
  /// Cutting steps without horizontal motion of a cutter without a flat end (no load model).
  std::size_t plungeSteps = 0;
  std::size_t stoppedSteps = 0;  ///< cutting steps with no spindle speed (no load model)
  /// Cutting steps of a tool whose axis lies off the part's axes or turns: the paper's model
  /// (a tool square to the faces it cuts, feeding across its axis) does not apply; their
  /// mrrExact and mrrPaper are NaN, outside the comparison.
  std::size_t obliqueSteps = 0;
};

/// Ask every simulation of this process to stop at its next step: simulate() and
/// analyticSteps() then throw Interrupted, and the run unwinds like a failed one (its staging
/// and new folders removed). Async-signal-safe (a lock-free atomic store), for the command
/// line's SIGINT and SIGTERM handlers.
void requestStop() noexcept;
/// Whether requestStop was called (the writers of a run check it before they publish).
bool stopRequested() noexcept;

/// Check that cutting `path` into steps no longer than `stepLength` (mm) makes at most
/// `maxSteps` steps. Throws ParameterError naming the count and the longest move.
void checkStepCount(const Toolpath& path, double stepLength, std::size_t maxSteps);

/// The steps `path` makes at steps of at most `stepLength` (mm): each move of some length
/// in whole steps, at least one (on a rotary machine, of the tip's travel on the part: the
/// simulation's steps also bound the rest of the tool's travel, and can be more).
double stepCount(const Toolpath& path, double stepLength);

/// Run a tool path through a stock, each step with the cutter of the tool in the spindle.
/// Throws Error from the model or the stock.
SimulationResult simulate(const Toolpath& path, const CutterSet& cutters, Stock& stock,
                          const SimulationOptions& options);
/// The same with one cutter for every move.
SimulationResult simulate(const Toolpath& path, const AptCutter& cutter, Stock& stock,
                          const SimulationOptions& options);

/// The same steps without a stock (the paper's setting): every feed step is taken to cut at
/// the nominal options.stepover and options.depth (both required), with the stock on the
/// right of the path (climb milling with an M3 spindle) or on its left, which decides
/// concave or convex; the analytic MRR in both forms per step, the measured fields NaN.
/// Steps no longer than options.stepLength (0: a tenth of the smallest cutter's diameter).
SimulationResult analyticSteps(const Toolpath& path, const CutterSet& cutters,
                               const SimulationOptions& options, bool stockOnRight = true);
SimulationResult analyticSteps(const Toolpath& path, const AptCutter& cutter,
                               const SimulationOptions& options, bool stockOnRight = true);

}  // namespace engage
