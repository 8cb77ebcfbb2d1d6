// Tests of engine/schedule/FeedScheduler.h: the rules, and the proof by re-simulation.

#include "engine/schedule/FeedScheduler.h"

#include "engine/gcode/GcodeReader.h"
#include "engine/model/EngagementModel.h"
#include "stock/VoxelStock.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

using namespace engage;

namespace {

std::string fig9() {
  std::ifstream in(ENGAGE_SOURCE_DIR "/data/gcode/paper/fig9_corner.ngc");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

VoxelStock fig9Stock() {
  Box3 b;
  b.min = {-30, -10, -10};
  b.max = {10, 30, 0};
  return VoxelStock::box(b, 0.3);
}

}  // namespace

TEST_CASE("re-fed corner program: MRR at the target, acceleration within the limit", "[schedule]") {
  const std::string source = fig9();
  const Toolpath path = readProgramText(source, "fig9.ngc");
  const AptCutter cutter = AptCutter::flat(6.0, 18.0);
  VoxelStock stock = fig9Stock();
  const SimulationResult sim = simulate(path, cutter, stock, {});

  ScheduleOptions o;
  o.targetMrr = 3600.0;  // the nominal MRR: s = r = 3, d = 2, 600 mm/min
  o.feedMin = 100.0;
  o.feedMax = 1200.0;
  o.acceleration = 500.0;  // mm/s^2
  o.minChange = 0.02;
  const Schedule sc = scheduleFeeds(path, sim, o);

  // Rule: no change between successive scheduled feed steps needs more than the limit
  // (Eq 24: a = (f1^2 - f0^2) / (2 ds), feeds in mm/s, ds the later step's length).
  double worst = 0.0;
  for (std::size_t i = 1; i < sim.steps.size(); ++i) {
    if (sim.steps[i].kind == MoveKind::Rapid || sim.steps[i - 1].kind == MoveKind::Rapid) continue;
    const double v0 = sc.feed[i - 1] / 60.0, v1 = sc.feed[i] / 60.0;
    worst = std::max(worst, std::abs(v1 * v1 - v0 * v0) / (2.0 * sim.steps[i].length));
  }
  CHECK(worst <= 500.0 * (1 + 1e-9));
  CHECK(sc.maxAcceleration == Approx(worst));
  // Rule: the corner's load peak is met by slowing down before it (backward pass): the feed
  // at the corner is about half the programmed one, and earlier steps are already slower.
  double cornerFeed = 0.0;
  for (std::size_t i = 0; i < sim.steps.size(); ++i)
    if (sim.steps[i].line == 15 && std::abs(sim.steps[i].end.x()) < 1e-9) cornerFeed = sc.feed[i];
  CHECK(cornerFeed < 600.0 * 0.55);
  // Rule: feeds are never more than the hysteresis (half a level) above the wanted feed and
  // never outside the limits.
  for (std::size_t i = 0; i < sim.steps.size(); ++i) {
    if (sim.steps[i].kind == MoveKind::Rapid) continue;
    CHECK(sc.feed[i] <= sc.wanted[i] * (1.01 + 1e-12));
    CHECK(sc.feed[i] >= 100.0 * (1 - 1e-12));
    CHECK(sc.feed[i] <= 1200.0 * (1 + 1e-12));
  }
  CHECK(sc.timeAfter > 0.0);

  // The re-fed program reads back to the same geometry (1e-6 mm) ...
  const std::string refed = writeProgram(source, path, sc.plan);
  const Toolpath back = readProgramText(refed, "fig9-refed.ngc");
  double total = 0.0, totalBack = 0.0;
  for (const Move& m : path.moves)
    total += moveLength(m);
  for (const Move& m : back.moves)
    totalBack += moveLength(m);
  CHECK(totalBack == Approx(total).epsilon(1e-9));
  for (const Move& m : back.moves) {
    // every re-fed move ends on the original path
    double best = 1e9;
    for (const Move& o2 : path.moves)
      for (int k = 0; k <= 2000; ++k)
        best = std::min(best, (pointAt(o2, k / 2000.0) - m.end).norm());
    CHECK(best < 0.02);  // sampling of the original at 1/2000 of each move
  }
  // ... and simulated again, holds the MRR within +-5 % of the target wherever no limit binds.
  VoxelStock again = fig9Stock();
  const SimulationResult re = simulate(back, cutter, again, {});
  std::size_t checked = 0;
  for (const StepRecord& s : re.steps) {
    if (s.kind == MoveKind::Rapid || s.mrr <= 0.0) continue;
    // The original step at this arc length, and whether a limit bound it.
    std::size_t k = 0;
    while (k + 1 < sim.steps.size() && sim.steps[k].arcLength < s.arcLength - 1e-9)
      ++k;
    if (sim.steps[k].line < 13) continue;  // the current pass only
    if (sc.binding[k] != Binding::None) continue;
    if (k > 0 && sc.binding[k - 1] != Binding::None) continue;  // step boundaries differ
    if (k + 1 < sim.steps.size() && sc.binding[k + 1] != Binding::None) continue;
    INFO("line " << s.line << " at " << s.arcLength << " mm, feed " << s.feed << ", original step "
                 << k << " feed " << sim.steps[k].feed << " wanted " << sc.wanted[k]
                 << " scheduled " << sc.feed[k] << " measured " << sim.steps[k].mrr);
    CHECK(s.mrr == Approx(3600.0).epsilon(0.05));
    ++checked;
  }
  CHECK(checked > 20);
}

TEST_CASE("inconsistent limits are refused", "[schedule]") {
  const Toolpath path = readProgramText(fig9(), "fig9.ngc");
  VoxelStock stock = fig9Stock();
  const SimulationResult sim = simulate(path, AptCutter::flat(6.0, 18.0), stock, {});
  ScheduleOptions o;
  o.feedMin = 900.0;
  o.feedMax = 300.0;
  CHECK_THROWS_AS(scheduleFeeds(path, sim, o), ParameterError);
}

TEST_CASE("F words: levels a minimum change apart, rounded down; air feed; short runs merged",
          "[schedule]") {
  // A synthetic run: one straight 20 mm line at 1000 mm/min in 20 steps of 1 mm, whose MRR
  // goes 0 (air) for 4 steps, then 2000, 2100, 2200, ... mm^3/min.
  const Toolpath path = readProgramText("G21 G90\nG1 X20 F1000\nM2\n", "line.ngc");
  SimulationResult sim;
  for (int i = 0; i < 20; ++i) {
    StepRecord s;
    s.move = 0;
    s.line = 2;
    s.kind = MoveKind::Line;
    s.length = 1.0;
    s.arcLength = i + 1.0;
    s.end = {i + 1.0, 0, 0};
    s.feed = 1000.0;
    s.dt = 0.06;
    s.mrr = i < 4 ? 0.0 : 2000.0 + 100.0 * (i - 4);
    sim.steps.push_back(s);
  }
  ScheduleOptions o;
  o.targetMrr = 2000.0;
  o.feedMin = 100.0;
  o.feedMax = 3000.0;
  o.airFeed = 2500.0;
  o.minChange = 0.05;
  const Schedule sc = scheduleFeeds(path, sim, o);
  for (int i = 0; i < 4; ++i) {
    CHECK(sc.binding[static_cast<std::size_t>(i)] == Binding::Air);
    CHECK(sc.feed[static_cast<std::size_t>(i)] <= 2500.0);
  }
  for (std::size_t i = 4; i < 20; ++i) {
    // Never more than half a level (hysteresis, 2.5 %) above the feed that meets the target;
    // at most one level (5 %) below it.
    CHECK(sc.feed[i] <= sc.wanted[i] * (1.025 + 1e-12));
    CHECK(sc.feed[i] >= sc.wanted[i] / 1.05 * (1 - 1e-12));
    // Levels are the programmed 1000 mm/min x 1.05^k.
    const double k = std::log(sc.feed[i] / 1000.0) / std::log(1.05);
    CHECK(k == Approx(std::round(k)).margin(1e-6));
  }
  CHECK(sc.feed[4] == 1000.0);  // the target at the programmed feed: unchanged
  // Successive different feeds differ by at least the minimum change.
  for (std::size_t i = 5; i < 20; ++i)
    if (sc.feed[i] != sc.feed[i - 1])
      CHECK(std::max(sc.feed[i], sc.feed[i - 1]) / std::min(sc.feed[i], sc.feed[i - 1]) >=
            1.05 - 1e-9);
  // With a 5 mm minimum segment every run of one feed (after the air) is at least 5 steps or
  // takes a lower neighbour's feed: fewer pieces, none faster than wanted.
  o.minSegment = 5.0;
  const Schedule merged = scheduleFeeds(path, sim, o);
  CHECK(merged.fWords <= sc.fWords);
  for (std::size_t i = 4; i < 20; ++i)
    CHECK(merged.feed[i] <= merged.wanted[i] * (1.025 + 1e-12));
}

TEST_CASE("a force limit gives the target MRR through Eq 17-18", "[schedule]") {
  // F = 200 N, E = 2 J/mm^3, D = 10 mm at 10000 rpm: v = pi 10 10000 mm/min = 314159 mm/min,
  // MRR = F v / E = 200 N x 314.159 m/min / 2 J/mm^3 = 31415.9 mm^3/min.
  CHECK(mrrForForce(200.0, 2.0, 10.0, 10000.0) == Approx(31415.93).epsilon(1e-6));
  // Round trip through the forward model (Eq 18).
  CHECK(tangentialForce(mrrForForce(200.0, 2.0, 10.0, 10000.0), 2.0, cuttingSpeed(10.0, 10000.0)) ==
        Approx(200.0).epsilon(1e-12));
  CHECK_THROWS_AS(mrrForForce(0.0, 2.0, 10.0, 10000.0), ParameterError);
}

TEST_CASE("the analytic model can drive the schedule instead of the measurement", "[schedule]") {
  // The corner program with the model at s = r, d = 2: the model sees a straight path
  // (MRR 3600 at 600 mm/min everywhere), so it keeps 600 mm/min into the corner the
  // measurement slows down for (the point of paper Fig 9).
  const Toolpath path = readProgramText(fig9(), "fig9.ngc");
  VoxelStock stock = fig9Stock();
  SimulationOptions so;
  so.stepover = 3.0;
  so.depth = 2.0;
  const SimulationResult sim = simulate(path, AptCutter::flat(6.0, 18.0), stock, so);
  ScheduleOptions o;
  o.targetMrr = 3600.0;
  o.analytic = true;
  const Schedule sc = scheduleFeeds(path, sim, o);
  for (std::size_t i = 0; i < sim.steps.size(); ++i)
    if (sim.steps[i].line == 15 && sc.binding[i] == Binding::None)
      CHECK(sc.feed[i] == Approx(600.0));
}

TEST_CASE("changeDistance: S-curve distances worked by hand", "[schedule]") {
  // a = 500 mm/s^2, j = 5000 mm/s^3: a^2/j = 50 mm/s. From 10 to 40 mm/s (dv = 30 < 50): the
  // acceleration is a triangle, T = 2 sqrt(30/5000) = 0.15492 s, distance 25 T = 3.873 mm.
  CHECK(changeDistance(10, 40, 500, 5000) ==
        Approx(25 * 2 * std::sqrt(30.0 / 5000)).epsilon(1e-12));
  // From 0 to 100 mm/s (dv = 100 >= 50): T = 100/500 + 500/5000 = 0.3 s, distance 50 T = 15 mm.
  CHECK(changeDistance(0, 100, 500, 5000) == Approx(15.0).epsilon(1e-12));
  CHECK(changeDistance(100, 0, 500, 5000) == Approx(15.0).epsilon(1e-12));  // symmetric
  // Without jerk limit: Eq 24's (v1^2 - v0^2) / (2a) = 10 mm.
  CHECK(changeDistance(0, 100, 500, 0) == Approx(10.0).epsilon(1e-12));
}

TEST_CASE("a jerk limit leaves room for the controller's S-curve before a load peak",
          "[schedule]") {
  // The corner program: the schedule must slow down for the corner's peak. With a jerk limit
  // every pair of scheduled feed steps i < k on one run of feed moves must be at least the
  // S-curve distance between their feeds apart (changeDistance, checked by hand above).
  const std::string source = fig9();
  const Toolpath path = readProgramText(source, "fig9.ngc");
  const AptCutter cutter = AptCutter::flat(6.0, 18.0);
  VoxelStock stock = fig9Stock();
  const SimulationResult sim = simulate(path, cutter, stock, {});
  ScheduleOptions o;
  o.targetMrr = 3600.0;
  o.feedMin = 100.0;
  o.feedMax = 1200.0;
  o.acceleration = 500.0;
  o.minChange = 0.02;
  const Schedule loose = scheduleFeeds(path, sim, o);
  const double jerk = 500.0;  // mm/s^3: a^2/j = 500 mm/s, so every change here is a triangle
  o.jerk = jerk;
  const Schedule sc = scheduleFeeds(path, sim, o);
  const auto& st = sim.steps;
  auto feedStep = [&](std::size_t i) { return st[i].kind != MoveKind::Rapid && st[i].feed > 0; };
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < st.size(); ++i)
    for (std::size_t k = i + 1; k < st.size() && feedStep(i); ++k) {
      if (!feedStep(k)) break;
      const double need = changeDistance(sc.feed[i] / 60, sc.feed[k] / 60, 500.0, jerk);
      REQUIRE(need <= st[k].arcLength - st[i].arcLength + 1e-9);
      ++pairs;
    }
  CHECK(pairs > 1000);
  // The jerk limit only lowers feeds, and it does lower some: the slow-down starts earlier.
  bool lower = false;
  for (std::size_t i = 0; i < st.size(); ++i) {
    CHECK(sc.feed[i] <= loose.feed[i] + 1e-9);
    lower = lower || sc.feed[i] < loose.feed[i] - 1e-9;
  }
  CHECK(lower);
  CHECK(sc.timeAfter > loose.timeAfter);
}

TEST_CASE("rapids are timed from standstill to standstill", "[schedule]") {
  // 100 mm at 6000 mm/min (100 mm/s) with a = 1000 mm/s^2: 5 mm to speed up, 5 to stop,
  // 0.1 s each, 90 mm at full speed: 1.1 s. 4 mm: the peak speed sqrt(a L) = 63.25 mm/s is
  // never passed, 2 sqrt(L/a) = 0.1265 s. Feed moves are not counted.
  const Toolpath path =
      readProgramText("G21 G90\nG0 X100\nG1 X110 F600\nG0 X106\nM2\n", "rapids.ngc");
  CHECK(rapidTime(path, 6000, 1000, 0) == Approx(1.1 + 2 * std::sqrt(4.0 / 1000)).epsilon(1e-9));
  CHECK(rapidTime(path, 6000, 0, 0) == Approx(1.04).epsilon(1e-12));  // no limit: 104 mm / 100
  CHECK(rapidTime(path, 0, 1000, 0) == 0.0);
  // A jerk limit only adds time.
  CHECK(rapidTime(path, 6000, 1000, 20000) > rapidTime(path, 6000, 1000, 0));
}
