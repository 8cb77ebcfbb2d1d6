#include "engine/run/PaperExamples.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/model/EngagementModel.h"
#include "engine/report/HtmlPage.h"
#include "engine/report/Plots.h"
#include "engine/run/CutterOptions.h"
#include "engine/run/Job.h"
#include "engine/run/Output.h"
#include "engine/run/PocketJob.h"
#include "engine/run/RunOutputs.h"
#include "engine/schedule/FeedScheduler.h"
#include "engine/sim/SteadyCut.h"
#include "engine/units/Quantity.h"

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace engage {
namespace {

namespace fs = std::filesystem;
using nlohmann::ordered_json;

constexpr double kIn = 25.4;  // mm
/// The paper's cutting conditions: D = 1 in, s = 0.5 in, d = 0.3 in (Figs 8-12) or 0.5 in
/// (Figs 13-14), V_f = 100 ipm; a 30 degree taper end mill for Figs 13-14.
constexpr double kD = 1.0 * kIn, kS = 0.5 * kIn, kFeed = 100.0 * kIn;
/// 0.3 G, the paper's allowable acceleration (Fig 14c), in/s^2.
constexpr double kGravityInPerS2 = 9806.65 / kIn;

/// printf into a string.
template <typename... Args>
void appendf(std::string& out, const char* format, Args... args) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, format, args...);
  out += buf;
}

/// Progress and stage lines on a terminal (stderr), nothing otherwise.
struct Progress {
  bool on = false;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  void stage(const std::string& text) const {
    if (!on) return;
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "paper: [%5.1f s] %s\n", s, text.c_str());
  }
};

double toIn3PerMin(double mm3PerMin) {
  return toDisplay(mm3PerMin, Dimension::VolumeRate, UnitSystem::Inch);
}

/// The tools of Fig 12, by name, as `engage` options.
struct ToolSpec {
  const char* name;
  ToolOptions options;
};

std::vector<ToolSpec> fig12Tools() {
  ToolOptions taper{"taper", "1in", "", "30deg", "", "", "3in", 2};
  ToolOptions flat{"flat", "1in", "", "", "", "", "3in", 2};
  ToolOptions fillet{"bull", "1in", "0.25in", "", "", "", "3in", 2};
  ToolOptions ball{"ball", "1in", "", "", "", "", "3in", 2};
  return {{"taper", taper}, {"flat", flat}, {"fillet", fillet}, {"ball", ball}};
}

/// Draw charts; without gnuplot the CSV files stay and a warning says why (as `simulate`).
void plot(const fs::path& dir, const std::vector<Chart>& charts, const std::string& script) {
  try {
    drawCharts(dir.string(), charts, script);
  } catch (const Error& e) {
    std::fprintf(stderr, "engage: warning: plots not drawn: %s\n", e.what());
  }
}

// --- Fig 8 -------------------------------------------------------------------------------

