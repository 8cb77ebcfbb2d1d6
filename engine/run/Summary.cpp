#include "engine/run/Summary.h"

#include "engine/run/CutterOptions.h"
#include "engine/run/StepsTable.h"
#include "engine/units/Quantity.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace engage {
namespace {

using nlohmann::ordered_json;

ordered_json num(double v) {
  return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr);
}

ordered_json agreement(const Agreement& a) {
  return ordered_json{{"steps", a.steps},
                      {"mean_relative", num(a.meanRelative)},
                      {"max_relative", num(a.maxRelative)}};
}

/// printf into a string.
template <typename... Args>
void appendf(std::string& out, const char* format, Args... args) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, format, args...);
  out += buf;
}

ordered_json crossCheckJson(const RunResult& result) {
  const Job& job = result.job;
  const UnitSystem sys = job.units;
  const CrossCheck& c = result.cross;
  const auto& steps = result.sim.steps;
  const std::string other = stockModelName(job.otherModel());
  ordered_json places = ordered_json::array();
  for (std::size_t k = 0; k < c.differing.size() && k < 20; ++k) {
    const std::size_t i = c.differing[k];
    places.push_back(
        {{"step", i},
         {"line", steps[i].line},
         {"removed", toDisplay(steps[i].removed, Dimension::Volume, sys)},
         {"removed_" + other, toDisplay(c.other.steps[i].removed, Dimension::Volume, sys)}});
  }
  const double removed = result.sim.removed;
  return {{"model", stockModelName(job.stockModel)},
          {"other_model", other},
          {"tolerance_relative", job.crossTolerance},
          {"floor_volume", toDisplay(c.floorVolume, Dimension::Volume, sys)},
          {"steps", steps.size()},
          {"steps_differing", c.differing.size()},
          {"worst_relative", c.worstRelative},
          {"removed_" + other, toDisplay(c.other.removed, Dimension::Volume, sys)},
          {"removed_relative_difference", removed > 0 ? c.other.removed / removed - 1.0 : 0.0},
          {"run_time_" + other + "_s", c.other.seconds},
          {"memory_bytes_" + other, c.otherMemoryBytes},
          {"largest_differences", places}};
}

/// Per source line whose feed the schedule changed or held: its programmed feed, the
/// scheduled feeds' range and what bound them (binding names, most steps first).
struct LineFeeds {
  int file = 0, line = 0;
  double programmed = 0.0, lowest = 0.0, highest = 0.0;
  std::map<std::string, std::size_t> bound;
};

std::vector<LineFeeds> scheduledLines(const RunResult& result) {
  const auto& steps = result.sim.steps;
  const Schedule& plan = result.plan;
  std::map<std::pair<int, int>, LineFeeds> lines;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const StepRecord& s = steps[i];
    if (s.kind == MoveKind::Rapid || !(s.feed > 0.0) || i >= plan.feed.size()) continue;
    const int file = result.job.path.moves[s.move].file;
    auto [it, fresh] = lines.try_emplace({file, s.line});
    LineFeeds& l = it->second;
    if (fresh) {
      l.file = file;
      l.line = s.line;
      l.programmed = s.feed;
      l.lowest = l.highest = plan.feed[i];
    }
    l.lowest = std::min(l.lowest, plan.feed[i]);
    l.highest = std::max(l.highest, plan.feed[i]);
    if (plan.binding[i] != Binding::None) ++l.bound[bindingName(plan.binding[i])];
  }
  std::vector<LineFeeds> out;
  for (auto& [key, l] : lines)
    if (!l.bound.empty() || l.lowest != l.programmed || l.highest != l.programmed)
      out.push_back(std::move(l));
  return out;
}

