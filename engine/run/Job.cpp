#include "engine/run/Job.h"

#include "engine/tools/CamoticsProject.h"

#include "engine/run/Machine.h"
#include "engine/run/Memory.h"
#include "engine/run/ProbeContact.h"

#include "cutters/Error.h"
#include "engine/gcode/GcodeReader.h"
#include "stock/TriangleMesh.h"
#include "stock/VoxelStock.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace engage {
namespace {

/// The bounds (mm) of a stock read from a file, before it is read: a mesh's points, a
/// stock.vdb's metadata; none when they cannot be had (the stock's reading says why).
std::optional<Box3> stockFileBounds(const StockSpec& stock) {
  if (!stock.vdb.empty()) return VoxelStock::fileBounds(stock.vdb);
  if (stock.mesh.empty()) return std::nullopt;
  try {
    const TriangleMesh mesh = readMesh(stock.mesh);
    if (mesh.points.empty()) return std::nullopt;
    Box3 b;
    b.min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    b.max = -b.min;
    for (const auto& p : mesh.points)
      for (int a = 0; a < 3; ++a) {
        b.min[a] = std::min(b.min[a], static_cast<double>(p[static_cast<std::size_t>(a)]));
        b.max[a] = std::max(b.max[a], static_cast<double>(p[static_cast<std::size_t>(a)]));
      }
    return b;
  } catch (const Error&) {
    return std::nullopt;
  }
}

/// "a, b and c" (or "a, b or c" with `conjunction` "or").
std::string wordList(const std::vector<std::string>& words, const char* conjunction) {
  std::string list;
  for (std::size_t i = 0; i < words.size(); ++i)
    list += (i == 0                  ? ""
             : i + 1 == words.size() ? std::string(" ") + conjunction + " "
                                     : ", ") +
            words[i];
  return list;
}

/// Check that every name is an option of `command` and that each value has the kind the table
/// says (quantities are read later, when the unit system is known).
void checkNames(JobCommand command, const OptionValues& values) {
  for (const auto& [name, text] : values) {
    if (name == "program") continue;
    const OptionInfo* o = findJobOption(name);
    if (!o) throw ParameterError("unknown option \"" + name + "\"");
    if (!appliesTo(*o, command))
      throw ParameterError("--" + name + " applies to schedule jobs only");
    if (o->kind == OptionKind::Choice && !text.empty() &&
        std::find(o->choices.begin(), o->choices.end(), text) == o->choices.end()) {
      throw ParameterError("--" + name + ": expected " + wordList(o->choices, "or") + ", found '" +
                           text + "'");
    }
    if (o->kind == OptionKind::Flag && text != "true" && text != "false")
      throw ParameterError("--" + name + ": expected true or false, found '" + text + "'");
  }
}

int wholeNumber(const std::string& text, const char* name) {
  try {
    std::size_t used = 0;
    const int n = std::stoi(text, &used);
    if (used != text.size()) throw std::invalid_argument(text);
    return n;
  } catch (const std::exception&) {
    throw ParameterError(std::string(name) + ": expected a whole number, found '" + text + "'");
  }
}

double plainNumber(const std::string& text, const std::string& message) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size()) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw ParameterError(message);
  }
}

/// box:X0,Y0,Z0,X1,Y1,Z1 with bare numbers in `sys`; a .vdb an earlier run's stock; a mesh
/// file otherwise.
StockSpec parseStock(const std::string& text, UnitSystem sys) {
  StockSpec s;
  s.text = text;
  if (text.rfind("box:", 0) != 0) {
    const std::string ext = std::filesystem::path(text).extension().string();
    if (ext == ".vdb" || ext == ".VDB")
      s.vdb = text;
    else
      s.mesh = text;
    return s;
  }
  std::vector<double> v;
  std::stringstream in(text.substr(4));
  std::string item;
  while (std::getline(in, item, ','))
    v.push_back(parseQuantity(item, Dimension::Length, sys, "--stock box").value);
  if (v.size() != 6)
    throw ParameterError("--stock: expected box:X0,Y0,Z0,X1,Y1,Z1 (six numbers), found " +
                         std::to_string(v.size()) + " in '" + text + "'");
  // The low corner first: a box typed the other way round is more often a slip (a sign, a
  // swapped pair) than a choice, so it is refused, not reordered.
  for (int a = 0; a < 3; ++a)
    if (!(v[static_cast<std::size_t>(a)] < v[static_cast<std::size_t>(a + 3)])) {
      const std::string axis(1, static_cast<char>('X' + a));
      auto f = [&](double x) { return formatQuantity(x, Dimension::Length, sys); };
      throw ParameterError("--stock box: expected " + axis + "0 below " + axis +
                           "1 (box:X0,Y0,Z0,X1,Y1,Z1, the low corner first), found " + axis +
                           "0 = " + f(v[static_cast<std::size_t>(a)]) + " and " + axis +
                           "1 = " + f(v[static_cast<std::size_t>(a + 3)]) + " in '" + text + "'");
    }
  Box3 b;
  b.min = {v[0], v[1], v[2]};
  b.max = {v[3], v[4], v[5]};
  s.box = b;
  return s;
}