ordered_json figure8(const fs::path& dir, const PaperOptions& o, const Progress& progress) {
  const double cornerRatios[] = {0.0, 0.1, 0.2, 0.3, 0.4, 0.5};
  const double radiusRatios[] = {1, 1.5, 2, 3, 5, 10, 20};
  const double voxel =
      parseQuantity(o.steadyVoxel, Dimension::Length, UnitSystem::Inch, "--steady-voxel").value;
  struct Point {
    double k, q;
    PathSide side;
    double measured = 0, exact = 0, paper = 0;
  };
  std::vector<Point> points;
  for (double k : cornerRatios)
    for (PathSide side : {PathSide::Concave, PathSide::Convex})
      for (double q : radiusRatios)
        points.push_back({k, q, side});
  progress.stage(
      "Fig 8: " + std::to_string(points.size()) +
      " steady cuts (6 corner radii x 7 path radii x concave/convex) in the voxel stock");
  std::atomic<int> done{0};
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
    Point& p = points[i];
    const AptCutter cutter = p.k == 0.0   ? AptCutter::flat(kD, 3 * kD)
                             : p.k == 0.5 ? AptCutter::ball(kD, 3 * kD)
                                          : AptCutter::bull(kD, p.k * kD, 3 * kD);
    const double d = 0.3 * kIn;
    const PathShape shape{p.side, p.q * kD};
    const EngagementModel model(cutter, kS, d);
    p.measured = measureSteadyCut(cutter, kS, d, shape, kFeed, voxel).mrr;
    p.exact = model.mrr(kFeed, shape);
    p.paper = model.mrrPaper(kFeed, shape);
    const int n = ++done;
    if (progress.on && (n % 12 == 0 || n == static_cast<int>(points.size())))
      std::fprintf(stderr, "\rpaper: Fig 8: %d / %zu", n, points.size());
  });
  if (progress.on) std::fprintf(stderr, "\n");

  std::string csv =
      "corner_radius_over_D,path_radius_over_D,path,mrr_measured_in3_min,mrr_exact_in3_min,"
      "mrr_paper_in3_min,measured_vs_exact\n";
  double worst = 0.0;
  for (const Point& p : points) {
    const double rel = p.measured / p.exact - 1.0;
    worst = std::max(worst, std::abs(rel));
    csv += formatNumber(p.k) + "," + formatNumber(p.q) + "," +
           (p.side == PathSide::Concave ? "concave" : "convex") + "," +
           formatNumber(toIn3PerMin(p.measured)) + "," + formatNumber(toIn3PerMin(p.exact)) + "," +
           formatNumber(toIn3PerMin(p.paper)) + "," + formatNumber(rel) + "\n";
  }
  writeAtomically(dir / "fig8.csv", csv);
  // One CSV per corner radius and side for the plot.
  std::vector<Chart> charts;
  for (PathSide side : {PathSide::Concave, PathSide::Convex}) {
    const std::string sideName = side == PathSide::Concave ? "concave" : "convex";
    Chart c;
    c.name = "fig8_" + sideName;
    c.title = "Fig 8: MRR against R/D on " + sideName +
              " paths, D = 1 in, d = 0.3 in, s = 0.5 in, 100 ipm (points: voxel stock; solid: "
              "exact; dashed: paper Eq 15/16)";
    c.xlabel = "R/D (tool-centre path radius / cutter diameter)";
    c.ylabel = "MRR (in^3/min)";
    c.logX = true;
    int colour = 1;
    for (double k : cornerRatios) {
      std::string part = "corner_radius_over_D,path_radius_over_D,measured,exact,paper\n";
      for (const Point& p : points)
        if (p.k == k && p.side == side)
          part += formatNumber(p.k) + "," + formatNumber(p.q) + "," +
                  formatNumber(toIn3PerMin(p.measured)) + "," + formatNumber(toIn3PerMin(p.exact)) +
                  "," + formatNumber(toIn3PerMin(p.paper)) + "\n";
      const std::string file = "fig8_" + sideName + "_rtc" + formatNumber(k) + ".csv";
      writeAtomically(dir / file, part);
      const std::string lc = " lc " + std::to_string(colour++);
      c.series.push_back({file, "path_radius_over_D", "measured", "r_{tc}/D = " + formatNumber(k),
                          "points pt 7 ps 1.2" + lc});
      c.series.push_back({file, "path_radius_over_D", "exact", "", "lines lw 1.5" + lc});
      c.series.push_back({file, "path_radius_over_D", "paper", "", "lines lw 1 dt 2" + lc});
    }
    charts.push_back(c);
  }
  plot(dir, charts, "fig8.gp");

  // The paper's statements: MRR falls as R/D grows (concave) and as r_tc/D grows.
  auto at = [&](double k, double q, PathSide side) {
    for (const Point& p : points)
      if (p.k == k && p.q == q && p.side == side) return p;
    return Point{};
  };
  // Measured values agree with the exact model's order wherever the exact values differ by
  // more than 0.5 % (closer ones are within the voxel stock's noise).
  bool fallsWithRadius = true, fallsWithCorner = true;
  auto falls = [](const Point& before, const Point& after) {
    return after.exact > 0.995 * before.exact || after.measured < before.measured;
  };
  for (double k : cornerRatios)
    for (std::size_t i = 1; i < std::size(radiusRatios); ++i)
      fallsWithRadius = fallsWithRadius && falls(at(k, radiusRatios[i - 1], PathSide::Concave),
                                                 at(k, radiusRatios[i], PathSide::Concave));
  for (double q : radiusRatios)
    for (std::size_t i = 1; i < std::size(cornerRatios); ++i)
      fallsWithCorner = fallsWithCorner && falls(at(cornerRatios[i - 1], q, PathSide::Concave),
                                                 at(cornerRatios[i], q, PathSide::Concave));
  const Point flat1 = at(0.0, 1, PathSide::Concave), ball1 = at(0.5, 1, PathSide::Concave);
  return {{"points", points.size()},
          {"measured_vs_exact_worst_relative", worst},
          {"concave_mrr_falls_as_R_over_D_grows", fallsWithRadius},
          {"concave_mrr_falls_as_rtc_over_D_grows", fallsWithCorner},
          {"flat_R_over_D_1_concave_in3_min",
           {{"measured", toIn3PerMin(flat1.measured)},
            {"exact", toIn3PerMin(flat1.exact)},
            {"paper", toIn3PerMin(flat1.paper)}}},
          {"ball_R_over_D_1_concave_in3_min",
           {{"measured", toIn3PerMin(ball1.measured)},
            {"exact", toIn3PerMin(ball1.exact)},
            {"paper", toIn3PerMin(ball1.paper)}}}};
}

