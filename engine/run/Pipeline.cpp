#include "engine/run/Pipeline.h"

#include "engine/run/RefedProgram.h"
#include "engine/run/Summary.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/gcode/GcodeWriter.h"
#include "engine/run/Memory.h"
#include "engine/run/Output.h"
#include "engine/run/Resolution.h"
#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

namespace engage {
namespace {

/// The boxes a job's cuts reach in its box stock (a voxel stock holds leaves only there).
std::vector<Box3> jobReach(const Job& job) {
  return programReach(job.path, job.cutters, *job.stock.box);
}

/// A stock of the chosen model at resolution h (voxel size or ray spacing) for `job`'s cuts.
std::unique_ptr<Stock> makeStock(const Job& job, StockModel model, double h) {
  const StockSpec& spec = job.stock;
  const bool dexel = model == StockModel::Dexel;
  if (spec.box) {
    if (dexel) return std::make_unique<DexelStock>(DexelStock::box(*spec.box, h));
    const std::vector<Box3> reach = jobReach(job);
    return std::make_unique<VoxelStock>(VoxelStock::box(*spec.box, h, &reach));
  }
  if (!spec.vdb.empty()) {
    if (dexel) return std::make_unique<DexelStock>(VoxelStock::dexelsFromVdb(spec.vdb, h));
    return std::make_unique<VoxelStock>(VoxelStock::fromVdb(spec.vdb, h));
  }
  // Meshes are read in mm.
  if (dexel) return std::make_unique<DexelStock>(DexelStock::fromMesh(spec.mesh, h));
  return std::make_unique<VoxelStock>(VoxelStock::fromMesh(spec.mesh, h));
}

/// Throws when no move of the path comes near the stock: a wrong box or wrong units.
void checkReach(const Job& job, const Stock& stock) {
  if (job.path.moves.empty())
    throw ParameterError(job.program + ": the program makes no moves: nothing to simulate");
  // (The moves' X, Y, Z are not on the part.)
  if (job.path.kinematics.rotary() || !job.path.frames.empty()) return;
  const Box3 sb = stock.bounds();
  for (const Move& m : job.path.moves) {
    const AptCutter& cutter = job.cutters.of(m.tool);
    // An arc can bulge up to its diameter beyond its end points.
    const double reach = cutter.maxRadius() + (m.kind == MoveKind::Arc ? 2.0 * arcRadius(m) : 0.0);
    const Eigen::Vector3d lo = m.start.cwiseMin(m.end) - Eigen::Vector3d(reach, reach, 0.0);
    const Eigen::Vector3d hi =
        m.start.cwiseMax(m.end) + Eigen::Vector3d(reach, reach, cutter.height());
    if ((lo.array() <= sb.max.array()).all() && (hi.array() >= sb.min.array()).all()) return;
  }
  const UnitSystem sys = job.units;
  auto f = [&](double v) { return formatQuantity(v, Dimension::Length, sys); };
  // The stock as given where it is a box (its grid's bounds are rounded out to the cells).
  const Box3 shown = job.stock.box ? *job.stock.box : sb;
  throw ParameterError("the tool path never reaches the stock (stock from " + f(shown.min.x()) +
                       ", " + f(shown.min.y()) + ", " + f(shown.min.z()) + " to " +
                       f(shown.max.x()) + ", " + f(shown.max.y()) + ", " + f(shown.max.z()) + ")");
}

CrossCheck crossCheck(const Job& job, const SimulationResult& r, Stock& other) {
  CrossCheck c;
  SimulationOptions oo = job.simulation;
  oo.physics.reset();  // the cross-check compares removed volumes only
  oo.progress = nullptr;
  c.other = simulate(job.path, job.cutters, other, oo);
  c.floorVolume = 4.0 * job.voxel * job.voxel * job.voxel;
  c.differs.assign(r.steps.size(), 0);
  for (std::size_t i = 0; i < r.steps.size(); ++i) {
    const double a = r.steps[i].removed, b = c.other.steps[i].removed;
    const double gap = std::abs(a - b);
    if (std::max(a, b) > c.floorVolume)
      c.worstRelative = std::max(c.worstRelative, gap / std::max(a, b));
    if (gap > job.crossTolerance * std::max(a, b) + c.floorVolume) {
      c.differs[i] = 1;
      c.differing.push_back(i);
    }
  }
  std::stable_sort(c.differing.begin(), c.differing.end(), [&](std::size_t x, std::size_t y) {
    return std::abs(r.steps[x].removed - c.other.steps[x].removed) >
           std::abs(r.steps[y].removed - c.other.steps[y].removed);
  });
  c.otherMemoryBytes = other.memoryBytes();
  return c;
}

/// The jerk (mm/s^3) a change from v0 to v1 (mm/s) over `distance` (mm) needs under
/// acceleration `a` (0: none): the least j with changeDistance(v0, v1, a, j) <= distance
/// (infinite when even an unlimited jerk leaves too little room).
double jerkNeeded(double v0, double v1, double a, double distance) {
  if (v0 == v1) return 0.0;
  if (changeDistance(v0, v1, a, 0.0) > distance) return std::numeric_limits<double>::infinity();
  double lo = 0.0, hi = 1.0;
  while (changeDistance(v0, v1, a, hi) > distance)
    hi *= 2.0;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (changeDistance(v0, v1, a, mid) > distance ? lo : hi) = mid;
  }
  return hi;
}

/// --accel and --jerk on the re-fed program: a machine that brakes only where a lower F word
/// takes effect must be down to the speed each step's load limits allow (from its re-simulated
/// load; its F word where that is higher) when the step begins. Each earlier step of the same
/// run of feed moves whose F word is higher needs, over the distance between the two, the
/// deceleration (v0^2 - v1^2) / (2 distance) and the jerk of that S-curve (jerkNeeded); the
/// worst pair of each is checked. Pairs farther apart than the longest braking at the limits
/// (the top speed times the time of a change from it to standstill) need less than the limits
/// and are not looked at. Only load limits bound a step's speed:
/// without one (an MRR target alone) nothing is checked here.
void checkMotion(const RunResult& r, const SimulationResult& again, Verification& v) {
  const ScheduleOptions& o = r.job.schedule;
  if ((!(o.acceleration > 0.0) && !(o.jerk > 0.0)) || !o.physicsLimits() ||
      again.loads.size() != again.steps.size())
    return;
  const auto& st = again.steps;
  std::vector<double> cap;
  std::vector<Binding> which;
  physicsCaps(again, o, cap, which);
  auto cutting = [&](std::size_t i) { return st[i].kind != MoveKind::Rapid && st[i].feed > 0.0; };
  double vMax = 0.0;
  for (std::size_t i = 0; i < st.size(); ++i)
    if (cutting(i)) vMax = std::max(vMax, st[i].feed / 60.0);
  const double window = vMax * changeTime(vMax, o.acceleration, o.jerk);  // the longest braking
  LimitCheck accel{"--accel", Dimension::Acceleration, o.acceleration, 0.0, 0, true};
  LimitCheck jerk{"--jerk", Dimension::Jerk, o.jerk, 0.0, 0, true};
  for (std::size_t k = 1; k < st.size(); ++k) {
    if (!cutting(k) || !std::isfinite(cap[k])) continue;
    const double v1 = std::max(cap[k], st[k].feed) / 60.0;
    const double start = st[k].arcLength - st[k].length;
    for (std::size_t i = k; i-- > 0 && cutting(i);) {
      const double gap = start - st[i].arcLength;
      if (gap > window) break;
      const double v0 = st[i].feed / 60.0;
      if (!(v0 > v1)) continue;
      const double a =
          gap > 0.0 ? (v0 * v0 - v1 * v1) / (2.0 * gap) : std::numeric_limits<double>::infinity();
      const double j = o.jerk > 0.0 ? jerkNeeded(v0, v1, o.acceleration, gap) : 0.0;
      if (a > accel.worst) accel.worst = a, accel.line = st[k].line;
      if (j > jerk.worst) jerk.worst = j, jerk.line = st[k].line;
    }
  }
  for (LimitCheck* c : {&accel, &jerk}) {
    if (!(c->limit > 0.0)) continue;
    c->holds = c->worst <= c->limit * (1.0 + kVerifyTolerance);
    v.checks.push_back(*c);
  }
}

}  // namespace