/// The schedule's settings (schedule jobs only).
ScheduleOptions scheduleOptions(const OptionValues& values, UnitSystem sys, const Job& job) {
  auto text = [&](const char* name) { return optionText(values, name); };
  // Limits and feeds: none is negative (0 means "none" or "the programmed").
  auto quantity = [&](const char* name, Dimension d) {
    const std::string t = text(name);
    const double v = t.empty() ? 0.0 : parseQuantity(t, d, sys, "--" + std::string(name)).value;
    if (v < 0.0)
      throw ParameterError("--" + std::string(name) + " must not be negative, found '" + t + "'");
    return v;
  };
  ScheduleOptions s;
  const std::string target = text("target-mrr");
  if (target != "auto") {
    s.targetMrr = parseQuantity(target, Dimension::VolumeRate, sys, "--target-mrr").value;
    if (!(s.targetMrr > 0.0))
      throw ParameterError("--target-mrr must be positive (or auto), found '" + target + "'");
  }
  s.feedMin = quantity("feed-min", Dimension::Feed);
  s.allowUnmet = text("allow-unmet") == "true";
  s.feedMax = quantity("feed-max", Dimension::Feed);
  s.airFeed = quantity("air-feed", Dimension::Feed);
  s.acceleration = quantity("accel", Dimension::Acceleration);
  s.jerk = quantity("jerk", Dimension::Jerk);
  s.rapidFeed = quantity("rapid-feed", Dimension::Feed);
  const std::string change = text("min-change");
  s.minChange =
      plainNumber(change, "--min-change: expected a fraction such as 0.05, found '" + change + "'");
  if (!(s.minChange > 0.0 && s.minChange < 1.0))
    throw ParameterError("--min-change: expected a fraction in (0, 1), found " + change);
  s.minSegment = quantity("min-segment", Dimension::Length);
  s.analytic = text("model") == "analytic";
  const struct {
    const char* name;
    Dimension dimension;
    double* field;
  } limits[] = {{"max-chip", Dimension::Length, &s.maxChip},
                {"max-force", Dimension::Force, &s.maxForce},
                {"max-torque", Dimension::Torque, &s.maxTorque},
                {"max-power", Dimension::Power, &s.maxPower}};
  for (const auto& l : limits) {
    *l.field = quantity(l.name, l.dimension);
    if (!text(l.name).empty() && !(*l.field > 0.0))
      throw ParameterError(std::string("--") + l.name + " must be positive, found '" +
                           text(l.name) + "'");
  }
  if (s.physicsLimits()) {
    if (text("material").empty())
      throw ParameterError(
          "--max-chip, --max-force, --max-torque and --max-power need --material (the "
          "coefficients the chip and the forces are computed with)");
    if (s.analytic)
      throw ParameterError(
          "--max-chip, --max-force, --max-torque and --max-power need the "
          "measured engagement: not with --model analytic");
    if (!text("force-limit").empty())
      throw ParameterError("give either --force-limit (paper Eq 17-18) or --max-force");
    // Without an MRR target given, the physics limits alone set the feeds.
    s.mrrTarget = target != "auto";
  }
  if (!text("force-limit").empty()) {
    if (target != "auto") throw ParameterError("give either --target-mrr or --force-limit");
    if (text("specific-energy").empty() || text("spindle").empty())
      throw ParameterError("--force-limit needs --specific-energy and --spindle (paper Eq 17-18)");
    // Each tool's target from its own diameter.
    auto targetFor = [&](const AptCutter& c) {
      return mrrForForce(quantity("force-limit", Dimension::Force),
                         quantity("specific-energy", Dimension::SpecificEnergy), 2.0 * c.radius(),
                         quantity("spindle", Dimension::SpindleSpeed));
    };
    s.targetMrr = targetFor(job.cutter);
    for (const auto& [tool, cutter] : job.cutters.byTool)
      s.targetByTool[tool] = targetFor(cutter);
  }
  return s;
}

/// The parts of a library tool above its flutes, checked for collisions: the shank (the
/// library's diameter, else the cutter's) from the flute length up to the stickout (else the
/// overall length), and the holder's segments stacked from the stickout up. None when the
/// library gives no length above the flutes.
std::vector<ToolPart> toolParts(const ToolEntry& e) {
  std::vector<ToolPart> parts;
  const AptCutter& c = *e.cutter;
  const double h = c.height();
  const double top = e.stickout > 0.0 ? e.stickout : e.overallLength;
  if (top > h + 1e-9) {
    const double d = e.shankDiameter > 0.0 ? e.shankDiameter : 2.0 * c.maxRadius();
    parts.push_back({"shank", AptCutter::flat(d, top - h), h});
  }
  double z = e.stickout;
  for (std::size_t i = 0; e.stickout > 0.0 && i < e.holder.size(); ++i) {
    const HolderSegment& s = e.holder[i];
    if (!(s.height > 0.0)) continue;
    try {
      const double beta = std::atan2(0.5 * (s.upperDiameter - s.lowerDiameter), s.height);
      parts.push_back({"holder",
                       std::abs(beta) < 1e-12 ? AptCutter::flat(s.lowerDiameter, s.height)
                                              : AptCutter::taper(s.lowerDiameter, beta, s.height),
                       z});
    } catch (const Error& err) {
      throw ParameterError("holder segment " + std::to_string(i + 1) + ": " + err.what());
    }
    z += s.height;
  }
  return parts;
}