// --- pocket programs ---------------------------------------------------------------------

struct Pocket {
  fs::path program;
  std::vector<int> ringLines;
};

Pocket makePocket(const PaperOptions& o, const fs::path& dir, const std::string& boundary,
                  const std::string& name, const std::string& depth, const std::string& top,
                  const std::string& safeZ) {
  PocketJobOptions c;
  c.boundary = (fs::path(o.data) / "paper" / boundary).string();
  c.diameter = "1";
  c.stepover = "0.5";
  c.depth = depth;
  c.top = top;
  c.safeZ = safeZ;
  c.feed = "100";
  const PocketProgram p = makePocketProgram(c);
  const fs::path file = dir / name;
  writeAtomically(file, p.text);
  return {file, p.ringLines};
}

// --- simulated figures ---------------------------------------------------------------------

/// One simulation of the paper's examples, with the steps of its outer (wall) ring.
struct Run {
  RunResult outcome;
  std::size_t first = 0, last = 0;  ///< steps of the outer ring: [first, last)
};

Run simulatePocket(const Pocket& pocket, const ToolOptions& tool, const std::string& stock,
                   const std::string& depth, const fs::path& out, const PaperOptions& o,
                   const std::string& label) {
  const OptionValues values = {{"program", pocket.program.string()},
                               {"tool", tool.tool},
                               {"diameter", tool.diameter},
                               {"corner-radius", tool.cornerRadius},
                               {"taper-angle", tool.taperAngle},
                               {"tip-angle", tool.tipAngle},
                               {"bottom-angle", tool.bottomAngle},
                               {"flute-length", tool.fluteLength},
                               {"flutes", std::to_string(tool.flutes)},
                               {"stock", stock},
                               // The paper's figures compare single steps with the exact
                               // model: voxels hold a side cut's steps within 0.04 %, dexels
                               // 0.54 % (docs/accuracy.md).
                               {"stock-model", "voxel"},
                               {"voxel", o.voxel},
                               {"stepover", "0.5in"},
                               {"depth", depth},
                               {"out", out.string()},
                               {"quiet", o.quiet ? "true" : "false"}};
  Job job = makeJob(JobCommand::Simulate, values);
  job.progressLabel = "paper: " + label;
  Run run{runIntoFolder(std::move(job)).result, 0, 0};
  // The last ring is the wall pass: from its first line to the retract after it.
  const int from = pocket.ringLines.back();
  const auto& steps = run.outcome.sim.steps;
  run.first = steps.size();
  for (std::size_t i = 0; i < steps.size(); ++i)
    if (steps[i].line >= from && steps[i].kind != MoveKind::Rapid) {
      if (run.first == steps.size()) run.first = i;
      run.last = i + 1;
    }
  if (run.first >= run.last)
    throw Error(pocket.program.string() + ": no feed steps after line " + std::to_string(from) +
                ", where its wall pass should start");
  return run;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// Per step of the outer ring: arc length from the ring's start, MRR measured and analytic,
/// the adaptive feed of the paper (Eq 21-23, V_fc held at the straight cut's) and engage's
/// schedule from the measured MRR to the same target, and Eq 24's acceleration of the paper's
/// feed and of the machine's speed under engage's (Schedule::speed).
struct Ring {
  std::vector<double> s, mrr, exact, paper, feedPaper, feedMeasured, speedMeasured, accPaper,
      accMeasured;
  std::vector<PathSide> side;
  double target = 0.0;  ///< mm^3/min
};

Ring outerRing(const Run& run, double depth) {
  const auto& steps = run.outcome.sim.steps;
  const EngagementModel model(run.outcome.job.cutter, kS, depth);
  Ring r;
  r.target = model.mrr(kFeed, {});
  // engage's own schedule from the measured MRR: the straight cut's load as the target,
  // feeds within [F/4, 2F], 1 % feed levels, 0.3 G tangential acceleration.
  ScheduleOptions so;
  so.targetMrr = r.target;
  so.feedMin = 0.25 * kFeed;
  so.feedMax = 2.0 * kFeed;
  so.acceleration = 0.3 * 9806.65;
  so.minChange = 0.01;
  const Schedule plan = scheduleFeeds(run.outcome.job.path, run.outcome.sim, so);
  const double targetPaper = model.mrrPaper(kFeed, {});
  const double s0 = run.first > 0 ? steps[run.first - 1].arcLength : 0.0;
  for (std::size_t i = run.first; i < run.last; ++i) {
    const StepRecord& st = steps[i];
    const PathShape shape = st.side == PathSide::Straight || st.curvature == 0.0
                                ? PathShape{}
                                : PathShape{st.side, 1.0 / std::abs(st.curvature)};
    r.s.push_back(st.arcLength - s0);
    r.mrr.push_back(st.mrr);
    r.exact.push_back(st.mrrExact);
    r.paper.push_back(st.mrrPaper);
    r.side.push_back(st.side);
    double fp = std::numeric_limits<double>::quiet_NaN();
    try {
      fp = model.adaptiveFeedPaper(targetPaper, shape);
    } catch (const Error&) {
    }
    r.feedPaper.push_back(fp);
    r.feedMeasured.push_back(plan.feed[i]);
    r.speedMeasured.push_back(plan.speed[i]);
    const std::size_t k = r.s.size() - 1;
    auto acc = [&](const std::vector<double>& f) {
      if (k == 0 || !std::isfinite(f[k]) || !std::isfinite(f[k - 1])) return 0.0;
      return tangentialAcceleration(f[k - 1], f[k], st.length);
    };
    r.accPaper.push_back(acc(r.feedPaper));
    r.accMeasured.push_back(acc(r.speedMeasured));
  }
  return r;
}

void writeRingCsv(const fs::path& file, const Ring& r) {
  auto L = [](double v) { return formatNumber(toDisplay(v, Dimension::Length, UnitSystem::Inch)); };
  auto Q = [](double v) { return formatNumber(toIn3PerMin(v)); };
  auto F = [](double v) { return formatNumber(toDisplay(v, Dimension::Feed, UnitSystem::Inch)); };
  auto A = [](double v) {
    return formatNumber(toDisplay(v, Dimension::Acceleration, UnitSystem::Inch));
  };
  std::string csv =
      "arc_length_in,path,mrr_in3_min,mrr_exact_in3_min,mrr_paper_in3_min,feed_adaptive_paper_in_"
      "min,feed_adaptive_measured_in_min,acceleration_paper_in_s2,acceleration_measured_in_s2\n";
  for (std::size_t i = 0; i < r.s.size(); ++i)
    csv += L(r.s[i]) + "," +
           (r.side[i] == PathSide::Concave  ? "concave"
            : r.side[i] == PathSide::Convex ? "convex"
                                            : "straight") +
           "," + Q(r.mrr[i]) + "," + Q(r.exact[i]) + "," + Q(r.paper[i]) + "," + F(r.feedPaper[i]) +
           "," + F(r.feedMeasured[i]) + "," + A(r.accPaper[i]) + "," + A(r.accMeasured[i]) + "\n";
  writeAtomically(file, csv);
}

/// Median of `v` over the ring's steps on one side of the path (NaN when there are none):
/// the plateau of that side, not pulled by the transitions between sides.
double medianOn(const Ring& r, const std::vector<double>& v, PathSide side) {
  std::vector<double> on;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (r.side[i] == side && std::isfinite(v[i])) on.push_back(v[i]);
  return on.empty() ? std::numeric_limits<double>::quiet_NaN() : median(on);
}

ordered_json figure9(const fs::path& dir, const fs::path& programs, const PaperOptions& o,
                     const Progress& progress) {
  progress.stage("Fig 9: rectangular pocket, flat end mill, uncut corners");
  const Pocket pocket =
      makePocket(o, programs, "fig9_boundary.ngc", "fig9_pocket.ngc", "0.3", "0", "");
  const Run run = simulatePocket(pocket, fig12Tools()[1].options, "box:-0.5,-0.5,-0.6,5.5,3.5,0",
                                 "0.3in", dir / "fig9", o, "Fig 9");
  const Ring r = outerRing(run, 0.3 * kIn);
  writeRingCsv(dir / "fig9.csv", r);
  plot(dir,
       {{"fig9_mrr",
         "Fig 9: MRR along the last contour pass of a 5 x 3 in pocket with 90 degree corners "
         "(flat D = 1 in, s = r = 0.5 in, d = 0.3 in, 100 ipm)",
         "arc length along the pass (in)",
         "MRR (in^3/min)",
         {{"fig9.csv", "arc_length_in", "mrr_in3_min", "measured (voxels)", "lines lw 2"},
          {"fig9.csv", "arc_length_in", "mrr_exact_in3_min", "analytic, exact", "lines lw 1 dt 2"},
          {"fig9.csv", "arc_length_in", "mrr_paper_in3_min", "analytic, paper", "lines lw 1 dt 3"}},
         {},
         false}},
       "fig9.gp");
  // Peak over nominal; the exact value at the corner is 2 (the full slot: the previous pass
  // left the whole corner square uncut, see tests/engine/sim/Simulation.cpp).
  std::vector<double> straight;
  for (std::size_t i = 0; i < r.s.size(); ++i)
    if (r.side[i] == PathSide::Straight) straight.push_back(r.mrr[i]);
  if (straight.empty()) throw Error("Fig 9: the wall pass has no straight steps");
  const double nominal = median(straight);
  const double peak = *std::max_element(r.mrr.begin(), r.mrr.end());
  // Where the rise begins: the first step 2 % above nominal before the first peak.
  const std::size_t ip =
      static_cast<std::size_t>(std::max_element(r.mrr.begin(), r.mrr.end()) - r.mrr.begin());
  std::size_t rise = ip;
  while (rise > 0 && r.mrr[rise - 1] > 1.02 * nominal)
    --rise;
  return {{"nominal_mrr_in3_min", toIn3PerMin(nominal)},
          {"peak_mrr_in3_min", toIn3PerMin(peak)},
          {"peak_over_nominal_measured", peak / nominal},
          {"peak_over_nominal_exact_at_corner", 2.0},
          {"peak_over_nominal_analytic_model", 1.0},
          {"rise_starts_before_peak_in",
           toDisplay(r.s[ip] - r.s[rise], Dimension::Length, UnitSystem::Inch)},
          {"rise_length_exact_in", 2 * 0.5}};
}

ordered_json figure12(const fs::path& dir, const fs::path& programs, const PaperOptions& o,
                      const Progress& progress) {
  const Pocket pocket =
      makePocket(o, programs, "fig10_boundary.ngc", "fig11_pocket.ngc", "0.3", "0", "");
  ordered_json tools = ordered_json::object();
  Chart mrr{"fig12_mrr",
            "Fig 12a: MRR along the wall pass of the free-form pocket (D = 1 in, s = 0.5 in, d = "
            "0.3 in, 100 ipm; solid: voxel stock, dashed: analytic exact)",
            "arc length along the pass (in)",
            "MRR (in^3/min)",
            {},
            {},
            false};
  Chart feed{"fig12_feed",
             "Fig 12b: adaptive feed for a constant load (dashed: paper Eq 21-23; solid: engage "
             "schedule from the measured MRR, within 0.3 G)",
             "arc length along the pass (in)",
             "feed (in/min)",
             {},
             {},
             false};
  int colour = 1;
  std::vector<std::pair<std::string, double>> means;
  for (const ToolSpec& t : fig12Tools()) {
    progress.stage(std::string("Fig 12: free-form pocket, ") + t.name + " end mill");
    const Run run = simulatePocket(pocket, t.options, "box:-2.7,-2.7,-0.6,7.2,2.7,0", "0.3in",
                                   dir / "fig12" / t.name, o, std::string("Fig 12 ") + t.name);
    const Ring r = outerRing(run, 0.3 * kIn);
    const std::string file = std::string("fig12_") + t.name + ".csv";
    writeRingCsv(dir / file, r);
    const std::string lc = " lc " + std::to_string(colour++);
    mrr.series.push_back({file, "arc_length_in", "mrr_in3_min", t.name, "lines lw 2" + lc});
    mrr.series.push_back({file, "arc_length_in", "mrr_exact_in3_min", "", "lines lw 1 dt 2" + lc});
    feed.series.push_back(
        {file, "arc_length_in", "feed_adaptive_measured_in_min", t.name, "lines lw 2" + lc});
    feed.series.push_back(
        {file, "arc_length_in", "feed_adaptive_paper_in_min", "", "lines lw 1 dt 2" + lc});
    double all = 0.0;
    for (double v : r.mrr)
      all += v;
    all /= static_cast<double>(std::max<std::size_t>(r.mrr.size(), 1));
    means.emplace_back(t.name, all);
    tools[t.name] = {
        {"mean_mrr_in3_min", toIn3PerMin(all)},
        {"concave_median_mrr_in3_min", toIn3PerMin(medianOn(r, r.mrr, PathSide::Concave))},
        {"convex_median_mrr_in3_min", toIn3PerMin(medianOn(r, r.mrr, PathSide::Convex))},
        {"concave_median_exact_in3_min", toIn3PerMin(medianOn(r, r.exact, PathSide::Concave))},
        {"convex_median_exact_in3_min", toIn3PerMin(medianOn(r, r.exact, PathSide::Convex))},
        {"concave_median_paper_in3_min", toIn3PerMin(medianOn(r, r.paper, PathSide::Concave))},
        {"convex_median_paper_in3_min", toIn3PerMin(medianOn(r, r.paper, PathSide::Convex))},
        {"straight_exact_in3_min", toIn3PerMin(r.target)},
        {"whole_program_removed_in3",
         toDisplay(run.outcome.sim.removed, Dimension::Volume, UnitSystem::Inch)}};
  }
  plot(dir, {mrr, feed}, "fig12.gp");
  std::sort(means.begin(), means.end(),
            [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string order;
  for (const auto& m : means)
    order += (order.empty() ? "" : " > ") + m.first;
  return {{"tools", tools}, {"measured_order_by_mean_mrr", order}};
}

ordered_json figure14(const fs::path& dir, const fs::path& programs, const PaperOptions& o,
                      const Progress& progress) {
  const Pocket upper =
      makePocket(o, programs, "fig13_upper_boundary.ngc", "fig13_upper.ngc", "0.5", "0", "");
  const Pocket lower =
      makePocket(o, programs, "fig13_lower_boundary.ngc", "fig13_lower.ngc", "0.5", "-0.5", "0.2");
  const ToolOptions taper = fig12Tools()[0].options;
  progress.stage("Fig 14: two-level pocket with 30 degree walls, upper pocket, taper end mill");
  const Run run = simulatePocket(upper, taper, "box:-4.3,-3.1,-1.2,4.3,3.1,0", "0.5in",
                                 dir / "fig14", o, "Fig 14 upper");
  progress.stage("Fig 13c: the lower pocket");
  // The lower pocket lies inside the upper one's floor: its stock is the block below it.
  const Run low = simulatePocket(lower, taper, "box:-2.2,-2.2,-1.2,2.2,2.2,-0.5", "0.5in",
                                 dir / "fig13_lower", o, "Fig 13 lower");
  const Ring r = outerRing(run, 0.5 * kIn);
  writeRingCsv(dir / "fig14.csv", r);
  const double limit = 0.3 * kGravityInPerS2;
  const std::string x = "arc_length_in";
  plot(dir,
       {{"fig14_mrr",
         "Fig 14a: MRR along the outer pass of the upper pocket (taper 30 deg, D = 1 in, s = 0.5 "
         "in, d = 0.5 in, 100 ipm)",
         "arc length along the pass (in)",
         "MRR (in^3/min)",
         {{"fig14.csv", x, "mrr_in3_min", "measured (voxels)", "lines lw 2"},
          {"fig14.csv", x, "mrr_exact_in3_min", "analytic, exact", "lines lw 1 dt 2"},
          {"fig14.csv", x, "mrr_paper_in3_min", "analytic, paper", "lines lw 1 dt 3"}},
         {},
         false},
        {"fig14_feed",
         "Fig 14b: adaptive feed for a constant load",
         "arc length along the pass (in)",
         "feed (in/min)",
         {{"fig14.csv", x, "feed_adaptive_paper_in_min", "paper Eq 21-23", "lines lw 2"},
          {"fig14.csv", x, "feed_adaptive_measured_in_min", "engage schedule (measured MRR, 0.3 G)",
           "lines lw 1.5"}},
         {},
         false},
        {"fig14_acceleration",
         "Fig 14c: tangential acceleration between successive steps (Eq 24) and 0.3 G",
         "arc length along the pass (in)",
         "acceleration (in/s^2)",
         {{"fig14.csv", x, "acceleration_paper_in_s2", "paper feed", "lines lw 2"},
          {"fig14.csv", x, "acceleration_measured_in_s2", "engage schedule", "lines lw 1.5"}},
         {{limit, "0.3 G"}, {-limit, ""}},
         false}},
       "fig14.gp");
  auto maxAbs = [](const std::vector<double>& v) {
    double m = 0.0;
    for (double a : v)
      m = std::max(m, std::abs(a));
    return m;
  };
  const double stepIn =
      toDisplay(run.outcome.sim.steps.empty() ? 0.0 : run.outcome.sim.steps[run.first].length,
                Dimension::Length, UnitSystem::Inch);
  return {{"max_acceleration_paper_feed_in_s2",
           toDisplay(maxAbs(r.accPaper), Dimension::Acceleration, UnitSystem::Inch)},
          {"max_acceleration_measured_feed_in_s2",
           toDisplay(maxAbs(r.accMeasured), Dimension::Acceleration, UnitSystem::Inch)},
          {"paper_max_acceleration_in_s2", 7.27},
          {"limit_0_3_g_in_s2", limit},
          {"step_length_in", stepIn},
          {"concave_median_mrr_in3_min", toIn3PerMin(medianOn(r, r.mrr, PathSide::Concave))},
          {"concave_median_exact_in3_min", toIn3PerMin(medianOn(r, r.exact, PathSide::Concave))},
          {"concave_median_paper_in3_min", toIn3PerMin(medianOn(r, r.paper, PathSide::Concave))},
          {"straight_median_mrr_in3_min", toIn3PerMin(medianOn(r, r.mrr, PathSide::Straight))},
          {"straight_exact_in3_min", toIn3PerMin(r.target)},
          {"lower_pocket_removed_in3",
           toDisplay(low.outcome.sim.removed, Dimension::Volume, UnitSystem::Inch)}};
}

}  // namespace

/// report.html of the examples: the statements measured, the figures, and one row per
/// simulation (each folder's summary.json) with a link to its own report.
std::string paperReportHtml(const fs::path& dir, const std::string& statements) {
  std::vector<fs::path> summaries, images;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.path().filename() == "summary.json") summaries.push_back(e.path());
    if (e.path().extension() == ".png" && e.path().parent_path() == dir) images.push_back(e.path());
  }
  std::sort(summaries.begin(), summaries.end());
  std::sort(images.begin(), images.end());
  ordered_json jobs = ordered_json::array();
  for (const fs::path& file : summaries) {
    const ordered_json s = ordered_json::parse(readFile(file));
    const fs::path folder = fs::relative(file.parent_path(), dir);
    const bool report = fs::exists(file.parent_path() / "report.html");
    jobs.push_back({{"name", folder.generic_string()},
                    {"status", "ok"},
                    {"program", s["program"]},
                    {"error", nullptr},
                    {"warnings", ordered_json::array()},
                    {"report", report ? ordered_json((folder / "report.html").generic_string())
                                      : ordered_json()},
                    {"figures",
                     {{"removed", s["removed"]},
                      {"peak_mrr", s["peak_mrr"]["value"]},
                      {"peak_mrr_line", s["peak_mrr"]["line"]},
                      {"cutting_time_s", s["cutting_time_s"]},
                      {"collisions", s["collisions"]["count"]}}}});
  }
  ordered_json lines = ordered_json::array();
  std::size_t at = 0;
  for (std::size_t nl; (nl = statements.find('\n', at)) != std::string::npos; at = nl + 1)
    lines.push_back(statements.substr(at, nl - at));
  ordered_json pictures = ordered_json::array();
  for (const fs::path& p : images)
    pictures.push_back(p.filename().string());
  ordered_json data;
  data["kind"] = "batch";
  data["title"] = "engage paper: Kloypayan & Lee, IMECE2002-33615, Figs 8-14";
  data["batch"] = {{"subtitle", dir.string() + " · every example rebuilt and measured · inches"},
                   {"statements", lines},
                   {"rows_title", "One row per simulation (name: its own report)"},
                   {"jobs", jobs},
                   {"units", {{"volume", "in^3"}, {"mrr", "in^3/min"}}},
                   {"images", pictures},
                   {"files", {"paper.json"}}};
  return htmlPage(PageKind::Batch, data["title"].get<std::string>(),
                  data.dump(-1, ' ', false, ordered_json::error_handler_t::replace));
}