Verification verifySchedule(const RunResult& r) {
  const Job& job = r.job;
  const ScheduleOptions& o = job.schedule;
  Verification v;
  const Toolpath path = readProgramText(r.refed, job.mainProgram(), job.reader);
  const std::unique_ptr<Stock> stock = makeStock(job, job.stockModel, job.voxel);
  const SimulationResult sim = simulate(path, job.cutters, *stock, job.simulation);
  v.done = true;
  v.steps = sim.steps.size();
  v.removed = sim.removed;
  v.seconds = sim.seconds;
  auto check = [&](const char* option, Dimension d, double limit, auto value) {
    if (!(limit > 0.0)) return;
    LimitCheck c{option, d, limit, 0.0, 0, true};
    for (std::size_t i = 0; i < sim.steps.size(); ++i) {
      const StepRecord& s = sim.steps[i];
      if (s.kind == MoveKind::Rapid || !(s.feed > 0.0 || stillStep(s))) continue;
      const double x = value(i);
      if (x > c.worst) {  // NaN (no model) never wins
        c.worst = x;
        c.line = s.line;
      }
    }
    c.holds = c.worst <= limit * (1.0 + kVerifyTolerance);
    v.checks.push_back(c);
  };
  if (sim.loads.size() == sim.steps.size())
    for (const PhysicsLimit& k : kPhysicsLimits)
      check(k.option, k.dimension, o.*k.value,
            [&](std::size_t i) { return limitedLoad(sim.loads[i], k.binding); });
  check("--feed-max", Dimension::Feed, r.plan.feedMax, [&](std::size_t i) {
    return path.moves[sim.steps[i].move].fixedFeed() ? 0.0 : sim.steps[i].feed;
  });
  checkMotion(r, sim, v);
  return v;
}