/// --holder: segments "DxH" (a cylinder) or "D1-D2xH" (a cone frustum from D1 at its bottom),
/// comma-separated, from the holder's face up; lengths with units or in the program's.
std::vector<HolderSegment> parseHolder(const std::string& text, UnitSystem sys) {
  std::vector<HolderSegment> out;
  std::istringstream in(text);
  std::string piece;
  while (std::getline(in, piece, ',')) {
    const auto x = piece.find('x');
    if (x == std::string::npos)
      throw ParameterError(
          "--holder: expected segments such as 22x10 or 28-40x30 (diameter x "
          "height), found '" +
          piece + "'");
    const std::string diameters = piece.substr(0, x);
    const auto dash = diameters.find('-', 1);
    auto length = [&](const std::string& v) {
      const double l = parseQuantity(v, Dimension::Length, sys, "--holder").value;
      if (!(l > 0.0)) throw ParameterError("--holder: '" + v + "' must be positive");
      return l;
    };
    HolderSegment s;
    s.lowerDiameter = length(diameters.substr(0, dash));
    s.upperDiameter =
        dash == std::string::npos ? s.lowerDiameter : length(diameters.substr(dash + 1));
    s.height = length(piece.substr(x + 1));
    out.push_back(s);
  }
  return out;
}

/// A tool the program loads, with the file (index into Toolpath::files) and line that load it:
/// its M6 or M61, or where it is not known (a CAMotics project's first tool) its first move.
struct ToolChange {
  int tool = 0, file = 0, line = 0;
};

/// The tools a program cuts with, in order of their first moves.
std::vector<ToolChange> toolChanges(const Toolpath& path) {
  std::vector<ToolChange> changes;
  int current = 0;
  for (std::size_t i = 0; i < path.moves.size(); ++i) {
    const Move& m = path.moves[i];
    if (m.tool == current) continue;
    current = m.tool;
    if (current == 0) continue;
    ToolChange c{current, m.file, m.line};
    for (const ToolLoad& l : path.toolLoads)
      if (l.tool == current && l.firstMove <= i) c = {current, l.file, l.line};
    changes.push_back(c);
  }
  return changes;
}

/// The cutters of the job's moves: one --tool for all, or the library's per T number.
/// `defaultTool`: the tool taken for moves before any change when --tool is not given (a
/// CAMotics project: 1, as CAMotics selects it, where the project has it); 0: the program's
/// first tool.
void chooseCutters(Job& job, const std::optional<ToolLibrary>& lib,
                   const std::optional<AptCutter>& single, int defaultTool) {
  const auto changes = toolChanges(job.path);
  if (!lib) {
    if (!single) throw ParameterError("--tool is required (or --tools FILE, a tool library)");
    std::vector<int> numbers;
    std::string list;
    for (const ToolChange& c : changes)
      if (std::find(numbers.begin(), numbers.end(), c.tool) == numbers.end()) {
        numbers.push_back(c.tool);
        list += (list.empty() ? "" : ", ") + ("T" + std::to_string(c.tool) + " from ") +
                (c.file == 0 ? "line " : job.path.files[static_cast<std::size_t>(c.file)] + ":") +
                std::to_string(c.line);
      }
    if (numbers.size() > 1)
      throw ParameterError(job.program + ": the program changes tools (" + list +
                           ") and --tool gives one cutter for all of them: give the tool "
                           "library with --tools FILE");
    job.cutters.fallback = *single;
    job.cutter = *single;
    return;
  }
  job.toolsFormat = lib->format;
  if (changes.empty() && !single && defaultTool == 0)
    throw ParameterError(job.program +
                         ": the program loads no tool (no T.. M6 or M61 Q..): give --tool for "
                         "the tool in the spindle");
  // A library tool into the job: its entry, its cutter, its shank and holder.
  auto load = [&](int tool) {
    if (job.tools.count(tool)) return;
    const ToolEntry& e = lib->require(tool);
    job.tools.emplace(tool, e);
    job.cutters.byTool.emplace(tool, *e.cutter);
    job.cutters.partsByTool[tool] = toolParts(e);
  };
  for (const ToolChange& c : changes) {
    try {
      load(c.tool);
    } catch (const ParameterError& err) {
      throw ParameterError(job.path.files[static_cast<std::size_t>(c.file)] + ":" +
                           std::to_string(c.line) + ": T" + std::to_string(c.tool) + ": " +
                           err.what());
    }
  }
  // Moves before the first change run with --tool, else with the program's first tool.
  if (single) {
    job.cutters.byTool.emplace(0, *single);
  } else {
    // (A project without T1 whose program loads its tool after a few rapids: that tool.)
    const bool given = defaultTool != 0 && (!lib->numbered(defaultTool).empty() || changes.empty());
    job.startTool = given ? defaultTool : changes.front().tool;
    load(job.startTool);
    job.cutters.byTool.emplace(0, job.cutters.byTool.at(job.startTool));
    job.cutters.partsByTool[0] = job.cutters.partsByTool[job.startTool];
  }
  job.cutter = job.cutters.byTool.begin()->second;
  for (const auto& [tool, c] : job.cutters.byTool)
    if (c.radius() < job.cutter.radius()) job.cutter = c;
}

}  // namespace