/// The first 200 of scheduledLines (summary.json stays small on long programs).
ordered_json linesJson(const RunResult& result, const std::vector<LineFeeds>& lines) {
  const UnitSystem sys = result.job.units;
  ordered_json out = ordered_json::array();
  for (const LineFeeds& l : lines) {
    if (out.size() >= 200) break;
    std::vector<std::pair<std::size_t, std::string>> by;
    for (const auto& [name, count] : l.bound)
      by.emplace_back(count, name);
    std::sort(by.begin(), by.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    ordered_json bound = ordered_json::array();
    for (const auto& [count, name] : by)
      bound.push_back({{"limit", name}, {"steps", count}});
    out.push_back({{"file", l.file},
                   {"line", l.line},
                   {"feed_programmed", toDisplay(l.programmed, Dimension::Feed, sys)},
                   {"feed_lowest", toDisplay(l.lowest, Dimension::Feed, sys)},
                   {"feed_highest", toDisplay(l.highest, Dimension::Feed, sys)},
                   {"bound_by", bound}});
  }
  return out;
}

/// The re-simulated re-fed program's checks (null without a stock).
ordered_json verificationJson(const RunResult& result) {
  const Verification& v = result.verified;
  if (!v.done) return nullptr;
  const UnitSystem sys = result.job.units;
  ordered_json checks = ordered_json::array();
  for (const LimitCheck& c : v.checks)
    checks.push_back({{"option", c.option},
                      {"limit", toDisplay(c.limit, c.dimension, sys)},
                      {"worst", toDisplay(c.worst, c.dimension, sys)},
                      {"line", c.line},
                      {"holds", c.holds},
                      {"unit", std::string(unitLabel(c.dimension, sys))}});
  return {{"steps", v.steps},
          {"run_time_s", v.seconds},
          {"removed", toDisplay(v.removed, Dimension::Volume, sys)},
          {"tolerance_relative", kVerifyTolerance},
          {"checks", checks}};
}

ordered_json scheduleJson(const RunResult& result) {
  const UnitSystem sys = result.job.units;
  const ScheduleOptions& sched = result.job.schedule;
  const Schedule& plan = result.plan;
  const auto& steps = result.sim.steps;
  std::map<std::string, std::size_t> counts;
  ordered_json places = ordered_json::array();
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (plan.binding[i] == Binding::None || steps[i].kind == MoveKind::Rapid) continue;
    ++counts[bindingName(plan.binding[i])];
    if (places.size() < 50 && (i == 0 || plan.binding[i - 1] != plan.binding[i]))
      places.push_back(
          {{"step", i}, {"line", steps[i].line}, {"limit", bindingName(plan.binding[i])}});
  }
  double mrrBefore = 0.0, peakBefore = 0.0, peakAfter = 0.0, meanAfter = 0.0;
  std::size_t cutting = 0;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const StepRecord& s = steps[i];
    // Without a stock the statistics are the analytic model's.
    const double load = result.stock ? s.mrr : s.mrrExact;
    if (s.kind == MoveKind::Rapid || !(load > 0.0) || plan.binding[i] == Binding::Air) continue;
    // The removal per unit length does not depend on the feed: the MRR scales with it.
    const double after = load * feedScale(result, i);
    mrrBefore += load;
    meanAfter += after;
    peakBefore = std::max(peakBefore, load);
    peakAfter = std::max(peakAfter, after);
    ++cutting;
  }
  const double n = static_cast<double>(std::max<std::size_t>(cutting, 1));
  auto rate = [&](double v) { return toDisplay(v, Dimension::VolumeRate, sys); };
  ordered_json limits = ordered_json::object();
  if (sched.maxChip > 0) limits["max_chip"] = toDisplay(sched.maxChip, Dimension::Length, sys);
  if (sched.maxForce > 0) limits["max_force"] = toDisplay(sched.maxForce, Dimension::Force, sys);
  if (sched.maxTorque > 0)
    limits["max_torque"] = toDisplay(sched.maxTorque, Dimension::Torque, sys);
  if (sched.maxPower > 0) limits["max_power"] = toDisplay(sched.maxPower, Dimension::Power, sys);
  const std::vector<LineFeeds> lines = scheduledLines(result);
  return {{"target_mrr", plan.targetMrr > 0 ? ordered_json(rate(plan.targetMrr)) : nullptr},
          {"physics_limits", limits},
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
          {"mrr_mean_before", rate(mrrBefore / n)},
          {"mrr_mean_after", rate(meanAfter / n)},
          {"mrr_peak_before", rate(peakBefore)},
          {"mrr_peak_after", rate(peakAfter)},
          {"feed_pieces", plan.fWords},
          {"noise_relative", plan.noise},
          {"steps_limited", counts},
          {"limited_places", places},
          {"lines", linesJson(result, lines)},
          {"lines_count", lines.size()},
          {"verified", verificationJson(result)}};
}

/// The peaks of a run's cutting physics (SimulationResult::loads), at the programmed feeds or,
/// with `scheduled`, at the scheduled ones: per quantity the largest value and its step.
struct PhysicsPeaks {
  double value[4] = {0, 0, 0, 0};  ///< h_max, peak force, torque, power
  std::size_t step[4] = {0, 0, 0, 0};
};

PhysicsPeaks physicsPeaks(const RunResult& result, bool scheduled) {
  PhysicsPeaks p;
  const auto& loads = result.sim.loads;
  for (std::size_t i = 0; i < loads.size(); ++i) {
    ScaledLoad a{loads[i].hMax, loads[i].peak, loads[i].torque, loads[i].power};
    if (scheduled) a = scaleLoad(loads[i], feedScale(result, i));
    const double v[4] = {a.hMax, a.peak, a.torque, a.power};
    for (int k = 0; k < 4; ++k)
      if (v[k] > p.value[k]) {  // NaN (no model) never wins
        p.value[k] = v[k];
        p.step[k] = i;
      }
  }
  return p;
}

ordered_json physicsJson(const RunResult& result) {
  const Job& job = result.job;
  const UnitSystem sys = job.units;
  const PhysicsOptions& o = *job.simulation.physics;
  const Material& m = o.material;
  const bool linear = m.model == ForceModel::Linear;
  ordered_json coefficients =
      linear ? ordered_json{{"Ktc_N_mm2", m.linear.Ktc}, {"Krc_N_mm2", m.linear.Krc},
                            {"Kac_N_mm2", m.linear.Kac}, {"Kte_N_mm", m.linear.Kte},
                            {"Kre_N_mm", m.linear.Kre},  {"Kae_N_mm", m.linear.Kae}}
             : ordered_json{{"kc11_N_mm2", m.kienzle.kc11}, {"mc", m.kienzle.mc},
                            {"kf11_N_mm2", m.kienzle.kf11}, {"mf", m.kienzle.mf},
                            {"kp11_N_mm2", m.kienzle.kp11}, {"mp", m.kienzle.mp}};
  auto peaks = [&](const PhysicsPeaks& p) {
    const Dimension dims[4] = {Dimension::Length, Dimension::Force, Dimension::Torque,
                               Dimension::Power};
    const char* names[4] = {"h_max", "f_peak", "torque", "power"};
    ordered_json j;
    for (int k = 0; k < 4; ++k)
      j[names[k]] = {{"value", toDisplay(p.value[k], dims[k], sys)},
                     {"step", p.step[k]},
                     {"line", result.sim.steps.empty() ? 0 : result.sim.steps[p.step[k]].line}};
    return j;
  };
  ordered_json j = {
      {"material", m.name},
      {"file", m.path},
      {"model", linear ? "linear" : "kienzle"},
      {"coefficients", coefficients},
      {"source", m.source},
      {"conditions", m.conditions},
      {"helix_deg", std::round(o.helix * kDegPerRad * 1e9) / 1e9},
      {"peaks", peaks(physicsPeaks(result, false))},
      {"steps_without_model",
       {{"plunge", result.sim.plungeSteps}, {"spindle_stopped", result.sim.stoppedSteps}}},
      {"unit_labels",
       {{"chip", std::string(unitLabel(Dimension::Length, sys))},
        {"force", std::string(unitLabel(Dimension::Force, sys))},
        {"torque", std::string(unitLabel(Dimension::Torque, sys))},
        {"power", std::string(unitLabel(Dimension::Power, sys))}}}};
  if (job.scheduling()) j["peaks_scheduled"] = peaks(physicsPeaks(result, true));
  return j;
}