std::string runPaper(const PaperOptions& o) {
  std::string text;
  if (!fs::is_directory(fs::path(o.data) / "paper"))
    throw Error("no paper data in '" + o.data + "' (expected " + o.data +
                "/paper/fig10_boundary.ngc ...; give --data)");
  Progress progress;
  progress.on = isatty(2) && !o.quiet;
  const fs::path dir(o.out), programs = dir / "programs";
  OutputDirectory outputs(dir);
  fs::create_directories(programs);
  ordered_json j;
  j["source"] =
      "Kloypayan & Lee, Adaptive feedrate scheduling and material engagement analysis for high "
      "performance machining, IMECE2002-33615";
  j["units"] = "in";
  j["voxel"] = o.voxel;
  j["steady_voxel"] = o.steadyVoxel;
  j["fig8"] = figure8(dir, o, progress);
  j["fig9"] = figure9(dir, programs, o, progress);
  j["fig12"] = figure12(dir, programs, o, progress);
  j["fig14"] = figure14(dir, programs, o, progress);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - progress.start).count();
  j["run_time_s"] = seconds;
  writeAtomically(dir / "paper.json", j.dump(2) + "\n");

  const auto& f8 = j["fig8"];
  const auto& f9 = j["fig9"];
  const auto& f12 = j["fig12"];
  const auto& f14 = j["fig14"];
  appendf(text,
          "Fig 8: %zu steady cuts, measured within %.2f %% of the exact model; concave MRR "
          "falls as R/D grows: %s, as r_tc/D grows: %s\n",
          f8["points"].get<std::size_t>(),
          100 * f8["measured_vs_exact_worst_relative"].get<double>(),
          f8["concave_mrr_falls_as_R_over_D_grows"].get<bool>() ? "yes" : "no",
          f8["concave_mrr_falls_as_rtc_over_D_grows"].get<bool>() ? "yes" : "no");
  appendf(text,
          "Fig 9: corner peak %.3f x nominal (exact at the corner 2, analytic model 1), rise "
          "over %.2f in before the peak\n",
          f9["peak_over_nominal_measured"].get<double>(),
          f9["rise_starts_before_peak_in"].get<double>());
  appendf(text, "Fig 12: mean MRR on the wall pass %s",
          f12["measured_order_by_mean_mrr"].get<std::string>().c_str());
  for (const auto& [name, t] : f12["tools"].items())
    appendf(text, "; %s %.2f (concave plateau %.2f, convex %.2f)", name.c_str(),
            t["mean_mrr_in3_min"].get<double>(), t["concave_median_mrr_in3_min"].get<double>(),
            t["convex_median_mrr_in3_min"].get<double>());
  appendf(text, " in^3/min\n");
  appendf(text,
          "Fig 14: largest acceleration of the paper's adaptive feed %.2f in/s^2 (paper 7.27, "
          "0.3 G = %.1f), of the measured one %.2f in/s^2, steps of %.4f in\n",
          f14["max_acceleration_paper_feed_in_s2"].get<double>(),
          f14["limit_0_3_g_in_s2"].get<double>(),
          f14["max_acceleration_measured_feed_in_s2"].get<double>(),
          f14["step_length_in"].get<double>());
  writeAtomically(dir / "report.html", paperReportHtml(dir, text));
  appendf(text,
          "wrote %s/{report.html, paper.json, fig8*, fig9*, fig12*, fig14*, programs/} in %.0f s\n",
          o.out.c_str(), seconds);
  outputs.keep();
  return text;
}

}  // namespace engage
