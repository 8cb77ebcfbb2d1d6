#include "apps/SimulateCommand.h"

#include "apps/ToolOptions.h"
#include "cutters/Error.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/sim/Simulation.h"
#include "engine/units/Quantity.h"
#include "stock/VoxelStock.h"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

namespace engage::app {
namespace {

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
};

/// Write text to `path` through a temporary name, so that nothing is ever half-written.
void writeAtomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".part";
  {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw Error("cannot write '" + path.string() + "'");
    f << text;
    if (!f) throw Error("cannot write '" + path.string() + "'");
  }
  std::filesystem::rename(tmp, path);
}

VoxelStock makeStock(const std::string& spec, double voxel, UnitSystem sys) {
  if (spec.rfind("box:", 0) == 0) {
    std::vector<double> v;
    std::stringstream s(spec.substr(4));
    std::string item;
    while (std::getline(s, item, ','))
      v.push_back(parseQuantity(item, Dimension::Length, sys, "--stock box").value);
    if (v.size() != 6)
      throw ParameterError("--stock: expected box:X0,Y0,Z0,X1,Y1,Z1 (six numbers), found " +
                           std::to_string(v.size()) + " in '" + spec + "'");
    Box3 b;
    b.min = {std::min(v[0], v[3]), std::min(v[1], v[4]), std::min(v[2], v[5])};
    b.max = {std::max(v[0], v[3]), std::max(v[1], v[4]), std::max(v[2], v[5])};
    return VoxelStock::box(b, voxel);
  }
  return VoxelStock::fromMesh(spec, voxel);  // meshes are read in mm
}

const char* sideName(PathSide s) {
  return s == PathSide::Concave ? "concave" : s == PathSide::Convex ? "convex" : "straight";
}