/// What one tool did in a run.
struct ToolTotals {
  double removed = 0.0, time = 0.0, peak = -1.0;
  std::size_t peakStep = 0, steps = 0;
  int firstLine = 0;
};

/// Per tool number the steps ran with: removed volume, cutting time, peak MRR (the analytic one
/// without a stock).
std::map<int, ToolTotals> toolTotals(const RunResult& result) {
  std::map<int, ToolTotals> totals;
  const auto& steps = result.sim.steps;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const StepRecord& s = steps[i];
    ToolTotals& t = totals[s.tool];
    if (t.steps++ == 0) t.firstLine = s.line;
    if (std::isfinite(s.removed)) t.removed += s.removed;
    t.time += s.dt;
    const double load = result.stock ? s.mrr : s.mrrExact;
    if (std::isfinite(load) && load > t.peak * (1.0 + kSamePeak)) {  // (the first, as peakStep)
      t.peak = load;
      t.peakStep = i;
    }
  }
  return totals;
}

/// The library number of the steps of tool `tool`: tool 0 (before any change) is the start
/// tool when the library gives it.
int libraryNumber(const Job& job, int tool) {
  return tool == 0 && job.startTool != 0 ? job.startTool : tool;
}

/// The source file of a collision's move.
const std::string& fileOf(const Job& job, const Collision& c) {
  return job.path.files[static_cast<std::size_t>(job.path.moves[c.move].file)];
}

/// The tool's name: the library's (else its kind and diameter), else --tool's.
std::string toolName(const Job& job, int tool) {
  const auto entry = job.tools.find(libraryNumber(job, tool));
  if (entry == job.tools.end()) return job.toolText;
  const ToolEntry& e = entry->second;
  if (!e.name.empty()) return e.name;
  return e.kind + " " + formatQuantity(2.0 * e.cutter->maxRadius(), Dimension::Length, job.units);
}

/// Per tool the program ran with: its cutter, what it removed, its peak MRR, its time.
ordered_json toolsJson(const RunResult& result) {
  const Job& job = result.job;
  const UnitSystem sys = job.units;
  const auto& steps = result.sim.steps;
  const std::map<int, ToolTotals> totals = toolTotals(result);
  ordered_json out = ordered_json::array();
  for (const auto& [tool, t] : totals) {
    const auto entry = job.tools.find(libraryNumber(job, tool));
    ordered_json j{{"number", tool}};
    if (libraryNumber(job, tool) != tool) j["taken_as"] = job.startTool;
    j["name"] = toolName(job, tool);
    if (entry != job.tools.end()) j["defined_at"] = entry->second.origin;
    j["cutter"] = describeCutter(job.cutters.of(tool), sys);
    j["first_line"] = t.firstLine;
    j["steps"] = t.steps;
    j["removed"] =
        result.stock ? num(toDisplay(t.removed, Dimension::Volume, sys)) : ordered_json(nullptr);
    j["cutting_time_s"] = t.time;
    j["peak_mrr"] = t.peak > 0.0
                        ? ordered_json{{"value", toDisplay(t.peak, Dimension::VolumeRate, sys)},
                                       {"step", t.peakStep},
                                       {"line", steps[t.peakStep].line}}
                        : ordered_json(nullptr);
    if (job.scheduling()) {
      const auto target = result.plan.targets.find(tool);
      j["target_mrr"] = target != result.plan.targets.end() && target->second > 0.0
                            ? ordered_json(toDisplay(target->second, Dimension::VolumeRate, sys))
                            : ordered_json(nullptr);
    }
    out.push_back(j);
  }
  return out;
}

