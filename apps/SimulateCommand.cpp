#include "apps/SimulateCommand.h"

#include "apps/Output.h"
#include "apps/ToolOptions.h"
#include "cutters/Error.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/gcode/GcodeWriter.h"
#include "engine/model/EngagementModel.h"
#include "engine/report/Plots.h"
#include "engine/schedule/FeedScheduler.h"
#include "engine/sim/Simulation.h"
#include "engine/units/Quantity.h"
#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

namespace engage::app {
namespace {

/// A stock of the chosen model ("voxel" or "dexel") from --stock (a box in program units, or
/// a mesh in mm) at resolution h (voxel size or ray spacing).
std::unique_ptr<Stock> makeStock(const std::string& spec, const std::string& model, double h,
                                 UnitSystem sys) {
  const bool dexel = model == "dexel";
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
    if (dexel) return std::make_unique<DexelStock>(DexelStock::box(b, h));
    return std::make_unique<VoxelStock>(VoxelStock::box(b, h));
  }
  // Meshes are read in mm.
  if (dexel) return std::make_unique<DexelStock>(DexelStock::fromMesh(spec, h));
  return std::make_unique<VoxelStock>(VoxelStock::fromMesh(spec, h));
}

const char* sideName(PathSide s) {
  return s == PathSide::Concave ? "concave" : s == PathSide::Convex ? "convex" : "straight";
}

/// printf into a string.
template <typename... Args>
void appendf(std::string& out, const char* format, Args... args) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, format, args...);
  out += buf;
}

}  // namespace

