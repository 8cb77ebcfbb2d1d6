#include "engine/run/RunOutputs.h"

#include "cutters/Error.h"
#include "engine/report/Plots.h"
#include "engine/run/Output.h"
#include "engine/run/RefedProgram.h"
#include "engine/run/RunReport.h"
#include "engine/run/StepsTable.h"
#include "engine/run/StockFiles.h"
#include "engine/units/Quantity.h"
#include "stock/AtomicFile.h"

#include <malloc.h>

#include <cstdio>
#include <functional>
#include <future>
#include <optional>

namespace engage {
namespace {

PlotSpec plotSpec(const RunResult& result, const std::filesystem::path& dir) {
  const UnitSystem sys = result.job.units;
  PlotSpec ps;
  ps.folder = dir.string();
  ps.length = unitTag(Dimension::Length, sys);
  ps.feed = unitTag(Dimension::Feed, sys);
  ps.rate = unitTag(Dimension::VolumeRate, sys);
  ps.accelerationTag = unitTag(Dimension::Acceleration, sys);
  ps.lengthLabel = unitLabel(Dimension::Length, sys);
  ps.feedLabel = unitLabel(Dimension::Feed, sys);
  ps.rateLabel = unitLabel(Dimension::VolumeRate, sys);
  ps.accelerationLabel = unitLabel(Dimension::Acceleration, sys);
  ps.schedule = result.job.scheduling();
  ps.model = result.job.stockModel == StockModel::Dexel ? "dexels" : "voxels";
  ps.accelerationLimit = toDisplay(result.job.schedule.acceleration, Dimension::Acceleration, sys);
  if (result.job.simulation.physics) {
    const ScheduleOptions& o = result.job.schedule;
    ps.physics = true;
    ps.forceTag = unitTag(Dimension::Force, sys);
    ps.powerTag = unitTag(Dimension::Power, sys);
    ps.forceLabel = unitLabel(Dimension::Force, sys);
    ps.powerLabel = unitLabel(Dimension::Power, sys);
    if (ps.schedule) {
      ps.maxChip = toDisplay(o.maxChip, Dimension::Length, sys);
      ps.maxForce = toDisplay(o.maxForce, Dimension::Force, sys);
      ps.maxPower = toDisplay(o.maxPower, Dimension::Power, sys);
    }
  }
  // Where each tool starts along the path, when the program changes tools.
  const auto& steps = result.sim.steps;
  for (std::size_t i = 1; i < steps.size(); ++i)
    if (steps[i].tool != steps[i - 1].tool)
      ps.toolChanges.emplace_back(toDisplay(steps[i - 1].arcLength, Dimension::Length, sys),
                                  "T" + std::to_string(steps[i].tool));
  return ps;
}

}  // namespace

WrittenOutputs writeRunOutputs(const RunResult& result, const std::filesystem::path& dir) {
  WrittenOutputs w;
  const Job::Outputs which = result.job.outputs;
  // The stock as voxels, for its files and the 3D view; stock.stl's and the view's surfaces.
  const StockView view(result, {result.job.stlTriangles, kMaxTriangles});
  w.steps = which != Job::Outputs::Summary;
  // Row by row into the file, never whole in memory.
  auto writeTable = [&](const std::string& name, const std::vector<std::size_t>* rows) {
    writeFileAtomically((dir / name).string(),
                        [&](std::ostream& os) { writeStepsTable(os, result, rows); });
  };
  if (w.steps) writeTable("steps.csv", nullptr);
  const PartCheck& part = result.part;
  if (part.done && which != Job::Outputs::Summary) {
    for (const bool gouges : {true, false})
      writeAtomically(
          dir / (gouges ? "gouges.csv" : "leftovers.csv"),
          regionTable(part, gouges, result.job.path, result.sim.steps, result.job.units));
    w.partTables = true;
  }
  if (part.done && which == Job::Outputs::All) {
    writeDeviationVdb((dir / "deviation.vdb").string(), part.stockPoints, part.deviation,
                      result.stock->resolution());
    w.deviationVdb = true;
  }
  const std::string summary = summaryJson(result);
  writeAtomically(dir / "summary.json", summary);
  writeRefedProgram(result, dir);
  w.refedProgram = result.job.scheduling();
  // The steps the report's plots show, and for a long run the plots' too (below).
  const bool plotted =
      which == Job::Outputs::All || (result.job.report && which != Job::Outputs::Summary);
  const std::vector<std::size_t> shown =
      plotted ? reportSteps(result, summary) : std::vector<std::size_t>();
  std::optional<ReportSurface> surface;  // the report's 3D view
  if (which == Job::Outputs::All) {
    w.stockFiles = result.stock != nullptr;
    // gnuplot draws in its own process while the stock files are written (seconds each on a
    // fine grid); its outcome is collected below.
    PlotSpec ps = plotSpec(result, dir);
    // A long run's plots read fewer steps: the curves along the path the extremes of one
    // bucket per pixel column of the pictures, the top view the steps the report plots (4000
    // buckets): gnuplot's time follows the points it draws, not the steps of the run.
    if (shown.size() < result.sim.steps.size()) {
      ps.topData = ".plot_steps.csv";
      writeTable(ps.topData, &shown);
    }
    const std::vector<std::size_t> lines = reportSteps(result, summary, kPlotWidth, 2 * kPlotWidth);
    if (lines.size() < result.sim.steps.size()) {
      ps.data = ".plot_lines.csv";
      writeTable(ps.data, &lines);
    }
    auto plots = std::async(std::launch::async, [&ps] { return writePlots(ps); });
    // The report's 3D view made beside the stock files.
    std::function<void()> view3d;
    if (result.job.report)
      view3d = [&] {
        double cell = 0.0;
        const TriangleMesh mesh = view.surface(kMaxTriangles, &cell);
        surface = reportSurface(result, mesh, cell);
      };
    w.openEdges = writeStockFiles(result, view, dir, view3d);
    try {
      for (const std::string& f : plots.get())
        if (f.size() > 4 && f.compare(f.size() - 4, 4, ".png") == 0) w.plots.push_back(f);
    } catch (const Error& e) {
      std::fprintf(stderr, "engage: warning: plots not drawn: %s\n", e.what());
    }
    for (const std::string& data : {ps.data, ps.topData})
      if (data != "steps.csv") std::filesystem::remove(dir / data);
    // What the stock files' tasks freed goes back to the system before the report grows the
    // main thread's heap (it sits in the worker threads' malloc arenas otherwise, adding to
    // the run's peak).
    malloc_trim(0);
  } else if (result.job.keepStock) {
    writeStockVdb(view, dir);
  }
  // The page names the other files: it comes last.
  if (result.job.report && which != Job::Outputs::Summary) {
    writeFileAtomically((dir / "report.html").string(), [&](std::ostream& os) {
      writeRunReportHtml(os, result, summary, shown, w, surface ? &*surface : nullptr);
    });
    w.report = true;
  }
  return w;
}

CompletedRun runIntoFolder(Job job) {
  PreparedRun prepared = prepareRun(std::move(job));
  OutputDirectory outputs(prepared.job.out);
  const ProgressFunction progress =
      terminalProgress(prepared.job.progressLabel, prepared.job.quiet);
  CompletedRun run;
  run.result = executeRun(std::move(prepared), progress);
  StagedOutputs staged(run.result.job.out);
  run.written = writeRunOutputs(run.result, staged.staging());
  // Interrupted while writing: nothing is published (the staging goes with the unwinding).
  if (stopRequested()) throw Interrupted();
  staged.publish();
  outputs.keep();
  return run;
}

}  // namespace engage
