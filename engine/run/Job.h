#pragma once
/// \file Job.h
/// One simulate or schedule job as a value: the program read, the cutter built, the stock
/// described, and every setting typed and in internal units (mm, mm/min, mm^3/min, s). The
/// command line, a batch manifest and the Python module make it the same way, by makeJob from
/// the option values of OptionTable.h; makeJob is the one validation, and its errors name the
/// option and the value found.

#include "cutters/AptCutter.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/gcode/Toolpath.h"
#include "engine/run/CutterOptions.h"
#include "engine/run/OptionTable.h"
#include "engine/run/PartCheck.h"
#include "engine/run/Resolution.h"
#include "engine/schedule/FeedScheduler.h"
#include "engine/sim/Simulation.h"
#include "engine/tools/ToolLibrary.h"
#include "engine/units/Quantity.h"

#include <map>
#include <optional>
#include <string>

namespace engage {

/// The two stock models.
enum class StockModel { Voxel, Dexel };

/// "voxel" or "dexel".
const char* stockModelName(StockModel model);

/// The stock of a job: none (schedule --model analytic), a box (mm), a closed mesh file (mm)
/// or the stock.vdb of an earlier run.
struct StockSpec {
  std::string text;         ///< as typed ("" for none), shown in summary.json
  std::optional<Box3> box;  ///< a box:X0,Y0,Z0,X1,Y1,Z1, ordered corners, mm
  std::string mesh;         ///< a mesh file, when not a box or a .vdb
  std::string vdb;          ///< a stock.vdb of an earlier run (its grid "stock")
  bool none() const { return text.empty(); }
};

/// A job, checked: everything in it is valid.
struct Job {
  JobCommand command = JobCommand::Simulate;
  std::string program;   ///< the program's path, as given (or a CAMotics project's)
  Toolpath path;         ///< the program, read
  ReaderOptions reader;  ///< how it was read (a re-fed program is read back the same way)
  /// A CAMotics project's programs, run one after the other; empty for a program.
  std::vector<std::string> projectFiles;
  std::string toolText;  ///< the --tool value, as typed (summary.json)
  /// The single cutter (--tool), or with --tools the program's tool of the smallest radius.
  AptCutter cutter = AptCutter::flat(1.0, 1.0);
  std::string toolsFile;       ///< --tools, as given ("" for none)
  std::string toolsFormat;     ///< its format: linuxcnc, fusion360, freecad, camotics
  bool toolTableInch = false;  ///< a LinuxCNC table's lengths are inches (--tool-table-units in)
  /// The machine's start-up units were given (--startup-units, a machine file's
  /// startup_units): a program that sets neither G20 nor G21 is read in them without a warning.
  bool startupUnitsGiven = false;
  /// With --tools: the library's entries of the tools the program loads, by number.
  std::map<int, ToolEntry> tools;
  /// With --tools and no --tool: the tool taken to be in the spindle before the program's
  /// first change (its first tool), 0 otherwise.
  int startTool = 0;
  CutterSet cutters;  ///< the cutter of every move's tool
  /// Probing moves stopped on the bounds of a mesh or stock.vdb stock, not its surface.
  bool probesOnBounds = false;
  StockSpec stock;
  PartSpec part;  ///< --part, --tolerance, --allowance
  StockModel stockModel = StockModel::Dexel;
  UnitSystem units = UnitSystem::Metric;  ///< of the reports (and of bare numbers)
  double voxel = 0.0;                     ///< voxel size or dexel ray spacing, mm
  /// The engagement the cell follows (for the coarse-cell warning whatever set the cell) and,
  /// without --voxel, what set it (engine/run/Resolution.h).
  CellChoice cellChoice;
  bool voxelGiven = false;       ///< --voxel was given
  SimulationOptions simulation;  ///< step length, stepover, depth (no progress)
  double maxMemory = 0.0;        ///< --max-memory, bytes; 0: what the process may use
  bool crossCheck = false;       ///< also run the other stock model
  double crossTolerance = 0.03;  ///< relative per-step difference it allows
  ScheduleOptions schedule;      ///< used by schedule jobs
  /// Without a stock: the stock is on the right of the path (climb with M3) or on the left.
  bool materialOnRight = true;
  std::string materialSide;  ///< as typed ("" = default right)
  std::string out = "out";   ///< output folder
  /// Which files to write: all; tables (steps.csv, summary.json, the re-fed program,
  /// report.html without 3D view); summary
  /// (summary.json, the re-fed program): a batch of ten thousand programs fits a quota.
  enum class Outputs { All, Tables, Summary } outputs = Outputs::All;
  /// stock.stl's triangle budget (StockView::surface); 0: every cell of the grid.
  std::size_t stlTriangles = 2'000'000;
  /// Write stock.vdb whatever the outputs (a later batch job takes it as its stock).
  bool keepStock = false;
  bool quiet = false;  ///< no progress on the terminal
  /// Write report.html (outputs all and tables; with all it has the 3D view).
  bool report = true;
  std::string progressLabel = "simulate";

  bool scheduling() const { return command == JobCommand::Schedule; }
  /// The G-code file the re-fed program rewrites: the program, or a CAMotics project's (one)
  /// program.
  const std::string& mainProgram() const { return path.files.empty() ? program : path.files[0]; }
  /// The step length L the simulation uses, mm: --step, else simulate()'s default (2.5 voxels)
  /// with a stock, analyticSteps()'s (D/10) without one.
  double stepLength() const {
    if (simulation.stepLength > 0.0) return simulation.stepLength;
    return stock.none() ? 2.0 * cutters.smallestRadius() / 10.0 : 2.5 * voxel;
  }
  /// The other stock model, for the cross-check.
  StockModel otherModel() const {
    return stockModel == StockModel::Voxel ? StockModel::Dexel : StockModel::Voxel;
  }
};

/// Read the program named by values["program"] and check every option: unknown names, values
/// of the wrong kind, options that do not apply to `command`, inconsistent combinations. Bare
/// numbers are read in the report units (--units, else the program's). Throws Error (a
/// GcodeError, UnitError or ParameterError) naming the option and the value.
Job makeJob(JobCommand command, const OptionValues& values);

/// The G-code reader's options from a job's values (--dialect, --machine, --start, --startup-units,
/// --tool-table and --tool-table-units, --block-delete, --cutter-comp, --max-moves) for
/// `program`: the one reading of them, for the jobs and for `engage moves`. A tool table's
/// units default to the program's (its first G20/G21), else the start-up units.
ReaderOptions readerOptions(const OptionValues& values, const std::string& program);

/// The value of option `name` in `values`, or the table's default.
std::string optionText(const OptionValues& values, const std::string& name);

}  // namespace engage