int runSimulate(const SimulateOptions& o) {
  // Everything that can be checked is checked before any work and before any output.
  ReaderOptions ro;
  ro.toolTable = o.toolTable;
  const Toolpath path = readProgram(o.program, ro);
  const UnitSystem sys = o.units == "in"   ? UnitSystem::Inch
                         : o.units == "mm" ? UnitSystem::Metric
                         : path.inch       ? UnitSystem::Inch
                                           : UnitSystem::Metric;
  const AptCutter cutter = buildCutter(o.tool, sys);
  const double voxel = o.voxel.empty()
                           ? 2.0 * cutter.radius() / 20.0
                           : parseQuantity(o.voxel, Dimension::Length, sys, "--voxel").value;
  if (!(voxel > 0.0)) throw ParameterError("--voxel must be positive");
  SimulationOptions so;
  so.stepLength =
      o.step.empty() ? 0.0 : parseQuantity(o.step, Dimension::Length, sys, "--step").value;
  if (!o.step.empty() && !(so.stepLength > 0.0)) throw ParameterError("--step must be positive");
  if (!o.stepover.empty())
    so.stepover = parseQuantity(o.stepover, Dimension::Length, sys, "--stepover").value;
  if (!o.depth.empty()) so.depth = parseQuantity(o.depth, Dimension::Length, sys, "--depth").value;
  VoxelStock stock = makeStock(o.stock, voxel, sys);
  {
    // Does the cutter ever meet the stock?
    const Box3 sb = stock.bounds();
    bool meets = false;
    const double w = cutter.maxRadius();
    for (const Move& m : path.moves) {
      const Eigen::Vector3d lo =
          m.start.cwiseMin(m.end) -
          Eigen::Vector3d(w + (m.kind == MoveKind::Arc ? arcRadius(m) * 2 : 0),
                          w + (m.kind == MoveKind::Arc ? arcRadius(m) * 2 : 0), 0);
      const Eigen::Vector3d hi =
          m.start.cwiseMax(m.end) +
          Eigen::Vector3d(w + (m.kind == MoveKind::Arc ? arcRadius(m) * 2 : 0),
                          w + (m.kind == MoveKind::Arc ? arcRadius(m) * 2 : 0), cutter.height());
      if ((lo.array() <= sb.max.array()).all() && (hi.array() >= sb.min.array()).all()) {
        meets = true;
        break;
      }
    }
    if (!meets)
      throw ParameterError("the tool path never reaches the stock (stock from " +
                           formatQuantity(sb.min.x(), Dimension::Length, sys) + ", " +
                           formatQuantity(sb.min.y(), Dimension::Length, sys) + ", " +
                           formatQuantity(sb.min.z(), Dimension::Length, sys) + " to " +
                           formatQuantity(sb.max.x(), Dimension::Length, sys) + ", " +
                           formatQuantity(sb.max.y(), Dimension::Length, sys) + ", " +
                           formatQuantity(sb.max.z(), Dimension::Length, sys) + ")");
  }
  stock.captureRemoved(true);

  const bool tty = isatty(2) && !o.quiet;
  auto last = std::chrono::steady_clock::now();
  if (tty)
    so.progress = [&](std::size_t done, std::size_t total) {
      const auto now = std::chrono::steady_clock::now();
      if (done < total && now - last < std::chrono::milliseconds(200)) return;
      last = now;
      std::fprintf(stderr, "\rsimulate: %zu / %zu steps (%.0f %%)", done, total,
                   100.0 * static_cast<double>(done) / static_cast<double>(total));
      if (done == total) std::fprintf(stderr, "\n");
    };
  const SimulationResult r = simulate(path, cutter, stock, so);

  // Outputs.
  const std::filesystem::path dir(o.out);
  std::filesystem::create_directories(dir);
  const std::string L(unitTag(Dimension::Length, sys));
  const std::string F(unitTag(Dimension::Feed, sys));
  const std::string V(unitTag(Dimension::Volume, sys));
  const std::string Q(unitTag(Dimension::VolumeRate, sys));
  auto D = [&](double v, Dimension d) { return formatNumber(toDisplay(v, d, sys)); };
  std::string csv = "step,move,line,kind,arc_length_" + L + ",x_" + L + ",y_" + L + ",z_" + L +
                    ",feed_" + F + ",dt_s,removed_" + V + ",mrr_" + Q + ",width_" + L + ",depth_" +
                    L + ",engagement_deg,curvature_1_" + L + ",path,mrr_exact_" + Q +
                    ",mrr_paper_" + Q + ",voxels_changed\n";
  for (std::size_t i = 0; i < r.steps.size(); ++i) {
    const StepRecord& s = r.steps[i];
    csv += std::to_string(i) + "," + std::to_string(s.move) + "," + std::to_string(s.line) + "," +
           moveKindName(s.kind) + "," + D(s.arcLength, Dimension::Length) + "," +
           D(s.end.x(), Dimension::Length) + "," + D(s.end.y(), Dimension::Length) + "," +
           D(s.end.z(), Dimension::Length) + "," + D(s.feed, Dimension::Feed) + "," +
           formatNumber(s.dt) + "," + D(s.removed, Dimension::Volume) + "," +
           D(s.mrr, Dimension::VolumeRate) + "," + D(s.width, Dimension::Length) + "," +
           D(s.depth, Dimension::Length) + "," + formatNumber(s.engagementRad * 57.29577951308232) +
           "," + formatNumber(s.curvature * displayFactor(Dimension::Length, sys)) + "," +
           sideName(s.side) + "," + D(s.mrrExact, Dimension::VolumeRate) + "," +
           D(s.mrrPaper, Dimension::VolumeRate) + "," + std::to_string(s.voxelsChanged) + "\n";
  }
  writeAtomically(dir / "steps.csv", csv);

  using nlohmann::ordered_json;
  auto num = [](double v) -> ordered_json {
    return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr);
  };
  auto agreement = [&](const Agreement& a) {
    return ordered_json{{"steps", a.steps},
                        {"mean_relative", num(a.meanRelative)},
                        {"max_relative", num(a.maxRelative)}};
  };
  std::size_t peak = 0;
  for (std::size_t i = 0; i < r.steps.size(); ++i)
    if (r.steps[i].mrr > r.steps[peak].mrr) peak = i;
  ordered_json j;
  j["program"] = o.program;
  j["units"] = std::string(systemName(sys));
  j["tool"] = o.tool.tool;
  j["stock"] = o.stock;
  j["voxel"] = toDisplay(voxel, Dimension::Length, sys);
  j["step_length"] =
      toDisplay(so.stepLength > 0 ? so.stepLength : 2.5 * voxel, Dimension::Length, sys);
  j["moves"] = path.moves.size();
  j["steps"] = r.steps.size();
  j["volume_before"] = toDisplay(r.volumeBefore, Dimension::Volume, sys);
  j["volume_after"] = toDisplay(r.volumeAfter, Dimension::Volume, sys);
  j["removed"] = toDisplay(r.removed, Dimension::Volume, sys);
  j["removed_vs_stock_change_relative"] =
      r.removed > 0 ? std::abs(r.removed - (r.volumeBefore - r.volumeAfter)) / r.removed : 0.0;
  j["removed_by_rapids"] = toDisplay(r.rapidRemoved, Dimension::Volume, sys);
  j["cutting_time_s"] = r.cuttingTime;
  j["run_time_s"] = r.seconds;
  j["steps_per_second"] = r.seconds > 0 ? static_cast<double>(r.steps.size()) / r.seconds : 0.0;
  j["voxels_changed"] = r.voxelsChanged;
  j["voxels_changed_per_second"] =
      r.seconds > 0 ? static_cast<double>(r.voxelsChanged) / r.seconds : 0.0;
  j["peak_mrr"] =
      r.steps.empty()
          ? ordered_json(nullptr)
          : ordered_json{{"value", toDisplay(r.steps[peak].mrr, Dimension::VolumeRate, sys)},
                         {"step", peak},
                         {"line", r.steps[peak].line}};
  j["agreement_exact"] = {{"straight", agreement(r.straight)},
                          {"concave", agreement(r.concave)},
                          {"convex", agreement(r.convex)}};
  j["agreement_paper"] = {{"straight", agreement(r.straightPaper)},
                          {"concave", agreement(r.concavePaper)},
                          {"convex", agreement(r.convexPaper)}};
  ordered_json largest = ordered_json::array();
  for (const Difference& d : r.largest)
    largest.push_back({{"step", d.step},
                       {"line", d.line},
                       {"measured", toDisplay(d.measured, Dimension::VolumeRate, sys)},
                       {"analytic", toDisplay(d.analytic, Dimension::VolumeRate, sys)},
                       {"relative", d.relative}});
  j["largest_differences"] = largest;
  j["unit_labels"] = {{"length", std::string(unitLabel(Dimension::Length, sys))},
                      {"volume", std::string(unitLabel(Dimension::Volume, sys))},
                      {"mrr", std::string(unitLabel(Dimension::VolumeRate, sys))},
                      {"feed", std::string(unitLabel(Dimension::Feed, sys))}};
  writeAtomically(dir / "summary.json", j.dump(2) + "\n");
  stock.writeRemovedVdb((dir / "removed.vdb").string());
  stock.writeStockVdb((dir / "stock.vdb").string());
  const std::size_t open = stock.writeStl((dir / "stock.stl").string());

  std::printf("%zu moves, %zu steps in %.2f s (%.0f steps/s)\n", path.moves.size(), r.steps.size(),
              r.seconds, j["steps_per_second"].get<double>());
  std::printf(
      "removed %s (stock %s -> %s), peak MRR %s at line %d\n",
      formatQuantity(r.removed, Dimension::Volume, sys).c_str(),
      formatQuantity(r.volumeBefore, Dimension::Volume, sys).c_str(),
      formatQuantity(r.volumeAfter, Dimension::Volume, sys).c_str(),
      r.steps.empty() ? "0" : formatQuantity(r.steps[peak].mrr, Dimension::VolumeRate, sys).c_str(),
      r.steps.empty() ? 0 : r.steps[peak].line);
  std::printf(
      "measured vs analytic (exact) on steady steps: straight %zu steps mean %.2f %%, concave %zu "
      "mean %.2f %%, convex %zu mean %.2f %%\n",
      r.straight.steps, 100 * r.straight.meanRelative, r.concave.steps,
      100 * r.concave.meanRelative, r.convex.steps, 100 * r.convex.meanRelative);
  if (r.rapidRemoved > 0.0)
    std::printf("warning: rapids removed %s of material (a crash on a machine)\n",
                formatQuantity(r.rapidRemoved, Dimension::Volume, sys).c_str());
  if (open > 0) std::printf("warning: stock.stl has %zu open edges\n", open);
  std::printf("wrote %s/{steps.csv,summary.json,removed.vdb,stock.vdb,stock.stl}\n", o.out.c_str());
  return 0;
}

}  // namespace