/// The final stock against --part: the limits, and the regions (the first 100 of each kind,
/// largest volume first; a gouge with the lines that cut its floor, the first 20).
ordered_json partJson(const RunResult& result) {
  const PartCheck& c = result.part;
  const UnitSystem sys = result.job.units;
  auto L = [&](double v) { return num(toDisplay(v, Dimension::Length, sys)); };
  auto regions = [&](const std::vector<DeviationRegion>& list, bool gouge) {
    ordered_json a = ordered_json::array();
    double volume = 0.0;
    for (const DeviationRegion& r : list)
      volume += r.volume;
    for (std::size_t i = 0; i < list.size() && i < 100; ++i) {
      const DeviationRegion& r = list[i];
      ordered_json o{{gouge ? "depth" : "thickness", L(r.extreme)},
                     {"area", num(toDisplay(r.area, Dimension::Area, sys))},
                     {"volume", num(toDisplay(r.volume, Dimension::Volume, sys))},
                     {"at", {L(r.at.x()), L(r.at.y()), L(r.at.z())}}};
      if (gouge) {
        ordered_json lines = ordered_json::array();
        const std::vector<GougeLine> by = gougeLines(r, result.job.path, result.sim.steps);
        for (std::size_t k = 0; k < by.size() && k < 20; ++k)
          lines.push_back({{"file", result.job.path.files[static_cast<std::size_t>(by[k].file)]},
                           {"line", by[k].line},
                           {"floor_area", num(toDisplay(by[k].area, Dimension::Area, sys))},
                           {"first_step", by[k].steps.front()}});
        o["lines"] = lines;
      }
      a.push_back(o);
    }
    return ordered_json{
        {"count", list.size()},
        {gouge ? "deepest" : "thickest", L(gouge ? c.deepestGouge() : c.thickestLeftover())},
        {"volume", num(toDisplay(volume, Dimension::Volume, sys))},
        {"regions", a}};
  };
  return {{"file", c.spec.file},
          {"tolerance", L(c.spec.tolerance)},
          {"allowance", L(c.spec.allowance)},
          {"area", num(toDisplay(c.area, Dimension::Area, sys))},
          {"volume", num(toDisplay(c.partVolume, Dimension::Volume, sys))},
          {"sample_size", L(c.spacing)},
          {"samples", c.samples},
          {"gouges", regions(c.gouges, true)},
          {"leftovers", regions(c.leftovers, false)},
          {"missing", regions(c.missing, true)},
          {"seconds", c.seconds}};
}

}  // namespace

std::string summaryJson(const RunResult& result) {
  const Job& job = result.job;
  const UnitSystem sys = job.units;
  const SimulationResult& r = result.sim;
  const std::size_t peak = result.peakStep;
  ordered_json j;
  j["program"] = job.program;
  if (!job.projectFiles.empty()) j["project_programs"] = job.projectFiles;
  j["units"] = std::string(systemName(sys));
  j["tool"] = job.toolText;
  if (!job.toolsFile.empty())
    j["tool_library"] = {{"file", job.toolsFile}, {"format", job.toolsFormat}};
  j["tools"] = toolsJson(result);
  j["stock"] = job.stock.text;
  j["voxel"] = toDisplay(job.voxel, Dimension::Length, sys);
  j["cell_reason"] = job.voxelGiven ? std::string("--voxel") : describeCell(job.cellChoice, sys);
  j["step_length"] = toDisplay(job.stepLength(), Dimension::Length, sys);
  j["moves"] = job.path.moves.size();
  j["steps"] = r.steps.size();
  j["volume_before"] = toDisplay(r.volumeBefore, Dimension::Volume, sys);
  j["volume_after"] = toDisplay(r.volumeAfter, Dimension::Volume, sys);
  j["removed"] = toDisplay(r.removed, Dimension::Volume, sys);
  j["removed_vs_stock_change_relative"] =
      r.removed > 0 ? std::abs(r.removed - (r.volumeBefore - r.volumeAfter)) / r.removed : 0.0;
  j["removed_by_rapids"] = toDisplay(r.rapidRemoved, Dimension::Volume, sys);
  {
    // What must not cut and met material: rapids, shanks, holders (the first 1000 places).
    ordered_json list = ordered_json::array();
    for (std::size_t i = 0; i < r.collisions.size() && i < 1000; ++i) {
      const Collision& c = r.collisions[i];
      list.push_back({{"file", fileOf(job, c)},
                      {"line", c.line},
                      {"tool", c.tool},
                      {"part", c.part},
                      {"first_step", c.firstStep},
                      {"last_step", c.lastStep},
                      {"volume", toDisplay(c.volume, Dimension::Volume, sys)}});
    }
    j["collisions"] = {{"count", r.collisions.size()}, {"places", list}};
  }
  j["cutting_time_s"] = r.cuttingTime;
  j["run_time_s"] = r.seconds;
  j["steps_per_second"] = r.seconds > 0 ? static_cast<double>(r.steps.size()) / r.seconds : 0.0;
  j["stock_model"] = result.stock ? std::string(stockModelName(job.stockModel)) : "none";
  j["stock_memory_bytes"] = result.stock ? result.stock->memoryBytes() : std::size_t(0);
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
  j["analytic_not_applied"] = {{"oblique_tool_steps", r.obliqueSteps}};
  ordered_json largest = ordered_json::array();
  for (const Difference& d : r.largest)
    largest.push_back({{"step", d.step},
                       {"line", d.line},
                       {"measured", toDisplay(d.measured, Dimension::VolumeRate, sys)},
                       {"analytic", toDisplay(d.analytic, Dimension::VolumeRate, sys)},
                       {"relative", d.relative}});
  j["largest_differences"] = largest;
  if (result.crossChecked) j["cross_check"] = crossCheckJson(result);
  j["unit_labels"] = {{"length", std::string(unitLabel(Dimension::Length, sys))},
                      {"volume", std::string(unitLabel(Dimension::Volume, sys))},
                      {"mrr", std::string(unitLabel(Dimension::VolumeRate, sys))},
                      {"feed", std::string(unitLabel(Dimension::Feed, sys))}};
  if (job.scheduling()) j["schedule"] = scheduleJson(result);
  if (job.simulation.physics) j["physics"] = physicsJson(result);
  if (result.part.done) j["part"] = partJson(result);
  return j.dump(2) + "\n";
}