SimulateOutcome runSimulateJob(const SimulateOptions& o) {
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
  ScheduleOptions sched;
  if (o.schedule) {
    if (o.targetMrr != "auto")
      sched.targetMrr =
          parseQuantity(o.targetMrr, Dimension::VolumeRate, sys, "--target-mrr").value;
    auto feedOption = [&](const std::string& text, const char* name) {
      return text.empty() ? 0.0 : parseQuantity(text, Dimension::Feed, sys, name).value;
    };
    sched.feedMin = feedOption(o.feedMin, "--feed-min");
    sched.feedMax = feedOption(o.feedMax, "--feed-max");
    sched.airFeed = feedOption(o.airFeed, "--air-feed");
    if (!o.accel.empty())
      sched.acceleration = parseQuantity(o.accel, Dimension::Acceleration, sys, "--accel").value;
    if (!o.jerk.empty()) sched.jerk = parseQuantity(o.jerk, Dimension::Jerk, sys, "--jerk").value;
    if (!o.rapidFeed.empty())
      sched.rapidFeed = parseQuantity(o.rapidFeed, Dimension::Feed, sys, "--rapid-feed").value;
    try {
      sched.minChange = std::stod(o.minChange);
    } catch (const std::exception&) {
      throw ParameterError("--min-change: expected a fraction such as 0.05, found '" + o.minChange +
                           "'");
    }
    if (!(sched.minChange > 0.0 && sched.minChange < 1.0))
      throw ParameterError("--min-change: expected a fraction in (0, 1), found " + o.minChange);
    if (!o.minSegment.empty())
      sched.minSegment = parseQuantity(o.minSegment, Dimension::Length, sys, "--min-segment").value;
    sched.analytic = o.model == "analytic";
    if (!o.forceLimit.empty()) {
      if (o.targetMrr != "auto") throw ParameterError("give either --target-mrr or --force-limit");
      if (o.specificEnergy.empty() || o.spindle.empty())
        throw ParameterError(
            "--force-limit needs --specific-energy and --spindle (paper Eq 17-18)");
      sched.targetMrr = mrrForForce(
          parseQuantity(o.forceLimit, Dimension::Force, sys, "--force-limit").value,
          parseQuantity(o.specificEnergy, Dimension::SpecificEnergy, sys, "--specific-energy")
              .value,
          2.0 * cutter.radius(),
          parseQuantity(o.spindle, Dimension::SpindleSpeed, sys, "--spindle").value);
    }
  }
  // Without a stock (schedule --model analytic only) the steps carry the analytic model
  // alone, as in the paper.
  const bool noStock = o.stock.empty();
  if (noStock && !(o.schedule && o.model == "analytic"))
    throw ParameterError("--stock is required (only schedule --model analytic runs without one)");
  if (!noStock && !o.materialSide.empty())
    throw ParameterError("--material-side applies without --stock (the stock tells the side)");
  if (o.crossCheck && noStock) throw ParameterError("--cross-check needs a --stock");
  if (!(o.crossTolerance > 0.0 && o.crossTolerance < 1.0))
    throw ParameterError("--cross-check-tolerance: expected a fraction in (0, 1)");
  std::unique_ptr<Stock> stockStore, otherStore;
  auto* voxelStock = static_cast<VoxelStock*>(nullptr);
  if (!noStock) {
    stockStore = makeStock(o.stock, o.stockModel, voxel, sys);
    if (o.crossCheck)
      otherStore = makeStock(o.stock, o.stockModel == "dexel" ? "voxel" : "dexel", voxel, sys);
    voxelStock = dynamic_cast<VoxelStock*>(stockStore.get());
  }
  if (!noStock) {
    Stock& stock = *stockStore;
    // Does the cutter ever meet the stock?
    const Box3 sb = stock.bounds();
    bool meets = false;
    const double w = cutter.maxRadius();
    for (const Move& m : path.moves) {
      // An arc can bulge up to its diameter beyond its end points.
      const double reach = w + (m.kind == MoveKind::Arc ? 2.0 * arcRadius(m) : 0.0);
      const Eigen::Vector3d lo = m.start.cwiseMin(m.end) - Eigen::Vector3d(reach, reach, 0.0);
      const Eigen::Vector3d hi =
          m.start.cwiseMax(m.end) + Eigen::Vector3d(reach, reach, cutter.height());
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
    if (voxelStock) voxelStock->captureRemoved(true);
    if (auto* dexels = dynamic_cast<DexelStock*>(stockStore.get())) dexels->captureRemoved(true);
  }

  // The output folder, made (and checked) before any work.
  const std::filesystem::path dir(o.out);
  OutputDirectory outputs(dir);

  const bool tty = isatty(2) && !o.quiet;
  auto last = std::chrono::steady_clock::now();
  if (tty)
    so.progress = [&](std::size_t done, std::size_t total) {
      const auto now = std::chrono::steady_clock::now();
      if (done < total && now - last < std::chrono::milliseconds(200)) return;
      last = now;
      std::fprintf(stderr, "\r%s: %zu / %zu steps (%.0f %%)", o.progressLabel.c_str(), done, total,
                   100.0 * static_cast<double>(done) / static_cast<double>(total));
      if (done == total) std::fprintf(stderr, "\n");
    };
  const SimulationResult r = noStock ? analyticSteps(path, cutter, so, o.materialSide != "left")
                                     : simulate(path, cutter, *stockStore, so);
  // The cross-check: the same steps through the other stock model, compared per step. A
  // step differs when its volumes differ by more than the tolerance of the larger, plus a
  // floor of four cells (steps that remove almost nothing differ by rounding alone).
  SimulationResult other;
  std::vector<char> differs;
  std::vector<std::size_t> differing;
  double worstCross = 0.0;
  const std::string otherModel = o.stockModel == "dexel" ? "voxel" : "dexel";
  if (o.crossCheck) {
    SimulationOptions oo = so;
    oo.progress = nullptr;
    other = simulate(path, cutter, *otherStore, oo);
    const double floor = 4.0 * voxel * voxel * voxel;
    differs.assign(r.steps.size(), 0);
    for (std::size_t i = 0; i < r.steps.size(); ++i) {
      const double a = r.steps[i].removed, b = other.steps[i].removed;
      const double gap = std::abs(a - b);
      if (std::max(a, b) > floor) worstCross = std::max(worstCross, gap / std::max(a, b));
      if (gap > o.crossTolerance * std::max(a, b) + floor) {
        differs[i] = 1;
        differing.push_back(i);
      }
    }
    std::stable_sort(differing.begin(), differing.end(), [&](std::size_t x, std::size_t y) {
      return std::abs(r.steps[x].removed - other.steps[x].removed) >
             std::abs(r.steps[y].removed - other.steps[y].removed);
    });
  }
  // The schedule and the re-fed program are made before any output is written.
  Schedule plan;
  std::string refed;
  if (o.schedule) {
    plan = scheduleFeeds(path, r, sched);
    refed = writeProgram(readFile(o.program), path, plan.plan);
  }

  // Outputs.
  const std::string L(unitTag(Dimension::Length, sys));
  const std::string F(unitTag(Dimension::Feed, sys));
  const std::string V(unitTag(Dimension::Volume, sys));
  const std::string Q(unitTag(Dimension::VolumeRate, sys));
  const std::string A(unitTag(Dimension::Acceleration, sys));
  // Eq 24 between the previous feed step and this one, with the scheduled feeds, mm/s^2.
  auto accelerationAt = [&](std::size_t i) {
    if (i == 0 || r.steps[i].kind == MoveKind::Rapid || r.steps[i - 1].kind == MoveKind::Rapid)
      return 0.0;
    return tangentialAcceleration(plan.feed[i - 1], plan.feed[i], r.steps[i].length);
  };
  auto D = [&](double v, Dimension d) { return formatNumber(toDisplay(v, d, sys)); };
  std::string csv =
      "step,move,line,kind,arc_length_" + L + ",x_" + L + ",y_" + L + ",z_" + L + ",feed_" + F +
      ",dt_s,removed_" + V + ",mrr_" + Q + ",width_" + L + ",depth_" + L +
      ",engagement_deg,curvature_1_" + L + ",path,mrr_exact_" + Q + ",mrr_paper_" + Q +
      ",voxels_changed" +
      (o.schedule ? ",feed_scheduled_" + F + ",binding,mrr_scheduled_" + Q + ",acceleration_" + A
                  : std::string()) +
      (o.crossCheck ? ",removed_" + otherModel + "_" + V + ",cross_check" : std::string()) + "\n";
  for (std::size_t i = 0; i < r.steps.size(); ++i) {
    const StepRecord& s = r.steps[i];
    csv +=
        std::to_string(i) + "," + std::to_string(s.move) + "," + std::to_string(s.line) + "," +
        moveKindName(s.kind) + "," + D(s.arcLength, Dimension::Length) + "," +
        D(s.end.x(), Dimension::Length) + "," + D(s.end.y(), Dimension::Length) + "," +
        D(s.end.z(), Dimension::Length) + "," + D(s.feed, Dimension::Feed) + "," +
        formatNumber(s.dt) + "," + D(s.removed, Dimension::Volume) + "," +
        D(s.mrr, Dimension::VolumeRate) + "," + D(s.width, Dimension::Length) + "," +
        D(s.depth, Dimension::Length) + "," + formatNumber(s.engagementRad * 57.29577951308232) +
        "," + formatNumber(s.curvature * displayFactor(Dimension::Length, sys)) + "," +
        sideName(s.side) + "," + D(s.mrrExact, Dimension::VolumeRate) + "," +
        D(s.mrrPaper, Dimension::VolumeRate) + "," + std::to_string(s.voxelsChanged) +
        (o.schedule
             ? "," + D(plan.feed[i], Dimension::Feed) + "," + bindingName(plan.binding[i]) + "," +
                   D(s.feed > 0 ? s.mrr * plan.feed[i] / s.feed : 0.0, Dimension::VolumeRate) +
                   "," + D(accelerationAt(i), Dimension::Acceleration)
             : std::string()) +
        (o.crossCheck ? "," + D(other.steps[i].removed, Dimension::Volume) +
                            (differs[i] ? ",differs" : ",agrees")
                      : std::string()) +
        "\n";
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
  j["stock_model"] = noStock ? std::string("none") : o.stockModel;
  j["stock_memory_bytes"] = noStock ? std::size_t(0) : stockStore->memoryBytes();
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
  if (o.crossCheck) {
    ordered_json places = ordered_json::array();
    for (std::size_t k = 0; k < differing.size() && k < 20; ++k) {
      const std::size_t i = differing[k];
      places.push_back(
          {{"step", i},
           {"line", r.steps[i].line},
           {"removed", toDisplay(r.steps[i].removed, Dimension::Volume, sys)},
           {"removed_" + otherModel, toDisplay(other.steps[i].removed, Dimension::Volume, sys)}});
    }
    j["cross_check"] = {
        {"model", o.stockModel},
        {"other_model", otherModel},
        {"tolerance_relative", o.crossTolerance},
        {"floor_volume", toDisplay(4.0 * voxel * voxel * voxel, Dimension::Volume, sys)},
        {"steps", r.steps.size()},
        {"steps_differing", differing.size()},
        {"worst_relative", worstCross},
        {"removed_" + otherModel, toDisplay(other.removed, Dimension::Volume, sys)},
        {"removed_relative_difference", r.removed > 0 ? other.removed / r.removed - 1.0 : 0.0},
        {"run_time_" + otherModel + "_s", other.seconds},
        {"memory_bytes_" + otherModel, otherStore->memoryBytes()},
        {"largest_differences", places}};
  }
  j["unit_labels"] = {{"length", std::string(unitLabel(Dimension::Length, sys))},
                      {"volume", std::string(unitLabel(Dimension::Volume, sys))},
                      {"mrr", std::string(unitLabel(Dimension::VolumeRate, sys))},
                      {"feed", std::string(unitLabel(Dimension::Feed, sys))}};
  if (o.schedule) {
    std::map<std::string, std::size_t> counts;
    ordered_json places = ordered_json::array();
    for (std::size_t i = 0; i < r.steps.size(); ++i) {
      if (plan.binding[i] == Binding::None || r.steps[i].kind == MoveKind::Rapid) continue;
      ++counts[bindingName(plan.binding[i])];
      if (places.size() < 50 && (i == 0 || plan.binding[i - 1] != plan.binding[i]))
        places.push_back(
            {{"step", i}, {"line", r.steps[i].line}, {"limit", bindingName(plan.binding[i])}});
    }
    double mrrBefore = 0.0, peakBefore = 0.0, peakAfter = 0.0, meanAfter = 0.0;
    std::size_t cutting = 0;
    for (std::size_t i = 0; i < r.steps.size(); ++i) {
      const StepRecord& s = r.steps[i];
      // Without a stock the statistics are the analytic model's.
      const double load = noStock ? s.mrrExact : s.mrr;
      if (s.kind == MoveKind::Rapid || !(load > 0.0) || plan.binding[i] == Binding::Air) continue;
      // The removal per unit length does not depend on the feed: the MRR scales with it.
      const double after = load * plan.feed[i] / s.feed;
      mrrBefore += load;
      meanAfter += after;
      peakBefore = std::max(peakBefore, load);
      peakAfter = std::max(peakAfter, after);
      ++cutting;
    }
    const double n = static_cast<double>(std::max<std::size_t>(cutting, 1));
    j["schedule"] = {
        {"target_mrr", toDisplay(plan.targetMrr, Dimension::VolumeRate, sys)},
        {"acceleration_limit", num(toDisplay(sched.acceleration, Dimension::Acceleration, sys))},
        {"max_acceleration", toDisplay(plan.maxAcceleration, Dimension::Acceleration, sys)},
        {"jerk_limit", num(toDisplay(sched.jerk, Dimension::Jerk, sys))},
        {"feed_time_before_s", plan.timeBefore},
        {"feed_time_after_s", plan.timeAfter},
        {"rapid_feed", num(toDisplay(sched.rapidFeed, Dimension::Feed, sys))},
        {"rapid_time_s", plan.rapidTime},
        {"cycle_time_before_s", plan.timeBefore + plan.rapidTime},
        {"cycle_time_after_s", plan.timeAfter + plan.rapidTime},
        {"saving_relative", plan.timeBefore > 0 ? 1.0 - plan.timeAfter / plan.timeBefore : 0.0},
        {"mrr_mean_before", toDisplay(mrrBefore / n, Dimension::VolumeRate, sys)},
        {"mrr_mean_after", toDisplay(meanAfter / n, Dimension::VolumeRate, sys)},
        {"mrr_peak_before", toDisplay(peakBefore, Dimension::VolumeRate, sys)},
        {"mrr_peak_after", toDisplay(peakAfter, Dimension::VolumeRate, sys)},
        {"feed_pieces", plan.fWords},
        {"steps_limited", counts},
        {"limited_places", places}};
  }
  writeAtomically(dir / "summary.json", j.dump(2) + "\n");
  if (o.schedule) writeAtomically(dir / std::filesystem::path(o.program).filename(), refed);
  PlotSpec ps;
  ps.folder = dir.string();
  ps.length = L;
  ps.feed = F;
  ps.rate = Q;
  ps.accelerationTag = A;
  ps.lengthLabel = unitLabel(Dimension::Length, sys);
  ps.feedLabel = unitLabel(Dimension::Feed, sys);
  ps.rateLabel = unitLabel(Dimension::VolumeRate, sys);
  ps.accelerationLabel = unitLabel(Dimension::Acceleration, sys);
  ps.schedule = o.schedule;
  ps.accelerationLimit = toDisplay(sched.acceleration, Dimension::Acceleration, sys);
  // gnuplot draws in its own process while the stock files are written (seconds each on a
  // fine grid); its outcome is collected below.
  auto plots = std::async(std::launch::async, [&ps] { return writePlots(ps); });
  std::size_t open = 0;
  if (voxelStock) {
    voxelStock->writeRemovedVdb((dir / "removed.vdb").string());
    voxelStock->writeStockVdb((dir / "stock.vdb").string());
    open = voxelStock->writeStl((dir / "stock.stl").string());
  } else if (!noStock) {
    // A dexel stock: its removal and its material as voxel fractions, for the same viewers.
    const auto& dexels = static_cast<const DexelStock&>(*stockStore);
    VoxelStock::writeRemovedVdb(dexels, (dir / "removed.vdb").string());
    const VoxelStock shown = VoxelStock::fromDexels(dexels);
    shown.writeStockVdb((dir / "stock.vdb").string());
    open = shown.writeStl((dir / "stock.stl").string());
  }
  std::string plotted;
  try {
    for (const std::string& f : plots.get())
      if (f.size() > 4 && f.compare(f.size() - 4, 4, ".png") == 0) plotted += "," + f;
  } catch (const Error& e) {
    std::fprintf(stderr, "engage: warning: plots not drawn: %s\n", e.what());
  }

  std::string report;
  appendf(report, "%zu moves, %zu steps in %.2f s (%.0f steps/s)\n", path.moves.size(),
          r.steps.size(), r.seconds, j["steps_per_second"].get<double>());
  if (noStock)
    appendf(report,
            "no stock: every feed step cut at stepover %s and depth %s, the stock on the %s of "
            "the path (the paper's analytic model)\n",
            formatQuantity(*so.stepover, Dimension::Length, sys).c_str(),
            formatQuantity(*so.depth, Dimension::Length, sys).c_str(),
            o.materialSide == "left" ? "left" : "right");
  else {
    appendf(report, "removed %s (stock %s -> %s), peak MRR %s at line %d\n",
            formatQuantity(r.removed, Dimension::Volume, sys).c_str(),
            formatQuantity(r.volumeBefore, Dimension::Volume, sys).c_str(),
            formatQuantity(r.volumeAfter, Dimension::Volume, sys).c_str(),
            r.steps.empty() ? "0"
                            : formatQuantity(r.steps[peak].mrr, Dimension::VolumeRate, sys).c_str(),
            r.steps.empty() ? 0 : r.steps[peak].line);
    appendf(report,
            "measured vs analytic (exact) on steady steps: straight %zu steps mean %.2f %%, "
            "concave %zu "
            "mean %.2f %%, convex %zu mean %.2f %%\n",
            r.straight.steps, 100 * r.straight.meanRelative, r.concave.steps,
            100 * r.concave.meanRelative, r.convex.steps, 100 * r.convex.meanRelative);
  }
  if (o.crossCheck)
    appendf(report,
            "cross-check against the %s stock: %zu of %zu steps differ by more than %.1f %% "
            "(worst %.2f %%%s), total removed differs by %.3f %% (%s run %.2f s)\n",
            otherModel.c_str(), differing.size(), r.steps.size(), 100 * o.crossTolerance,
            100 * worstCross,
            differing.empty()
                ? ""
                : (", largest at line " + std::to_string(r.steps[differing.front()].line)).c_str(),
            r.removed > 0 ? 100 * (other.removed / r.removed - 1.0) : 0.0, otherModel.c_str(),
            other.seconds);
  if (r.rapidRemoved > 0.0)
    appendf(report, "warning: rapids removed %s of material (a crash on a machine)\n",
            formatQuantity(r.rapidRemoved, Dimension::Volume, sys).c_str());
  if (open > 0) appendf(report, "warning: stock.stl has %zu open edges\n", open);
  if (o.schedule)
    appendf(
        report,
        "schedule: target %s, feed time %.1f s -> %.1f s (%.1f %% %s), largest acceleration %s, "
        "%zu feed pieces\n",
        formatQuantity(plan.targetMrr, Dimension::VolumeRate, sys).c_str(), plan.timeBefore,
        plan.timeAfter,
        plan.timeBefore > 0 ? std::abs(100.0 * (1.0 - plan.timeAfter / plan.timeBefore)) : 0.0,
        plan.timeAfter <= plan.timeBefore ? "saved" : "longer",
        formatQuantity(plan.maxAcceleration, Dimension::Acceleration, sys).c_str(), plan.fWords);
  if (o.schedule && plan.rapidTime > 0.0)
    appendf(report, "cycle time with rapids: %.1f s -> %.1f s (rapids %.1f s)\n",
            plan.timeBefore + plan.rapidTime, plan.timeAfter + plan.rapidTime, plan.rapidTime);
  const std::string programName =
      o.schedule ? "," + std::filesystem::path(o.program).filename().string() : "";
  appendf(report, "wrote %s/{steps.csv,summary.json%s%s%s}\n", o.out.c_str(),
          noStock ? "" : ",removed.vdb,stock.vdb,stock.stl", programName.c_str(), plotted.c_str());
  SimulateOutcome outcome;
  outcome.path = path;
  outcome.sim = r;
  outcome.plan = plan;
  outcome.units = sys;
  outcome.cutter = cutter;
  outcome.report = report;
  outputs.keep();
  return outcome;
}

namespace {

int runSimulate(const SimulateOptions& o) {
  std::fputs(runSimulateJob(o).report.c_str(), stdout);
  return 0;
}

CLI::App* addCommon(CLI::App& app, const char* name, const char* help, SimulateOptions& o) {
  CLI::App* cmd = app.add_subcommand(name, help);
  cmd->add_option("program", o.program, "G-code program")->required();
  addToolOptions(*cmd, o.tool, true);
  cmd->add_option("--stock", o.stock,
                  "box:X0,Y0,Z0,X1,Y1,Z1 (program units) or a closed STL/OBJ/PLY mesh (mm); "
                  "schedule --model analytic runs without one");
  cmd->add_option("--voxel", o.voxel, "voxel size (default: cutter diameter / 20)");
  cmd->add_option("--step", o.step, "longest step (default: 2.5 voxels)");
  cmd->add_option("--stepover", o.stepover,
                  "stepover for the analytic model (default: measured width)");
  cmd->add_option("--depth", o.depth,
                  "depth of cut for the analytic model (default: measured depth)");
  cmd->add_option("--out", o.out, "output folder")->capture_default_str();
  cmd->add_option("--units", o.units, "report units: mm or in (default: the program's)")
      ->check(CLI::IsMember({"mm", "in"}));
  cmd->add_option("--tool-table", o.toolTable, "LinuxCNC tool table for G43");
  cmd->add_option("--stock-model", o.stockModel,
                  "voxel (volume fractions) or dexel (vertical rays); --voxel sets the ray spacing")
      ->check(CLI::IsMember({"voxel", "dexel"}))
      ->capture_default_str();
  cmd->add_flag("--cross-check", o.crossCheck,
                "also run the other stock model and report the steps where they disagree");
  cmd->add_option("--cross-check-tolerance", o.crossTolerance,
                  "relative per-step difference allowed by --cross-check")
      ->capture_default_str();
  cmd->add_flag("--quiet", o.quiet, "no progress on the terminal");
  return cmd;
}

}  // namespace

void addSimulateCommand(CLI::App& app, std::function<int()>& run) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = addCommon(app, "simulate",
                            "sweep the cutter through a voxel stock step by step: measured removal "
                            "and engagement beside the analytic model",
                            *o);
  cmd->callback([o, &run] { run = [o] { return runSimulate(*o); }; });

  auto so = std::make_shared<SimulateOptions>();
  so->schedule = true;
  CLI::App* sc = addCommon(app, "schedule",
                           "simulate, then re-feed the program to hold the MRR at a target within "
                           "the machine's feed and acceleration limits",
                           *so);
  sc->add_option("--target-mrr", so->targetMrr, "target MRR, e.g. 18000mm3/min, or auto")
      ->capture_default_str();
  sc->add_option("--feed-min", so->feedMin, "lowest feed to command");
  sc->add_option("--feed-max", so->feedMax,
                 "highest feed to command (default: twice the programmed)");
  sc->add_option("--air-feed", so->airFeed, "feed where nothing is cut (default: the programmed)");
  sc->add_option("--accel", so->accel, "tangential acceleration limit, e.g. 2000mm/s2 or 0.3g");
  sc->add_option("--jerk", so->jerk,
                 "jerk limit, e.g. 50000mm/s3: room for the controller's S-curves");
  sc->add_option("--rapid-feed", so->rapidFeed,
                 "the machine's rapid feed, to time rapids in the cycle time, e.g. 15000mm/min");
  sc->add_option("--min-change", so->minChange, "relative step between F levels")
      ->capture_default_str();
  sc->add_option("--min-segment", so->minSegment, "shortest run of one feed along the path");
  sc->add_option("--force-limit", so->forceLimit,
                 "tangential force to hold instead of an MRR (with --specific-energy, --spindle)");
  sc->add_option("--specific-energy", so->specificEnergy, "specific cutting energy, e.g. 0.7J/mm3");
  sc->add_option("--spindle", so->spindle, "spindle speed, e.g. 12000rpm");
  sc->add_option("--material-side", so->materialSide,
                 "without --stock: the stock's side of the path (default right: climb, M3)")
      ->check(CLI::IsMember({"right", "left"}));
  sc->add_option("--model", so->model, "schedule from the measured MRR or the analytic model")
      ->check(CLI::IsMember({"measured", "analytic"}))
      ->capture_default_str();
  sc->callback([so, &run] { run = [so] { return runSimulate(*so); }; });
}

}  // namespace engage::app