MemoryEstimate memoryEstimate(const Job& job, double stopAbove) {
  MemoryEstimate e;
  e.moves = static_cast<double>(job.path.moves.size()) * sizeof(Move);
  const double perStep = static_cast<double>(sizeof(StepRecord)) +
                         (job.simulation.physics ? static_cast<double>(sizeof(StepLoad)) : 0.0);
  e.steps = stepCount(job.path, job.stepLength()) * perStep * (job.scheduling() ? 2.0 : 1.0);
  if (job.stock.box) {
    const bool voxel = job.stockModel == StockModel::Voxel || job.crossCheck;
    const std::vector<Box3> reach = voxel ? jobReach(job) : std::vector<Box3>{};
    const double rays = DexelStock::memoryBound(*job.stock.box, job.voxel) /
                        static_cast<double>(DexelStock::kBytesPerRay);
    auto one = [&](StockModel m) {
      return m == StockModel::Voxel
                 ? VoxelStock::memoryBound(*job.stock.box, job.voxel, &reach, stopAbove)
                 : 100.0 * rays;
    };
    e.stocks = one(job.stockModel);
    if (job.crossCheck) e.stocks += one(job.otherModel());
    if (job.scheduling()) e.stocks += one(job.stockModel);  // the re-fed program's re-simulation
    if (job.outputs == Job::Outputs::All)
      e.outputs =
          job.stockModel == StockModel::Voxel
              ? one(StockModel::Voxel)
              : (VoxelStock::dexelFileFactor(*job.stock.box, job.voxel) > 1 ? 60.0 : 160.0) * rays;
  }
  return e;
}