namespace {

/// Line numbers, sorted, each once: "4, 6, 9" (the first eight, then "and N more").
std::string lineList(std::vector<int> lines) {
  std::sort(lines.begin(), lines.end());
  lines.erase(std::unique(lines.begin(), lines.end()), lines.end());
  std::string named;
  for (std::size_t i = 0; i < lines.size() && i < 8; ++i)
    named += (i ? ", " : "") + std::to_string(lines[i]);
  if (lines.size() > 8) named += " and " + std::to_string(lines.size() - 8) + " more";
  return named;
}

}  // namespace

std::string unmetLimits(const RunResult& result) {
  const Schedule& plan = result.plan;
  const UnitSystem sys = result.job.units;
  std::string text;
  for (const PhysicsLimit& k : kPhysicsLimits) {
    std::vector<int> lines;
    const UnmetLimit* worst = nullptr;
    std::size_t steps = 0;
    for (const UnmetLimit& u : plan.unmet) {
      if (u.limit != k.binding) continue;
      ++steps;
      const int line = result.sim.steps[u.step].line;
      if (lines.empty() || lines.back() != line) lines.push_back(line);
      if (!worst || u.load > worst->load) worst = &u;
    }
    if (!worst) continue;
    const std::string named = lineList(lines);
    if (!text.empty()) text += "; ";
    text += std::string(k.option) + " " + formatQuantity(worst->value, k.dimension, sys) +
            " cannot be met on " + std::to_string(steps) + " step(s) of line(s) " + named +
            ": at the lowest feed allowed line " +
            std::to_string(result.sim.steps[worst->step].line) + " still carries " +
            formatQuantity(worst->load, k.dimension, sys) + " at " +
            (worst->feed > 0.0 ? formatQuantity(worst->feed, Dimension::Feed, sys)
                               : std::string("a tenth of its programmed rate (the tool turning "
                                             "about its standing tip)"));
  }
  return text;
}