const char* stockModelName(StockModel model) {
  return model == StockModel::Dexel ? "dexel" : "voxel";
}

std::string optionText(const OptionValues& values, const std::string& name) {
  const auto it = values.find(name);
  if (it != values.end()) return it->second;
  const OptionInfo* o = findJobOption(name);
  return o ? o->defaultText : std::string();
}

namespace {

/// Several missing options named together (one alone gets its own message where it is read);
/// a CAMotics project brings its tools and workpiece.
void refuseMissing(JobCommand command, const OptionValues& values, const std::string& program) {
  if (isCamoticsProject(program)) return;
  auto text = [&](const char* name) { return optionText(values, name); };
  std::vector<std::string> missing;
  if (text("tool").empty() && text("tools").empty()) missing.push_back("--tool (or --tools)");
  if (!text("tool").empty() && text("diameter").empty()) missing.push_back("--diameter");
  if (text("stock").empty() &&
      !(command == JobCommand::Schedule && text("model") == std::string("analytic")))
    missing.push_back("--stock");
  if (missing.size() > 1) throw ParameterError(wordList(missing, "and") + " are required");
}

/// The job's program read (a CAMotics project's programs one after the other) with the tool
/// Only a re-fed program is written back, from its words' positions: a run that is not keeps
/// none (megabytes on a long program).
void dropWords(Job& job) {
  if (job.command != JobCommand::Schedule)
    for (SourceBlock& b : job.path.blocks)
      std::vector<WordSpan>().swap(b.words);
}

/// Without a machine the tool is taken to start at the program's origin; where a box or
/// stock.vdb stock reaches above it (the program's Z0 below the stock's top), it starts at the
/// stock's top instead, above the origin, as a machine at its Z home is above the part: the
/// program is read again from there, so that its first rapid does not start in the material.
void startAboveStock(Job& job, bool project) {
  if (project || job.reader.machine || job.reader.startKnown || job.path.moves.empty()) return;
  const std::optional<Box3> b = job.stock.box           ? job.stock.box
                                : job.stock.vdb.empty() ? std::nullopt
                                                        : stockFileBounds(job.stock);
  if (!b || !(b->max.z() > job.reader.start.z() + 1e-9)) return;
  ReaderOptions ro = job.reader;
  ro.start.z() = b->max.z();
  job.path = readProgram(job.program, ro);
  job.reader = ro;
  dropWords(job);
}

/// --diameter in mm with bare numbers in `sys`, for G41/G42 of a run with the one --tool and no
/// table; 0 when it is not a length (the cutter's own reading says why).
double soleToolDiameter(const OptionValues& values, UnitSystem sys) {
  try {
    return parseQuantity(optionText(values, "diameter"), Dimension::Length, sys, "--diameter")
        .value;
  } catch (const Error&) {
    return 0.0;
  }
}

/// Probing moves (G38.2, G38.3) stop where they touch the stock, as on the machine: the
/// program is read again with the stock's box (a mesh's or stock.vdb's bounds: job.probesOnBounds)
/// and the tools' radii, so that what the program does with #5061-#5063 (G10 L20 zeroing on
/// the touched face) follows. Without a stock the probe runs to its target, as LinuxCNC's
/// stand-alone rs274 has it.
void probeAgainstStock(Job& job, const std::optional<CamoticsProject>& project) {
  if (std::none_of(job.path.moves.begin(), job.path.moves.end(),
                   [](const Move& m) { return m.feedSource == FeedSource::Probe; }))
    return;
  const std::optional<Box3> b = job.stock.box ? job.stock.box : stockFileBounds(job.stock);
  if (!b) return;
  ReaderOptions ro = job.reader;
  ro.probeContact = [box = *b, cutters = job.cutters](const Eigen::Vector3d& from,
                                                      const Eigen::Vector3d& to, int tool) {
    const bool known = cutters.byTool.count(tool) || cutters.fallback;
    return probeContact(box, known ? cutters.of(tool).radius() : 0.0, from, to);
  };
  job.path = project ? readPrograms(project->files, ro) : readProgram(job.program, ro);
  job.reader = ro;
  job.probesOnBounds = !job.stock.box;
  dropWords(job);
}

/// A tool no run can mean, refused before any work: narrower than the cell given (--voxel: no
/// cell would see its cut), or wider than four times the stock's largest side (a face mill
/// may be wider than a small part; a table read in the wrong units is 25.4 times off).
void refuseAbsurdTools(const Job& job) {
  const std::optional<Box3> b = job.stock.box ? job.stock.box : stockFileBounds(job.stock);
  std::vector<std::pair<std::string, const AptCutter*>> tools;
  for (const auto& [number, cutter] : job.cutters.byTool)
    if (number != 0) tools.emplace_back("T" + std::to_string(number), &cutter);
  if (job.cutters.fallback) tools.emplace_back("--tool", &*job.cutters.fallback);
  for (const auto& [name, cutter] : tools) {
    const double d = 2.0 * cutter->maxRadius();
    if (job.voxelGiven && d < job.voxel)
      throw ParameterError(name + " is " + formatNumber(d) +
                           " mm across, narrower than the cell (" + formatNumber(job.voxel) +
                           " mm): no cell would see its cut (give a --voxel a fifth of it or "
                           "less, or check the tool table's units: --tool-table-units)");
    if (b) {
      const double side = std::max(b->max.x() - b->min.x(), b->max.y() - b->min.y());
      if (d > 4.0 * side)
        throw ParameterError(name + " is " + formatNumber(d) +
                             " mm across, more than four times the stock's largest side (" +
                             formatNumber(side) +
                             " mm): is the tool table in other units than it was read in "
                             "(--tool-table-units)?");
    }
  }
}

/// Whether a program's first G20 or G21 (outside comments) says inches; nullopt when it has
/// neither or cannot be read (the reader then says why).
std::optional<bool> firstUnitsWord(const std::string& path) {
  if (path.empty()) return std::nullopt;
  std::ifstream in(path);
  static const std::regex units(R"(G\s*0*2\s*([01])(?![0-9.]))", std::regex::icase);
  for (std::string line; std::getline(in, line);) {
    std::string code;
    int depth = 0;
    for (const char c : line) {
      if (c == ';' && depth == 0) break;
      if (c == '(') ++depth;
      if (depth == 0) code += c;
      if (c == ')' && depth > 0) --depth;
    }
    std::smatch m;
    if (std::regex_search(code, m, units)) return m[1] == "0";
  }
  return std::nullopt;
}

/// --max-memory, bytes; 0 when not given.
double maxMemoryOption(const OptionValues& values) {
  const std::string text = optionText(values, "max-memory");
  return text.empty() ? 0.0 : parseMemory(text, "--max-memory");
}

}  // namespace