void addSimulateCommand(CLI::App& app, std::function<int()>& run) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "sweep the cutter through a voxel stock step by step: measured removal and "
      "engagement beside the analytic model");
  cmd->add_option("program", o->program, "G-code program")->required();
  addToolOptions(*cmd, o->tool, true);
  cmd->add_option("--stock", o->stock,
                  "box:X0,Y0,Z0,X1,Y1,Z1 (program units) or a closed STL/OBJ/PLY mesh (mm)")
      ->required();
  cmd->add_option("--voxel", o->voxel, "voxel size (default: cutter diameter / 20)");
  cmd->add_option("--step", o->step, "longest step (default: 2.5 voxels)");
  cmd->add_option("--stepover", o->stepover,
                  "stepover for the analytic model (default: measured width)");
  cmd->add_option("--depth", o->depth,
                  "depth of cut for the analytic model (default: measured depth)");
  cmd->add_option("--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--units", o->units, "report units: mm or in (default: the program's)")
      ->check(CLI::IsMember({"mm", "in"}));
  cmd->add_option("--tool-table", o->toolTable, "LinuxCNC tool table for G43");
  cmd->add_flag("--quiet", o->quiet, "no progress on the terminal");
  cmd->callback([o, &run] { run = [o] { return runSimulate(*o); }; });
}

}  // namespace engage::app