std::vector<std::string> runWarnings(const RunResult& result, const WrittenOutputs& written) {
  const Job& job = result.job;
  auto length = [&](double v) { return formatQuantity(v, Dimension::Length, job.units); };
  std::vector<std::string> w;
  // Units nobody gave: the program sets neither G20 nor G21 and the machine's are assumed.
  if (!job.path.unitsSet && !job.startupUnitsGiven && !job.path.moves.empty())
    w.push_back(
        "the program sets neither G20 nor G21: read in mm, as a machine that starts up "
        "in mm would (give the machine's start-up units: --startup-units in, or "
        "\"startup_units\" in the --machine file)");
  // M codes taken as moving nothing, each with its first lines.
  {
    std::map<int, std::vector<std::string>> where;
    for (const Toolpath::InertCode& c : job.path.inert) {
      auto& at = where[c.code];
      const std::string place =
          (c.file == 0 ? std::string() : job.path.files[static_cast<std::size_t>(c.file)] + ":") +
          std::to_string(c.line);
      if (at.size() < 4 && std::find(at.begin(), at.end(), place) == at.end()) at.push_back(place);
    }
    std::string list;
    for (const auto& [code, at] : where) {
      std::string lines;
      for (const std::string& a : at)
        lines += (lines.empty() ? "" : ", ") + a;
      list += (list.empty() ? "" : "; ") +
              ("M" + std::to_string(code) + (at.size() > 1 ? " (lines " : " (line ") + lines + ")");
    }
    if (!where.empty())
      w.push_back(list +
                  ": M codes engage does not know, taken as machine functions that move no axis "
                  "(a chip conveyor, a user M code's script); check them on the machine");
  }
  if (job.probesOnBounds)
    w.push_back(
        "probing moves stopped on the bounding box of the stock file, not its surface "
        "(give a box stock for exact contacts)");
  // Control compensation that offset nothing: the control would use its register.
  if (!job.path.unoffsetCompensation.empty()) {
    std::string lines;
    std::size_t shown = 0;
    for (const Toolpath::Place& p : job.path.unoffsetCompensation) {
      if (++shown > 4) break;
      lines +=
          (lines.empty() ? "" : ", ") +
          (p.file == 0 ? std::string() : job.path.files[static_cast<std::size_t>(p.file)] + ":") +
          std::to_string(p.line);
    }
    w.push_back("G41/G42 offset the path by nothing (line" +
                std::string(job.path.unoffsetCompensation.size() > 1 ? "s " : " ") + lines +
                "): D0, or a tool without a diameter; on the machine the control offsets by its "
                "register (give the tools' diameters with --tools or --tool-table, or "
                "--cutter-comp wear when the path is already the tool centre's)");
  }
  // Where the answer cannot be trusted: a grid too coarse for the tool or the stock.
  // The diameter the narrowest-cutting tool engages at the program's depths (Resolution.h).
  const ProgramEngagement& e = job.cellChoice.engagement;
  if (result.stock && e.engaged / job.voxel < 5.0)
    w.push_back("the cell (" + length(job.voxel) + ") is coarse for the " + length(e.engaged) +
                (e.known && e.engaged < e.nominal
                     ? " the " + length(e.nominal) + " tool engages at " + length(e.depth) + " deep"
                     : " tool") +
                ", fewer than 5 cells across it: volumes may be off by several percent (a "
                "twentieth is " +
                length(e.engaged / 20.0) + ")");
  if (result.stock) {
    const Box3 b = result.stock->bounds();
    const double smallest = (b.max - b.min).minCoeff();
    if (job.voxel > smallest)
      w.push_back("the voxel (" + length(job.voxel) +
                  ") is larger than the stock's smallest side (" + length(smallest) + ")");
    if (result.sim.removed <= 0.0)
      w.push_back(
          "the run removed no material: the path never cuts the stock (check its "
          "position, the program's Z and units)");
  }
  // Feeds no machine runs: 100 m/min is beyond the fastest milling machines' cutting feeds.
  constexpr double kFastestFeed = 100000.0;  // mm/min
  std::size_t fast = 0;
  const Move* first = nullptr;
  for (const Move& m : job.path.moves)
    if (m.kind != MoveKind::Rapid && m.feed > kFastestFeed && ++fast == 1) first = &m;
  if (first)
    w.push_back(std::to_string(fast) + " move(s) feed faster than 100 m/min, first at line " +
                std::to_string(first->line) + " (" +
                formatQuantity(first->feed, Dimension::Feed, job.units) +
                "): no machine cuts so fast; are the feeds in the program's units?");
  if (result.sim.rapidRemoved > 0.0)
    w.push_back("rapids removed " +
                formatQuantity(result.sim.rapidRemoved, Dimension::Volume, result.job.units) +
                " of material (a crash on a machine)");
  if (job.startTool != 0) {
    double before = 0.0;
    int line = 0;
    for (const StepRecord& s : result.sim.steps)
      if (s.tool == 0 && std::isfinite(s.removed) && s.removed > 0.0) {
        before += s.removed;
        if (line == 0) line = s.line;
      }
    if (before > 0.0)
      w.push_back("moves before the program's first tool change cut " +
                  formatQuantity(before, Dimension::Volume, job.units) + " (from line " +
                  std::to_string(line) + ") with T" + std::to_string(job.startTool) +
                  (job.projectFiles.empty() ? ", its first tool"
                                            : ", the tool CAMotics selects when none is") +
                  ": give --tool for the tool in the spindle at the start");
  }
  // A LinuxCNC table is in the machine's units, which the program does not tell: an inch
  // program whose tools all come out under 1 mm across most likely has an inch table.
  if (job.toolsFormat == "linuxcnc" && job.path.inch && !job.toolTableInch && !job.tools.empty()) {
    bool tiny = true;
    std::string example;
    for (const auto& [number, entry] : job.tools) {
      if (!entry.cutter) continue;
      const double d = 2.0 * entry.cutter->maxRadius();
      tiny = tiny && d < 1.0;
      if (example.empty()) example = "T" + std::to_string(number) + " " + formatNumber(d) + " mm";
    }
    if (tiny && !example.empty())
      w.push_back(
          "the LinuxCNC tool table was read in mm (--tool-table-units mm), "
          "and every tool this inch program loads is under 1 mm across (" +
          example + "): if the table is in inches, give --tool-table-units in");
  }
  if (written.openEdges > 0)
    w.push_back("stock.stl has " + std::to_string(written.openEdges) + " open edges");
  if (result.sim.plungeSteps > 0)
    w.push_back(std::to_string(result.sim.plungeSteps) +
                " cutting step(s) plunge straight down with a cutter whose end is not flat (a "
                "ball's or a cone's point): the force model does not cover that cut; their chip "
                "and forces are left empty (NaN)");
  for (const LimitCheck& c : result.verified.checks)
    if (!c.holds)
      w.push_back("the re-fed program, re-simulated, exceeds " + c.option + " " +
                  formatQuantity(c.limit, c.dimension, job.units) + ": " +
                  formatQuantity(c.worst, c.dimension, job.units) + " at its line " +
                  std::to_string(c.line));
  if (job.scheduling() && !result.plan.unmet.empty())
    w.push_back(unmetLimits(result) + ": written anyway (--allow-unmet)");
  if (job.scheduling()) {
    std::vector<int> lines;
    for (std::size_t i = 0; i < result.plan.binding.size(); ++i)
      if (result.plan.binding[i] == Binding::Unmodelled &&
          (lines.empty() || lines.back() != result.sim.steps[i].line))
        lines.push_back(result.sim.steps[i].line);
    if (!lines.empty()) {
      std::string why;
      if (job.schedule.analytic)
        why =
            "the analytic model has no value where a step cuts with a tool oblique to the "
            "part, a retract or an arc tighter than the cutter";
      if (!job.schedule.analytic || job.simulation.physics)
        why += std::string(why.empty() ? "" : ", and ") +
               "the force model does not cover what a ball's, a cone's or a corner radius's "
               "end cuts where the tool descends (plunges, ramps, helices), nor a stopped "
               "spindle";
      w.push_back(why + ": those feeds were kept at most as programmed (line(s) " +
                  lineList(lines) + ")");
    }
  }
  if (result.sim.obliqueSteps > 0)
    w.push_back(std::to_string(result.sim.obliqueSteps) +
                " cutting step(s) of a tool tilted off the part's X, Y and Z, or whose axis "
                "turns: the analytic model (the paper's, for a tool square to the faces it cuts) "
                "does not apply there; their analytic MRR is left empty (NaN) and out of the "
                "comparison");
  if (result.sim.stoppedSteps > 0)
    w.push_back(std::to_string(result.sim.stoppedSteps) +
                " cutting step(s) with the spindle stopped or no S word: no chip or forces; "
                "give --spindle");
  return w;
}