ReaderOptions readerOptions(const OptionValues& values, const std::string& program) {
  auto text = [&](const char* name) { return optionText(values, name); };
  ReaderOptions ro;
  ro.toolTable = text("tool-table");
  ro.dialect = dialectOf(text("dialect"));
  ro.blockDelete = text("block-delete") == "true";
  ro.wearCompensation = text("cutter-comp") == "wear";
  if (!text("machine").empty()) ro.machine = readMachine(text("machine"));
  // The start-up units: --startup-units, else the machine file's.
  const std::string startup = text("startup-units");
  ro.startInch = !startup.empty() ? unitSystemNamed(startup) == UnitSystem::Inch
                                  : ro.machine && ro.machine->startInch;
  // A LinuxCNC tool table's numbers: --tool-table-units, else the program's units (its first
  // G20 or G21, else the start-up units).
  if (!text("tool-table-units").empty()) {
    ro.toolTableInch = unitSystemNamed(text("tool-table-units")) == UnitSystem::Inch;
  } else if (!ro.toolTable.empty() || !text("tools").empty()) {  // (a table to read)
    const std::optional<bool> inch =
        firstUnitsWord(isCamoticsProject(program) ? std::string() : program);
    ro.toolTableInch = inch ? *inch : ro.startInch;
  }
  const int maxMoves = wholeNumber(text("max-moves"), "--max-moves");
  if (maxMoves < 1) throw ParameterError("--max-moves must be positive");
  ro.maxMoves = static_cast<std::size_t>(maxMoves);
  // The moves the run's memory holds, each with at least one step (a loop that never ends
  // under a cluster job's memory limit is refused here, not by the allocator); the list of
  // moves holds up to three times its moves while it grows (the old array and the new).
  const MemoryLimit memory = memoryLimit(maxMemoryOption(values));
  const double byMemory = memory.bytes / static_cast<double>(3 * sizeof(Move) + sizeof(StepRecord));
  if (byMemory < static_cast<double>(ro.maxMoves)) {
    ro.maxMoves = static_cast<std::size_t>(std::max(1.0, byMemory));
    ro.maxMovesWhy =
        " (what " + memoryText(memory.bytes) + " holds with their steps: " + memory.source + ")";
  }
  // --start: three lengths, bare numbers in the program's units (its first G20/G21).
  if (const std::string start = text("start"); !start.empty()) {
    const std::optional<bool> inch =
        firstUnitsWord(isCamoticsProject(program) ? std::string() : program);
    const UnitSystem sys = inch.value_or(ro.startInch) ? UnitSystem::Inch : UnitSystem::Metric;
    std::vector<std::string> parts;
    std::stringstream in(start);
    for (std::string part; std::getline(in, part, ',');)
      parts.push_back(part);
    if (parts.size() != 3)
      throw ParameterError("--start: expected X,Y,Z (three lengths), found '" + start + "'");
    for (int a = 0; a < 3; ++a)
      ro.start[a] =
          parseQuantity(parts[static_cast<std::size_t>(a)], Dimension::Length, sys, "--start")
              .value;
    ro.startKnown = true;
  }
  return ro;
}

