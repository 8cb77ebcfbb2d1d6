#pragma once
/// \file Pipeline.h
/// The run of one job: its stocks built and checked (prepareRun: everything that can fail on
/// the input fails here, before any output is made), then the simulation, the cross-check
/// against the other stock model and the schedule with its re-fed program (executeRun). The
/// result holds everything the output writers (RunOutputs.h) and the Python module read.

#include "engine/run/Job.h"
#include "engine/schedule/FeedScheduler.h"
#include "engine/sim/Simulation.h"
#include "stock/Stock.h"

#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace engage {

/// The same steps through the other stock model, compared per step. A step differs when its
/// volumes differ by more than the tolerance of the larger, plus a floor of four cells (steps
/// that remove almost nothing differ by rounding alone).
struct CrossCheck {
  SimulationResult other;              ///< the other model's run
  std::vector<char> differs;           ///< per step: 1 where it differs
  std::vector<std::size_t> differing;  ///< the differing steps, largest gap first
  double worstRelative = 0.0;          ///< largest relative gap above the floor
  double floorVolume = 0.0;            ///< four cells, mm^3
  std::size_t otherMemoryBytes = 0;    ///< the other stock's memory
};

/// A job whose stocks are built: ready to run.
struct PreparedRun {
  Job job;
  std::unique_ptr<Stock> stock;  ///< null without a stock
  std::unique_ptr<Stock> other;  ///< the cross-check's stock, or null
  std::unique_ptr<Part> part;    ///< --part, read and checked, or null
};

/// Called now and then with (steps done, steps in all).
using ProgressFunction = std::function<void(std::size_t, std::size_t)>;

/// Rates within this share of each other are the same where a peak's step is chosen: the first
/// step at the peak is reported, not one that rounding in the stock's sums put a few ulps higher.
constexpr double kSamePeak = 1e-9;

/// Everything a run made.
/// One limit of a schedule, checked on the re-simulated re-fed program (its worst step).
struct LimitCheck {
  std::string option;  ///< the option that set it: "--max-force", "--feed-max", ...
  Dimension dimension = Dimension::Force;
  double limit = 0.0;
  double worst = 0.0;  ///< the largest value over the re-simulated cutting steps
  int line = 0;        ///< the line of that step in the re-fed program
  bool holds = true;   ///< worst <= limit, within kVerifyTolerance above
};

/// A schedule's re-fed program read back and simulated again in a fresh stock: what the
/// machine will do, checked against every limit. Within 1 % above a limit counts as holding.
struct Verification {
  bool done = false;               ///< a schedule with a stock
  std::size_t steps = 0;           ///< of the re-simulation
  double removed = 0.0;            ///< mm^3 (the path is the same: the schedule's removal)
  double seconds = 0.0;            ///< the re-simulation's
  std::vector<LimitCheck> checks;  ///< the limits given, and --feed-max
};
constexpr double kVerifyTolerance = 0.01;

struct RunResult {
  Job job;
  std::unique_ptr<Stock> stock;  ///< the final stock (null without one)
  SimulationResult sim;
  bool crossChecked = false;
  CrossCheck cross;          ///< when crossChecked
  Schedule plan;             ///< empty unless the job schedules
  std::string refed;         ///< the re-fed program text (schedule jobs)
  Verification verified;     ///< the re-fed program re-simulated (schedule jobs with a stock)
  std::size_t peakStep = 0;  ///< the first step of the highest measured MRR (0 when none)
  PartCheck part;            ///< the final stock against --part (part.done with one)
  std::shared_ptr<const Part> partModel;  ///< --part, read (null without one)
};

/// A schedule's re-fed program (RunResult::refed) read back as the program was and simulated
/// in a fresh stock: its worst step against each limit the schedule was given and --feed-max;
/// with --accel or --jerk, the re-fed feeds on the run's steps, each change over the later
/// step (Eq 24's acceleration and the jerk its S-curve needs), as the schedule planned them.
/// executeRun calls it for every schedule with a stock.
Verification verifySchedule(const RunResult& r);

/// The memory a run of `job` may come to hold, bytes, by what holds it; checked against the
/// memory the run may use before it starts (prepareRun), and a batch reserves it for each job
/// it runs side by side.
struct MemoryEstimate {
  double fixed = 64e6;   ///< the process's libraries and small structures
  double moves = 0.0;    ///< the program's moves (already read)
  double steps = 0.0;    ///< a record per step (and its loads with --material; twice to schedule)
  double stocks = 0.0;   ///< the run's stock, the cross-check's, a schedule's re-simulation's
  double outputs = 0.0;  ///< the stock files and the report's 3D view (--outputs all)
  double total() const { return fixed + moves + steps + stocks + outputs; }
};

/// Per stock of a box: the voxel model's bound where the program cuts (VoxelStock::memoryBound
/// over programReach: 1.84 GB for the finishing benchmark at 0.05 mm, whose run peaks at 1.43
/// GB; 4.20 GB for tiger at 0.125 mm, peak 3.78 GB), or 100 bytes per dexel ray (the rays and
/// their record of the removal: a 0.2 mm tool's PCB isolation over 12 million rays peaks at
/// 1.3 GB with --outputs summary); the stock files and the report's view as much again for
/// voxels and for dexels 160 bytes a ray where stock.vdb is made through voxels at the rays'
/// cell, 60 where its box's faces alone ask for a coarser cell (VoxelStock::dexelFileFactor:
/// that PCB run peaks at 1.63 GB with all outputs, 27 bytes a ray more; over 20 x 15 mm, 3
/// million rays, 55). A mesh or stock.vdb stock counts the
/// 64 MB only. A voxel stock's bound stops counting above `stopAbove` bytes (a cell far too fine is
/// known to be too large before its leaves are all counted).
MemoryEstimate memoryEstimate(const Job& job,
                              double stopAbove = std::numeric_limits<double>::infinity());

/// Check the run's memory estimate against what it may use (--max-memory, else the process's
/// limit: Memory.h), build the job's stock (and the cross-check's), check that the tool path
/// reaches it, read the part and check that it lies in the stock. Throws Error; writes nothing.
PreparedRun prepareRun(Job job);

/// Simulate, cross-check and schedule, and compare the final stock with the part. Throws Error
/// from the model or the stock.
RunResult executeRun(PreparedRun run, const ProgressFunction& progress = {});

/// prepareRun then executeRun.
RunResult runJob(Job job, const ProgressFunction& progress = {});

/// A progress function that draws "label: done / total steps (p %)" on stderr when it is a
/// terminal and `quiet` is false; an empty function otherwise.
ProgressFunction terminalProgress(const std::string& label, bool quiet);

}  // namespace engage