std::string runReport(const RunResult& result, const WrittenOutputs& written) {
  const Job& job = result.job;
  const UnitSystem sys = job.units;
  const SimulationResult& r = result.sim;
  const Schedule& plan = result.plan;
  auto q = [&](double v, Dimension d) { return formatQuantity(v, d, sys); };
  std::string report;
  appendf(report, "%zu moves, %zu steps in %.2f s (%.0f steps/s)\n", job.path.moves.size(),
          r.steps.size(), r.seconds,
          r.seconds > 0 ? static_cast<double>(r.steps.size()) / r.seconds : 0.0);
  if (result.stock && !job.voxelGiven)
    appendf(report, "cell %s\n", describeCell(job.cellChoice, sys).c_str());
  if (!result.stock)
    appendf(report,
            "no stock: every feed step cut at stepover %s and depth %s, the stock on the %s of "
            "the path (the paper's analytic model)\n",
            q(*job.simulation.stepover, Dimension::Length).c_str(),
            q(*job.simulation.depth, Dimension::Length).c_str(),
            job.materialOnRight ? "right" : "left");
  else {
    const std::size_t peak = result.peakStep;
    appendf(report, "removed %s (stock %s -> %s), peak MRR %s at line %d\n",
            q(r.removed, Dimension::Volume).c_str(), q(r.volumeBefore, Dimension::Volume).c_str(),
            q(r.volumeAfter, Dimension::Volume).c_str(),
            r.steps.empty() ? "0" : q(r.steps[peak].mrr, Dimension::VolumeRate).c_str(),
            r.steps.empty() ? 0 : r.steps[peak].line);
    appendf(report,
            "measured vs analytic (exact) on steady steps: straight %zu steps mean %.2f %%, "
            "concave %zu "
            "mean %.2f %%, convex %zu mean %.2f %%\n",
            r.straight.steps, 100 * r.straight.meanRelative, r.concave.steps,
            100 * r.concave.meanRelative, r.convex.steps, 100 * r.convex.meanRelative);
  }
  if (const auto totals = toolTotals(result); totals.size() > 1)
    for (const auto& [tool, t] : totals)
      appendf(report, "  T%d %s: removed %s, peak MRR %s at line %d, cutting time %.1f s\n", tool,
              toolName(job, tool).c_str(),
              result.stock ? q(t.removed, Dimension::Volume).c_str() : "-",
              t.peak > 0.0 ? q(t.peak, Dimension::VolumeRate).c_str() : "0",
              t.peak > 0.0 ? r.steps[t.peakStep].line : 0, t.time);
  if (result.crossChecked) {
    const CrossCheck& c = result.cross;
    const std::string other = stockModelName(job.otherModel());
    appendf(report,
            "cross-check against the %s stock: %zu of %zu steps differ by more than %.1f %% + %s "
            "(four cells, for rounding)%s; the largest relative gap on steps above four cells is "
            "%.2f %%; total removed differs by %.3f %% (%s run %.2f s)\n",
            other.c_str(), c.differing.size(), r.steps.size(), 100 * job.crossTolerance,
            q(c.floorVolume, Dimension::Volume).c_str(),
            c.differing.empty()
                ? ""
                : (", the largest at line " + std::to_string(r.steps[c.differing.front()].line))
                      .c_str(),
            100 * c.worstRelative, r.removed > 0 ? 100 * (c.other.removed / r.removed - 1.0) : 0.0,
            other.c_str(), c.other.seconds);
  }
  if (job.simulation.physics) {
    // The peaks of the cutting physics, and after scheduling.
    for (const bool scheduled : {false, true}) {
      if (scheduled && !job.scheduling()) continue;
      const PhysicsPeaks p = physicsPeaks(result, scheduled);
      auto line = [&](int k) { return r.steps.empty() ? 0 : r.steps[p.step[k]].line; };
      appendf(
          report, "%s: peak chip %s (line %d), force %s (line %d), torque %s, power %s (line %d)\n",
          scheduled ? "  scheduled"
                    : ("physics, " + job.simulation.physics->material.name + ", " +
                       (job.simulation.physics->material.model == ForceModel::Linear ? "linear"
                                                                                     : "Kienzle") +
                       " model")
                          .c_str(),
          q(p.value[0], Dimension::Length).c_str(), line(0),
          q(p.value[1], Dimension::Force).c_str(), line(1),
          q(p.value[2], Dimension::Torque).c_str(), q(p.value[3], Dimension::Power).c_str(),
          line(3));
    }
  }
  for (const std::string& w : runWarnings(result, written))
    report += "warning: " + w + "\n";
  // Collisions: the first ten places, the rest in summary.json.
  for (std::size_t i = 0; i < r.collisions.size() && i < 10; ++i) {
    const Collision& c = r.collisions[i];
    appendf(report, "collision: %s:%d: T%d %s met %s (steps %zu-%zu)\n", fileOf(job, c).c_str(),
            c.line, c.tool, c.part.c_str(), q(c.volume, Dimension::Volume).c_str(), c.firstStep,
            c.lastStep);
  }
  if (r.collisions.size() > 10)
    appendf(report, "collision: %zu more places in summary.json\n", r.collisions.size() - 10);
  if (result.part.done) {
    // The part: the totals, then the five largest gouges with the lines that cut them.
    const PartCheck& c = result.part;
    appendf(report,
            "part %s: %zu gouge(s) deeper than %s (deepest %s), %zu leftover(s) thicker than %s "
            "(thickest %s); %zu samples of %s in %.2f s\n",
            c.spec.file.c_str(), c.gouges.size(), q(c.spec.tolerance, Dimension::Length).c_str(),
            q(c.deepestGouge(), Dimension::Length).c_str(), c.leftovers.size(),
            q(c.spec.allowance, Dimension::Length).c_str(),
            q(c.thickestLeftover(), Dimension::Length).c_str(), c.samples,
            q(c.spacing, Dimension::Length).c_str(), c.seconds);
    for (std::size_t i = 0; i < c.gouges.size() && i < 5; ++i) {
      const DeviationRegion& g = c.gouges[i];
      std::string lines;
      const std::vector<GougeLine> by = gougeLines(g, job.path, r.steps);
      for (std::size_t k = 0; k < by.size() && k < 3; ++k)
        lines += (k ? ", " : "") + job.path.files[static_cast<std::size_t>(by[k].file)] + ":" +
                 std::to_string(by[k].line);
      if (by.size() > 3) lines += " and " + std::to_string(by.size() - 3) + " more";
      appendf(report, "gouge: %s deep, %s, %s at (%s, %s, %s), cut by %s\n",
              q(g.extreme, Dimension::Length).c_str(), q(g.area, Dimension::Area).c_str(),
              q(g.volume, Dimension::Volume).c_str(),
              formatNumber(toDisplay(g.at.x(), Dimension::Length, sys)).c_str(),
              formatNumber(toDisplay(g.at.y(), Dimension::Length, sys)).c_str(),
              formatNumber(toDisplay(g.at.z(), Dimension::Length, sys)).c_str(), lines.c_str());
    }
    if (c.gouges.size() > 5)
      appendf(report, "gouge: %zu more in gouges.csv and summary.json\n", c.gouges.size() - 5);
    // Material the part needs that the stock never held: said where it is more than a reading's
    // error at the stock's own edges (a fraction of a cell).
    for (const DeviationRegion& m : c.missing)
      if (m.extreme > 0.5 * job.voxel) {
        appendf(report,
                "warning: the stock does not hold the part: %s of it missing at (%s, %s, %s), "
                "no step cut there (summary.json: part.missing)\n",
                q(m.extreme, Dimension::Length).c_str(),
                formatNumber(toDisplay(m.at.x(), Dimension::Length, sys)).c_str(),
                formatNumber(toDisplay(m.at.y(), Dimension::Length, sys)).c_str(),
                formatNumber(toDisplay(m.at.z(), Dimension::Length, sys)).c_str());
        break;
      }
  }
  std::string targets = q(plan.targetMrr, Dimension::VolumeRate);
  if (plan.targets.size() > 1) {
    targets.clear();
    for (const auto& [tool, target] : plan.targets)
      targets += (targets.empty() ? "T" : ", T") + std::to_string(tool) + " " +
                 (target > 0.0 ? q(target, Dimension::VolumeRate) : "none (programmed feeds)");
  }
  if (!job.schedule.mrrTarget) {
    // Physics limits alone: name them.
    const ScheduleOptions& o = job.schedule;
    targets.clear();
    auto add = [&](const char* what, double v, Dimension d) {
      if (v > 0) targets += (targets.empty() ? "" : ", ") + std::string(what) + " " + q(v, d);
    };
    add("chip <=", o.maxChip, Dimension::Length);
    add("peak force <=", o.maxForce, Dimension::Force);
    add("torque <=", o.maxTorque, Dimension::Torque);
    add("power <=", o.maxPower, Dimension::Power);
  }
  if (job.scheduling())
    appendf(
        report,
        "schedule: target %s, feed time %.1f s -> %.1f s (%.1f %% %s), largest acceleration %s, "
        "%zu feed pieces (the measurement's noise %.2f %%: no F word changes for less)\n",
        targets.c_str(), plan.timeBefore, plan.timeAfter,
        plan.timeBefore > 0 ? std::abs(100.0 * (1.0 - plan.timeAfter / plan.timeBefore)) : 0.0,
        plan.timeAfter <= plan.timeBefore ? "saved" : "longer",
        q(plan.maxAcceleration, Dimension::Acceleration).c_str(), plan.fWords, 100.0 * plan.noise);
  if (job.scheduling() && plan.rapidTime > 0.0)
    appendf(report, "cycle time with rapids: %.1f s -> %.1f s (rapids %.1f s)\n",
            plan.timeBefore + plan.rapidTime, plan.timeAfter + plan.rapidTime, plan.rapidTime);
  if (result.verified.done) {
    const Verification& v = result.verified;
    std::string checks;
    for (const LimitCheck& c : v.checks)
      checks += "; " + c.option + " " + q(c.worst, c.dimension) + " at re-fed line " +
                std::to_string(c.line) + " (limit " + q(c.limit, c.dimension) + ") " +
                (c.holds ? "holds" : "EXCEEDED");
    appendf(report,
            "verified: the re-fed program re-simulated, %zu steps in %.2f s, removed %s%s\n",
            v.steps, v.seconds, q(v.removed, Dimension::Volume).c_str(), checks.c_str());
  }
  std::string plotted, programName;
  for (const std::string& f : written.plots)
    plotted += "," + f;
  if (written.refedProgram)
    programName = "," + std::filesystem::path(job.mainProgram()).filename().string();
  appendf(report, "wrote %s/{%s%s%ssummary.json%s%s%s%s}\n", job.out.c_str(),
          written.report ? "report.html," : "", written.steps ? "steps.csv," : "",
          written.partTables ? "gouges.csv,leftovers.csv," : "",
          written.stockFiles ? ",removed.vdb,stock.vdb,stock.stl" : "",
          written.deviationVdb ? ",deviation.vdb" : "", programName.c_str(), plotted.c_str());
  return report;
}

}  // namespace engage