namespace {

/// Read the program (or a CAMotics project's programs) into job.path, with the tool
/// library that gives its tools (--tools, or the project's table); the project, if it is one.
std::optional<CamoticsProject> readJobProgram(Job& job, const OptionValues& values,
                                              std::optional<ToolLibrary>& library) {
  auto text = [&](const char* name) { return optionText(values, name); };
  const JobCommand command = job.command;
  ReaderOptions ro = readerOptions(values, job.program);
  if (!text("tool").empty() && text("tools").empty() && ro.toolTable.empty() &&
      !isCamoticsProject(job.program)) {
    const std::optional<bool> inch = firstUnitsWord(job.program);
    ro.soleToolDiameter = soleToolDiameter(
        values, inch.value_or(ro.startInch) ? UnitSystem::Inch : UnitSystem::Metric);
  }
  job.startupUnitsGiven =
      !text("startup-units").empty() || (ro.machine && ro.machine->startUnitsGiven);
  job.toolTableInch = ro.toolTableInch;
  job.toolsFile = text("tools");
  // A CAMotics project: its programs, its tool table (unless --tools), its workpiece (unless
  // --stock).
  std::optional<CamoticsProject> project;
  if (isCamoticsProject(job.program)) {
    project = readCamoticsProject(job.program);
    job.projectFiles = project->files;
    if (job.toolsFile.empty()) {
      library = project->tools;
      job.toolsFile = job.program;
    }
  }
  if (!job.toolsFile.empty() && !library) {
    ToolLibraryOptions lo;
    lo.linuxcncInch = ro.toolTableInch;
    library = readToolLibrary(job.toolsFile, lo);
    // A LinuxCNC table is also the machine's tool lengths (G43), unless --tool-table says.
    if (library->format == "linuxcnc" && ro.toolTable.empty()) ro.toolTable = job.toolsFile;
  }
  // Other libraries give G41/G42 their tools' diameters.
  if (library && library->format != "linuxcnc")
    for (const ToolEntry& t : library->tools)
      if (t.cutter) ro.toolDiameters.emplace(t.number, 2.0 * t.cutter->radius());
  const int maxSteps = wholeNumber(text("max-steps"), "--max-steps");
  if (maxSteps < 1) throw ParameterError("--max-steps must be positive");
  job.path = project ? readPrograms(project->files, ro) : readProgram(job.program, ro);
  job.reader = ro;
  job.simulation.maxSteps = static_cast<std::size_t>(maxSteps);
  job.maxMemory = maxMemoryOption(values);
  dropWords(job);
  if (project && project->files.size() > 1 && command == JobCommand::Schedule)
    throw ParameterError(job.program + ": schedule re-feeds one program and this project runs " +
                         std::to_string(project->files.size()) +
                         "; schedule each program (with --stock from the previous one's run)");
  if (job.path.latheLine != 0)
    throw ParameterError(job.program + ":" + std::to_string(job.path.latheLine) +
                         ": a lathe program (" + job.path.lathe +
                         "): engage simulates milling; `engage moves` lists its moves");
  return project;
}

/// --tool's shank and holder (--stickout, --shank-diameter, --holder), checked for collisions
/// as a library's are; refused where they describe no --tool.
void toolPartOptions(Job& job, const OptionValues& values, const std::optional<AptCutter>& single,
                     UnitSystem sys) {
  auto text = [&](const char* name) { return optionText(values, name); };
  if (single && !text("stickout").empty()) {
    ToolEntry e;
    e.cutter = *single;
    e.stickout = parseQuantity(text("stickout"), Dimension::Length, sys, "--stickout").value;
    if (!(e.stickout > single->height()))
      throw ParameterError("--stickout must exceed the flute length (" +
                           formatQuantity(single->height(), Dimension::Length, sys) + ")");
    if (!text("shank-diameter").empty())
      e.shankDiameter =
          parseQuantity(text("shank-diameter"), Dimension::Length, sys, "--shank-diameter").value;
    if (!(e.shankDiameter >= 0.0)) throw ParameterError("--shank-diameter must be positive");
    e.holder = parseHolder(text("holder"), sys);
    try {
      job.cutters.fallbackParts = toolParts(e);
    } catch (const Error& err) {
      throw ParameterError("--holder: " + std::string(err.what()));
    }
  } else if (!text("shank-diameter").empty() || !text("holder").empty()) {
    throw ParameterError(single ? "--shank-diameter and --holder need --stickout (where the "
                                  "holder's face is)"
                                : "--shank-diameter, --stickout and --holder describe --tool; a "
                                  "library's tools carry their own");
  } else if (!single && !text("stickout").empty()) {
    throw ParameterError("--stickout describes --tool; a library's tools carry their own");
  }
}

/// The cutting physics of --material (--force-model, --helix, --spindle), or none; the physics
/// options without --material refused.
std::optional<PhysicsOptions> physicsOptions(const OptionValues& values, UnitSystem sys) {
  auto text = [&](const char* name) { return optionText(values, name); };
  if (!text("material").empty()) {
    PhysicsOptions physics;
    physics.material = readMaterial(text("material"), text("force-model"));
    if (!text("helix").empty()) {
      physics.helix = parseQuantity(text("helix"), Dimension::Angle, sys, "--helix").value;
      if (!(physics.helix >= 0.0 && physics.helix < 1.5))
        throw ParameterError("--helix: expected an angle in [0, 86) deg, found '" + text("helix") +
                             "'");
    }
    if (!text("spindle").empty()) {
      physics.spindleRpm =
          parseQuantity(text("spindle"), Dimension::SpindleSpeed, sys, "--spindle").value;
      if (!(physics.spindleRpm > 0.0))
        throw ParameterError("--spindle must be positive, found '" + text("spindle") + "'");
    }
    return physics;
  } else {
    for (const char* name : {"force-model", "helix"})
      if (!text(name).empty())
        throw ParameterError(std::string("--") + name + " applies with --material");
    if (!text("spindle").empty() && text("force-limit").empty())
      throw ParameterError("--spindle applies with --material or --force-limit");
  }
  return std::nullopt;
}

/// --part and its --tolerance and --allowance (defaults 0.05 mm, 0.002 in for an inch
/// program); they need a stock.
void partOptions(Job& job, const OptionValues& values, UnitSystem sys) {
  auto text = [&](const char* name) { return optionText(values, name); };
  job.part.file = text("part");
  if (job.part.file.empty()) {
    for (const char* name : {"tolerance", "allowance"})
      if (!text(name).empty())
        throw ParameterError(std::string("--") + name + " applies with --part");
    return;
  }
  if (job.stock.none())
    throw ParameterError("--part needs a --stock: the final stock is compared with the part");
  if (!std::filesystem::is_regular_file(job.part.file))
    throw Error("--part: file not found: " + job.part.file);
  auto limit = [&](const char* name) {
    if (text(name).empty()) return sys == UnitSystem::Inch ? 0.002 * 25.4 : 0.05;
    const double v =
        parseQuantity(text(name), Dimension::Length, sys, std::string("--") + name).value;
    if (!(v >= 0.0))
      throw ParameterError(std::string("--") + name + " must not be negative, found '" +
                           text(name) + "'");
    return v;
  };
  job.part.tolerance = limit("tolerance");
  job.part.allowance = limit("allowance");
}

/// The job's stock (a CAMotics project's workpiece unless --stock) and the options that need
/// one.
void stockOptions(Job& job, const OptionValues& values,
                  const std::optional<CamoticsProject>& project, UnitSystem sys) {
  auto text = [&](const char* name) { return optionText(values, name); };
  const bool analytic = job.scheduling() && text("model") == "analytic";
  job.materialSide = text("material-side");
  job.materialOnRight = job.materialSide != "left";
  job.crossCheck = text("cross-check") == "true";
  const std::string tolerance = text("cross-check-tolerance");
  job.crossTolerance =
      plainNumber(tolerance, "--cross-check-tolerance: expected a fraction in (0, 1)");
  // Without a stock (schedule --model analytic only) the steps carry the analytic model
  // alone, as in the paper.
  std::string stock = text("stock");
  if (stock.empty() && project) {
    // The project's workpiece, in mm whatever the program's units.
    const Box3 b = project->automatic
                       ? camoticsAutomaticWorkpiece(
                             job.path, [&](int t) -> const AptCutter& { return job.cutters.of(t); },
                             project->marginPercent)
                       : project->bounds;
    char box[256];
    std::snprintf(box, sizeof box, "box:%.9gmm,%.9gmm,%.9gmm,%.9gmm,%.9gmm,%.9gmm", b.min.x(),
                  b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z());
    stock = box;
  }
  if (stock.empty() && !analytic)
    throw ParameterError("--stock is required (only schedule --model analytic runs without one)");
  if (!stock.empty() && !job.materialSide.empty())
    throw ParameterError("--material-side applies without --stock (the stock tells the side)");
  if (job.crossCheck && stock.empty()) throw ParameterError("--cross-check needs a --stock");
  if (job.simulation.physics && stock.empty())
    throw ParameterError(
        "--material needs a --stock: the forces come from the measured engagement");
  if (!(job.crossTolerance > 0.0 && job.crossTolerance < 1.0))
    throw ParameterError("--cross-check-tolerance: expected a fraction in (0, 1)");
  // A program that tilts the tool (a 4- or 5-axis machine's kinematics) runs in the voxel
  // stock unless told otherwise: the dexel stock's rays are vertical (the simulation refuses
  // a tilted tool in it, naming the line).
  const std::string model = text("stock-model");
  const bool tilts = tiltsTool(job.path);
  job.stockModel =
      model == "voxel" || (model.empty() && tilts) ? StockModel::Voxel : StockModel::Dexel;
  if (job.crossCheck && tilts)
    throw ParameterError(
        "--cross-check needs the dexel stock too, whose vertical rays cannot "
        "follow this program's tilted tool (" +
        std::string(kinematicsTypeName(job.path.kinematics.type)) + " kinematics)");
  if (!stock.empty()) job.stock = parseStock(stock, sys);
  partOptions(job, values, sys);
}

/// The output folder and what goes into it; a re-fed program that would replace its own
/// program refused.
void outputOptions(Job& job, const OptionValues& values) {
  auto text = [&](const char* name) { return optionText(values, name); };
  job.out = text("out");
  const std::string outputs = text("outputs");
  job.outputs = outputs == "tables"    ? Job::Outputs::Tables
                : outputs == "summary" ? Job::Outputs::Summary
                                       : Job::Outputs::All;
  // The re-fed program goes into --out under the program's own name: never over the program.
  if (job.scheduling()) {
    namespace fs = std::filesystem;
    std::error_code e1, e2;
    const fs::path refed =
        fs::weakly_canonical(fs::path(job.out) / fs::path(job.mainProgram()).filename(), e1);
    if (!e1 && refed == fs::weakly_canonical(job.mainProgram(), e2) && !e2)
      throw ParameterError("--out: the re-fed program would replace the program '" +
                           job.mainProgram() + "' itself; give another --out folder");
  }
  job.quiet = text("quiet") == "true";
  job.report = text("no-report") != "true";
  {
    const int triangles = wholeNumber(text("stl-triangles"), "--stl-triangles");
    if (triangles < 0) throw ParameterError("--stl-triangles must not be negative");
    if (triangles > 0 && triangles < 1000)
      throw ParameterError("--stl-triangles: expected 0 (the full grid) or at least 1000, found " +
                           std::to_string(triangles));
    job.stlTriangles = static_cast<std::size_t>(triangles);
  }
}

/// makeJob's work; `speak` gets the report units as soon as they are known. Everything that
/// can be checked is checked here, before any work and before any output.
Job buildJob(JobCommand command, const OptionValues& values, UnitSystem& speak) {
  checkNames(command, values);
  auto text = [&](const char* name) { return optionText(values, name); };
  for (const OptionInfo& o : jobOptions())
    if (o.required && text(o.name.c_str()).empty())
      throw ParameterError("--" + o.name + " is required");
  Job job;
  job.command = command;
  job.program = text("program");
  if (job.program.empty()) throw ParameterError("no program given");
  refuseMissing(command, values, job.program);
  std::optional<ToolLibrary> library;
  const std::optional<CamoticsProject> project = readJobProgram(job, values, library);
  // Bare numbers are in the program's units; --units changes the reports only.
  const UnitSystem sys = job.path.inch ? UnitSystem::Inch : UnitSystem::Metric;
  const std::string units = text("units");
  job.units = unitSystemNamed(units).value_or(sys);
  speak = job.units;
  ToolOptions tool{text("tool"),          text("diameter"),
                   text("corner-radius"), text("taper-angle"),
                   text("tip-angle"),     text("bottom-angle"),
                   text("flute-length"),  wholeNumber(text("flutes"), "--flutes")};
  job.toolText = tool.tool;
  std::optional<AptCutter> single;
  if (!tool.tool.empty()) {
    if (tool.diameter.empty()) throw ParameterError("--diameter is required with --tool");
    single = buildCutter(tool, sys);
  } else {
    for (const char* name :
         {"diameter", "corner-radius", "taper-angle", "tip-angle", "bottom-angle", "flute-length"})
      if (!text(name).empty())
        throw ParameterError("--" + std::string(name) +
                             " describes the --tool cutter; give --tool");
  }
  // G41/G42 of a program cut with the one --tool and no table offset by its radius: the
  // program was read with --diameter in its first G20/G21's units, read again if that was not
  // the units its numbers are read in.
  if (single && !library && job.reader.toolTable.empty() &&
      job.reader.soleToolDiameter != soleToolDiameter(values, sys)) {
    ReaderOptions ro = job.reader;
    ro.soleToolDiameter = soleToolDiameter(values, sys);
    job.path = project ? readPrograms(project->files, ro) : readProgram(job.program, ro);
    job.reader = ro;
    dropWords(job);
  }
  chooseCutters(job, library, single, project ? 1 : 0);
  toolPartOptions(job, values, single, sys);
  const std::string step = text("step");
  SimulationOptions& so = job.simulation;
  so.stepLength = step.empty() ? 0.0 : parseQuantity(step, Dimension::Length, sys, "--step").value;
  if (!step.empty() && !(so.stepLength > 0.0)) throw ParameterError("--step must be positive");
  if (!text("stepover").empty())
    so.stepover = parseQuantity(text("stepover"), Dimension::Length, sys, "--stepover").value;
  if (!text("depth").empty())
    so.depth = parseQuantity(text("depth"), Dimension::Length, sys, "--depth").value;
  if (job.scheduling()) job.schedule = scheduleOptions(values, sys, job);
  so.physics = physicsOptions(values, sys);
  stockOptions(job, values, project, sys);
  startAboveStock(job, project.has_value());
  probeAgainstStock(job, project);
  // The cell follows the narrowest engagement at the program's depths (Resolution.h).
  const std::string voxel = text("voxel");
  job.voxelGiven = !voxel.empty();
  const StockModels models{job.stockModel == StockModel::Voxel || job.crossCheck,
                           job.stockModel == StockModel::Dexel || job.crossCheck};
  job.cellChoice = job.stock.box
                       ? defaultCell(job.path, job.cutters, job.stock.box, models, so.stepLength)
                       : defaultCell(job.path, job.cutters, stockFileBounds(job.stock), models,
                                     so.stepLength, false);
  job.voxel = job.voxelGiven ? parseQuantity(voxel, Dimension::Length, sys, "--voxel").value
                             : job.cellChoice.cell;
  if (!(job.voxel > 0.0)) throw ParameterError("--voxel must be positive");
  refuseAbsurdTools(job);
  outputOptions(job, values);
  job.progressLabel = commandName(command);
  return job;
}

}  // namespace

Job makeJob(JobCommand command, const OptionValues& values) {
  // The cutter's and the stock's checks speak mm; an inch run's errors speak inches.
  UnitSystem speak = UnitSystem::Metric;
  try {
    return buildJob(command, values, speak);
  } catch (const ParameterError& e) {
    if (speak == UnitSystem::Metric) throw;
    throw ParameterError(inReportUnits(e.what(), speak));
  }
}

}  // namespace engage