namespace {

/// Refuses a run whose estimate exceeds what it may use, with the estimate, by part, and
/// what to change.
void checkMemory(const Job& job) {
  const MemoryLimit may = memoryLimit(job.maxMemory);
  const MemoryEstimate need = memoryEstimate(job, may.bytes);
  if (!(need.total() > may.bytes)) return;
  // What to change: what alone does not fit, else the stock files that make it not fit.
  std::string advice;
  if (need.total() - need.outputs <= may.bytes)
    advice = "--outputs tables or summary (no stock files), a larger --voxel";
  else if (need.stocks >= need.steps)
    advice = "a larger --voxel";
  else
    advice = "fewer steps (a longer --step)";
  throw ParameterError("this run needs about " + memoryText(need.total()) + " of memory (stock " +
                       memoryText(need.stocks) + ", stock files " + memoryText(need.outputs) +
                       ", steps " + memoryText(need.steps) + ", moves " + memoryText(need.moves) +
                       ") and may use " + memoryText(may.bytes) + " (" + may.source + "): use " +
                       advice + ", or give it more (--max-memory)");
}

PreparedRun prepareStocks(Job job) {
  // Bounded work: a move of 1e9 mm or a helix of 100000 turns is refused before anything.
  checkStepCount(job.path, job.stepLength(), job.simulation.maxSteps);
  checkMemory(job);
  PreparedRun run;
  if (!job.stock.none()) {
    run.stock = makeStock(job, job.stockModel, job.voxel);
    if (job.crossCheck) run.other = makeStock(job, job.otherModel(), job.voxel);
    checkReach(job, *run.stock);
    if (auto* v = dynamic_cast<VoxelStock*>(run.stock.get())) v->captureRemoved(true);
    if (auto* d = dynamic_cast<DexelStock*>(run.stock.get())) d->captureRemoved(true);
  }
  if (job.part.given()) {
    run.part = std::make_unique<Part>(Part::fromFile(job.part.file));
    const Box3 pb = run.part->bounds(), sb = run.stock->bounds();
    if ((pb.max.array() < sb.min.array()).any() || (pb.min.array() > sb.max.array()).any()) {
      auto f = [&](const Eigen::Vector3d& v) {
        return formatNumber(v.x()) + ", " + formatNumber(v.y()) + ", " + formatNumber(v.z());
      };
      throw ParameterError("--part: the part (from " + f(pb.min) + " to " + f(pb.max) +
                           " mm) lies outside the stock (from " + f(sb.min) + " to " + f(sb.max) +
                           " mm): a part mesh is read in mm, in the program's frame");
    }
  }
  run.job = std::move(job);
  return run;
}

}  // namespace

PreparedRun prepareRun(Job job) {
  // The stocks' checks speak mm; an inch run's errors speak inches.
  const UnitSystem speak = job.units;
  try {
    return prepareStocks(std::move(job));
  } catch (const ParameterError& e) {
    if (speak == UnitSystem::Metric) throw;
    throw ParameterError(inReportUnits(e.what(), speak));
  }
}

RunResult executeRun(PreparedRun run, const ProgressFunction& progress) {
  RunResult r;
  r.job = std::move(run.job);
  r.stock = std::move(run.stock);
  const Job& job = r.job;
  SimulationOptions so = job.simulation;
  so.progress = progress;
  r.sim = r.stock ? simulate(job.path, job.cutters, *r.stock, so)
                  : analyticSteps(job.path, job.cutters, so, job.materialOnRight);
  if (job.crossCheck && run.other) {
    r.cross = crossCheck(job, r.sim, *run.other);
    r.crossChecked = true;
  }
  if (job.scheduling()) {
    r.plan = scheduleFeeds(job.path, r.sim, job.schedule);
    if (!r.plan.unmet.empty() && !job.schedule.allowUnmet)
      throw UnmetLimitError(unmetLimits(r) +
                            " (the lowest feed: --feed-min, else a tenth of the programmed); "
                            "give --allow-unmet to write the program anyway");
    r.refed =
        withScheduleHeader(writeProgram(readFile(job.mainProgram()), job.path, r.plan.plan), job);
    if (r.stock) r.verified = verifySchedule(r);
  }
  r.partModel = std::move(run.part);
  if (r.partModel)
    r.part = checkPart(*r.partModel, job.part, *r.stock, job.path, r.sim.steps, job.cutters,
                       job.stock.box ? &*job.stock.box : nullptr);
  // The first step at the peak: a later one counts as higher only beyond rounding (a slot's
  // steps on two lines took the same MRR to the last bits, and which of them was "higher"
  // changed with the order the stock summed its columns in).
  for (std::size_t i = 0; i < r.sim.steps.size(); ++i)
    if (r.sim.steps[i].mrr > r.sim.steps[r.peakStep].mrr * (1.0 + kSamePeak)) r.peakStep = i;
  return r;
}

RunResult runJob(Job job, const ProgressFunction& progress) {
  return executeRun(prepareRun(std::move(job)), progress);
}

ProgressFunction terminalProgress(const std::string& label, bool quiet) {
  if (quiet || !isatty(2)) return {};
  auto last =
      std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
  return [label, last](std::size_t done, std::size_t total) {
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - *last < std::chrono::milliseconds(200)) return;
    *last = now;
    std::fprintf(stderr, "\r%s: %zu / %zu steps (%.0f %%)", label.c_str(), done, total,
                 100.0 * static_cast<double>(done) / static_cast<double>(total));
    if (done == total) std::fprintf(stderr, "\n");
  };
}

}  // namespace engage
