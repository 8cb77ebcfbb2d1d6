// Tests of engine/run/Pipeline.h and the writers it feeds (StepsTable.h, Summary.h,
// RunOutputs.h) on a slot whose removal is known in closed form.

#include "engine/run/Pipeline.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/run/RunOutputs.h"
#include "engine/run/StepsTable.h"
#include "engine/run/Summary.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace engage;

namespace {

OptionValues slotJob(const std::string& program) {
  return {{"program", program},
          {"tool", "flat"},
          {"diameter", "6mm"},
          {"stock", "box:-10,-10,-10,40,10,0"}};
}

std::size_t lineCount(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

}  // namespace

TEST_CASE("the pipeline measures a slot as its closed form", "[run]") {
  test::TempFolder dir("pipeline_slot");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  const RunResult r = runJob(makeJob(JobCommand::Simulate, slotJob(program)));
  REQUIRE(r.stock);
  // The slot: the stadium 30 x 6 mm plus a 3 mm disc, 2 mm deep. The default (dexel) stock is
  // within 0.5 % per step of closed forms at the default spacing (docs/accuracy.md); the total
  // of a flat slot far tighter: 0.2 % allows for the rim of 0.3 mm columns.
  const double slot = (30.0 * 6.0 + kPi * 9.0) * 2.0;
  CHECK(r.sim.removed == Approx(slot).epsilon(0.002));
  // The steady MRR D d F = 7200 mm^3/min at the step of the peak (the plunge is slower).
  CHECK(r.sim.steps[r.peakStep].mrr == Approx(7200.0).epsilon(0.005));
  CHECK_FALSE(r.crossChecked);
  CHECK(r.plan.feed.empty());

  // The writers: one row per step plus the header, columns in the run's units.
  const std::string csv = stepsTable(r);
  CHECK(lineCount(csv) == r.sim.steps.size() + 1);
  CHECK(csv.rfind("step,move,line,tool,kind,arc_length_mm,x_mm,", 0) == 0);
  const auto summary = nlohmann::json::parse(summaryJson(r));
  CHECK(summary["removed"].get<double>() == Approx(r.sim.removed).epsilon(1e-12));
  CHECK(summary["peak_mrr"]["line"].get<int>() == r.sim.steps[r.peakStep].line);
  CHECK(summary["stock_model"] == "dexel");
  CHECK_FALSE(summary.contains("schedule"));
}

TEST_CASE("the pipeline in inches reports inches", "[run]") {
  test::TempFolder dir("pipeline_inch");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  OptionValues v = slotJob(program);
  v["units"] = "in";
  v["stock"] = "box:-10mm,-10mm,-10mm,40mm,10mm,0mm";
  const RunResult r = runJob(makeJob(JobCommand::Simulate, v));
  const auto summary = nlohmann::json::parse(summaryJson(r));
  CHECK(summary["units"] == "in");
  // 1 in^3 = 25.4^3 mm^3.
  CHECK(summary["removed"].get<double>() ==
        Approx(r.sim.removed / (25.4 * 25.4 * 25.4)).epsilon(1e-12));
  CHECK(stepsTable(r).rfind("step,move,line,tool,kind,arc_length_in,", 0) == 0);
}

TEST_CASE("the pipeline cross-checks and schedules", "[run]") {
  test::TempFolder dir("pipeline_schedule");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  OptionValues v = slotJob(program);
  v["cross-check"] = "true";
  // Half the steady MRR: the slot's steady feed halves, 600 -> 300 mm/min (d D F = 3600).
  v["target-mrr"] = "3600mm3/min";
  const RunResult r = runJob(makeJob(JobCommand::Schedule, v));
  REQUIRE(r.crossChecked);
  REQUIRE(r.cross.other.steps.size() == r.sim.steps.size());
  // Both stock models are within 0.5 % of a slot's closed form: no step differs by 3 %.
  CHECK(r.cross.differing.empty());
  CHECK(r.cross.other.removed == Approx(r.sim.removed).epsilon(0.005));
  REQUIRE(r.plan.feed.size() == r.sim.steps.size());
  // The steady steps of the slot: the middle third of the 30 mm, far from entry and exit.
  std::size_t steady = 0;
  for (std::size_t i = 0; i < r.sim.steps.size(); ++i) {
    const StepRecord& s = r.sim.steps[i];
    if (s.kind != MoveKind::Line || s.feed != 600.0 || s.end.x() < 10.0 || s.end.x() > 20.0)
      continue;
    ++steady;
    // The scheduled feed sits on a level no more than min-change (5 %) below the wanted one.
    CHECK(r.plan.feed[i] <= 300.0 * 1.0001);
    CHECK(r.plan.feed[i] >= 300.0 * 0.95);
  }
  CHECK(steady > 10);
  CHECK(r.refed.find("F") != std::string::npos);
  const auto summary = nlohmann::json::parse(summaryJson(r));
  CHECK(summary["schedule"]["target_mrr"].get<double>() == Approx(3600.0).epsilon(1e-12));
  CHECK(summary["cross_check"]["other_model"] == "voxel");
}

TEST_CASE("runIntoFolder writes every file, and a refused job writes none", "[run]") {
  test::TempFolder dir("pipeline_folder");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  OptionValues v = slotJob(program);
  v["out"] = (dir.path() / "out").string();
  v["quiet"] = "true";
  const CompletedRun run = runIntoFolder(makeJob(JobCommand::Simulate, v));
  for (const char* f : {"steps.csv", "summary.json", "removed.vdb", "stock.vdb", "stock.stl"})
    CHECK(std::filesystem::exists(dir.path() / "out" / f));
  CHECK(run.written.openEdges == 0);
  CHECK(runReport(run.result, run.written).find("removed ") != std::string::npos);

  // A stock the path never reaches: refused before the output folder is made.
  v["stock"] = "box:500,500,-10,560,560,0";
  v["out"] = (dir.path() / "refused").string();
  CHECK_THROWS_WITH(runIntoFolder(makeJob(JobCommand::Simulate, v)),
                    Catch::Matchers::Contains("the tool path never reaches the stock"));
  CHECK_FALSE(std::filesystem::exists(dir.path() / "refused"));
}

TEST_CASE("warnings where the answer cannot be trusted", "[run]") {
  test::TempFolder dir("pipeline_warnings");
  auto warningsOf = [&](const std::string& text, const OptionValues& extra) {
    OptionValues v = slotJob(dir.write("p.ngc", text));
    for (const auto& [k, value] : extra)
      v[k] = value;
    const RunResult r = runJob(makeJob(JobCommand::Simulate, v));
    std::string all;
    for (const std::string& w : runWarnings(r, WrittenOutputs{}))
      all += w + "\n";
    return all;
  };
  using Catch::Matchers::Contains;
  CHECK(warningsOf(test::slotProgram(), {}).empty());
  // A program without G20 or G21, read in mm unless the start-up units are given.
  const std::string noUnits = "G90\nG0 X0 Y0 Z5\nG1 Z-2 F100\nG1 X30 F600\nM2\n";
  CHECK_THAT(warningsOf(noUnits, {}), Contains("the program sets neither G20 nor G21: read in mm"));
  CHECK(warningsOf(noUnits, {{"startup-units", "mm"}}).empty());
  // M codes engage does not know, each named with its lines.
  CHECK_THAT(warningsOf("G21 G90\nM31\nG0 X0 Y0 Z5\nM31\nM100\nG1 Z-2 F100\nG1 X30 F600\nM2\n", {}),
             Contains("M31 (lines 2, 4); M100 (line 5): M codes engage does not know, taken as "
                      "machine functions that move no axis"));
  // 6 mm tool, 1.5 mm voxels: 4 across it.
  CHECK_THAT(warningsOf(test::slotProgram(), {{"voxel", "1.5"}}),
             Contains("fewer than 5 cells across it"));
  // A 60 deg V-bit 0.07 mm deep engages 2 x 0.07 tan 30 = 0.081 mm: a cell of 0.159 mm (D/20
  // of its 3.175 mm) is coarse for it.
  CHECK_THAT(warningsOf("G21 G90\nG0 X0 Y0 Z1\nG1 Z-0.07 F100\nG1 X30 F600\nG0 Z1\nM2\n",
                        {{"tool", "chamfer"},
                         {"diameter", "3.175mm"},
                         {"tip-angle", "60deg"},
                         {"voxel", "0.159"}}),
             Contains("coarse for the 0.080829 mm the 3.175 mm tool engages at 0.07 mm deep"));
  // The path passes 1 mm above the stock: it reaches the box's bounds but cuts nothing.
  CHECK_THAT(warningsOf("G21 G90\nG0 X0 Y0 Z1\nG1 X30 F600\nM2\n", {}),
             Contains("removed no material"));
  // 4.5e6 mm/min, a feed no machine runs (an inch feed typed in the wrong units, say).
  CHECK_THAT(warningsOf("G21 G90\nG0 X0 Y0 Z5\nG1 Z-2 F100\nG1 X30 F4500000\nM2\n", {}),
             Contains("1 move(s) feed faster than 100 m/min, first at line 4"));
}

TEST_CASE("bounded work: what would run for hours or fill the memory is refused up front",
          "[run]") {
  test::TempFolder dir("pipeline_bounded");
  using Catch::Matchers::Contains;
  // A move of 1e10 mm: 1.3e10 steps of 0.75 mm (out of memory before; an int overflow too).
  OptionValues v = slotJob(
      dir.write("long.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10000000000 F600\nM2\n"));
  v["out"] = (dir.path() / "out").string();
  CHECK_THROWS_WITH(runIntoFolder(makeJob(JobCommand::Simulate, v)),
                    Contains("more than the limit of 5000000 (--max-steps)") &&
                        Contains("at line 4, is 1e+10 mm long"));
  CHECK_FALSE(std::filesystem::exists(dir.path() / "out"));
  // 100000 turns of a 5 mm circle: 4.2e6 steps, refused below that limit.
  v = slotJob(dir.write("turns.ngc",
                        "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG2 X0 Y0 I5 J0 P100000 F600\nM2\n"));
  v["max-steps"] = "1000000";
  CHECK_THROWS_WITH(prepareRun(makeJob(JobCommand::Simulate, v)), Contains("4.18881e+06 steps"));
  // A loop that never ends: refused at --max-moves.
  v = slotJob(dir.write("forever.ngc",
                        "G21 G90\nG0 X0 Y0 Z5\no1 while [1]\nG1 X10 F600\n"
                        "G1 X0\no1 endwhile\nM2\n"));
  v["max-moves"] = "1000";
  CHECK_THROWS_WITH(makeJob(JobCommand::Simulate, v), Contains("expected at most 1000 moves"));
  // A taper of 89.9 deg is 10 m wide at its flute length.
  v = slotJob(dir.write("slot.ngc", test::slotProgram()));
  v["tool"] = "taper";
  v["taper-angle"] = "89.9deg";
  CHECK_THROWS_WITH(makeJob(JobCommand::Simulate, v),
                    Contains("--taper-angle: expected at most 85 deg"));
}

TEST_CASE("a program of three tools: each tool's removal and target as its closed form",
          "[run][tools]") {
  // data/gcode/multitool/three_tools.ngc, 40 mm features along X, tools from a Fusion library:
  // - T1 6 mm flat, 2 mm deep slot: (40 x 6 + pi 3^2) x 2 mm^3; steady MRR D d F = 6 2 600.
  // - T2 4 mm ball, 1 mm deep: the circle segment at 1 mm from a 2 mm centre,
  //   A = r^2 acos((r-d)/r) - (r-d) sqrt(2rd - d^2) = 4 pi/3 - sqrt 3 mm^2, times 40 mm, plus
  //   the spherical cap pi d^2 (3r - d) / 3 of the two half-ends; steady MRR A F, F = 800.
  // - T3 90 deg V-bit, 1 mm deep: a triangle of area 1 mm^2 times 40 mm plus the cone
  //   pi 1^2 1 / 3 of the two half-ends; steady MRR 1 mm^2 x 500 mm/min.
  // Dexel stock at the default spacing: measured within 0.013 % of these (the V-bit's; 0.03 %
  // with the linear column share before); 0.05 % allowed.
  const double segment = 4.0 * kPi / 3.0 - std::sqrt(3.0);
  const double expected[] = {(40.0 * 6.0 + kPi * 9.0) * 2.0,
                             segment * 40.0 + kPi * 1.0 * (6.0 - 1.0) / 3.0, 40.0 + kPi / 3.0};
  const double targets[] = {6.0 * 2.0 * 600.0, segment * 800.0, 500.0};
  const OptionValues v = {{"program", ENGAGE_SOURCE_DIR "/data/gcode/multitool/three_tools.ngc"},
                          {"tools", ENGAGE_SOURCE_DIR "/data/tools/three_tools.json"},
                          {"stock", "box:0,0,-10,60,40,0"},
                          {"stock-model", "dexel"}};
  const RunResult r = runJob(makeJob(JobCommand::Schedule, v));
  const auto summary = nlohmann::json::parse(summaryJson(r));
  CHECK(summary["tool_library"]["format"] == "fusion360");
  REQUIRE(summary["tools"].size() == 3);
  for (int t = 0; t < 3; ++t) {
    const auto& tool = summary["tools"][static_cast<std::size_t>(t)];
    CHECK(tool["number"] == t + 1);
    CHECK(tool["removed"].get<double>() == Approx(expected[t]).epsilon(0.0005));
    // The automatic target is the median steady MRR of each tool: its steady slot MRR.
    // Measured -0.003 % (T1), +0.04 % (T2), +0.12 % (T3); 0.2 % allowed. (With the linear
    // column share before, T1's steps alternated 7146 / 7254 mm^3/min, the 0.5 mm step beating
    // the 0.2 mm dexel spacing at the cutter's round front.)
    CHECK(tool["target_mrr"].get<double>() == Approx(targets[t]).epsilon(0.002));
  }
  CHECK(summary["removed"].get<double>() ==
        Approx(expected[0] + expected[1] + expected[2]).epsilon(0.0005));
  // No step of one tool was scheduled towards another's target: T3's steady feed stays near
  // its programmed 500 mm/min (MRR at the target), not 14x faster towards T1's 7200 mm^3/min.
  for (std::size_t i = 0; i < r.sim.steps.size(); ++i)
    if (r.sim.steps[i].tool == 3 && r.sim.steps[i].feed == 500.0)
      CHECK(r.plan.feed[i] <= 500.0 * 1.06);
}

TEST_CASE("rapids, shanks and holders that meet material are collisions, with their lines",
          "[run][tools]") {
  // data/gcode/multitool/crashes.ngc with T1 of three_tools.json: flat D6, flutes 18 mm, the
  // shank (D6) up to 25 mm, then the holder (D22, 10 mm tall) in a box whose top is Z0.
  const double stadium = kPi * 9.0 + 6.0 * 20.0 / 27.0;  // disc + one step (20 mm / 27 steps)
  struct Expected {
    int line;
    const char* part;
    double volume, tolerance;
  };
  // - line 7: the cutter removes up to Z-2, the shank meets the top 2 mm: per step its disc
  //   and the step's stadium, 2 mm tall (the most at one step). 3 %: a layer of cells on
  //   the shank's 2 x (pi 6 + 2 x 0.74) mm^2 of contact.
  // - line 10: a rapid plunge 1 mm deep, pi 3^2 x 1; line 11: a rapid 10 mm along X at 1 mm,
  //   its disc already gone: 10 x 6 x 1. 1 %: what the stock models do on a slot's ends.
  // - line 14: the plunge swept the flutes through its column; the holder's face (D22) meets
  //   the ring pi (11^2 - 3^2) x 1 mm at the bottom. 6 %: the 1 mm contact is 3.3 cells of
  //   0.3 mm, and the cell centres below the top take 3.5 of them (1.05 mm, voxels +4.8 %).
  const Expected expected[] = {{7, "shank", 2.0 * stadium, 0.03},
                               {10, "rapid", kPi * 9.0, 0.01},
                               {11, "rapid", 60.0, 0.01},
                               {14, "holder", kPi * (121.0 - 9.0), 0.06}};
  for (const char* model : {"voxel", "dexel"}) {
    const OptionValues v = {{"program", ENGAGE_SOURCE_DIR "/data/gcode/multitool/crashes.ngc"},
                            {"tools", ENGAGE_SOURCE_DIR "/data/tools/three_tools.json"},
                            {"stock", "box:0,0,-30,60,40,0"},
                            {"stock-model", model}};
    const RunResult r = runJob(makeJob(JobCommand::Simulate, v));
    INFO(model);
    for (const Expected& e : expected) {
      INFO("line " << e.line << " " << e.part);
      const auto found =
          std::find_if(r.sim.collisions.begin(), r.sim.collisions.end(),
                       [&](const Collision& c) { return c.line == e.line && c.part == e.part; });
      REQUIRE(found != r.sim.collisions.end());
      CHECK(found->tool == 1);
      CHECK(found->volume == Approx(e.volume).epsilon(e.tolerance));
    }
    // The plunge of line 14 swept its flutes up the whole column: no shank contact there.
    for (const Collision& c : r.sim.collisions)
      CHECK_FALSE((c.line == 14 && c.part == "shank"));
    const auto summary = nlohmann::json::parse(summaryJson(r));
    CHECK(summary["collisions"]["count"].get<std::size_t>() == r.sim.collisions.size());
  }
  // The clean program with the same tool, shank and holder: none.
  const OptionValues clean = {
      {"program", ENGAGE_SOURCE_DIR "/data/gcode/multitool/three_tools.ngc"},
      {"tools", ENGAGE_SOURCE_DIR "/data/tools/three_tools.json"},
      {"stock", "box:0,0,-10,60,40,0"}};
  CHECK(runJob(makeJob(JobCommand::Simulate, clean)).sim.collisions.empty());
}

namespace {

/// The paper's Fig 9 corner at a stepover of a quarter diameter (s = 1.5 mm, D = 6 mm, 2 mm
/// deep, 600 mm/min, S10000 M3, two flutes: f_z = 0.03 mm): the current pass cuts ae = 1.5 mm
/// on its right, down milling, from phi = pi - acos(1 - 2 ae / D) = 120 deg to 180 deg, so
/// h_max = f_z sin(120 deg) = 0.866 f_z on the straight parts; at the corner the arc reaches
/// straight ahead (phi = 90 deg) and h_max = f_z.
std::string quarterCorner() {
  return "G21 G90 G17\nS10000 M3\nG0 X-25 Y1.5 Z5\nG1 Z-2 F100\nG1 X-1.5 F600\nG1 Y25\nG0 Z5\n"
         "G0 X-20 Y0\nG1 Z-2 F100\nG1 X0 F600\nG1 Y20\nG0 Z5\nM2\n";
}

OptionValues cornerJob(const std::string& program) {
  return {{"program", program},
          {"tool", "flat"},
          {"diameter", "6mm"},
          {"flutes", "2"},
          {"stock-model", "dexel"},
          {"voxel", "0.15mm"},
          {"material", "aluminium-7075-t6"},
          {"stock", "box:-30,-10,-10,10,30,0"}};
}

}  // namespace

TEST_CASE("cutting physics along the Fig 9 corner: chip thinning, and the corner's rise",
          "[run][physics]") {
  test::TempFolder dir("pipeline_physics");
  const std::string program = dir.write("corner.ngc", quarterCorner());
  const RunResult r = runJob(makeJob(JobCommand::Simulate, cornerJob(program)));
  const auto& st = r.sim.steps;
  REQUIRE(r.sim.loads.size() == st.size());
  const double fz = 600.0 / (10000.0 * 2.0);
  double straightH = 0.0, straightF = 0.0, straightT = 0.0, straightMrr = 0.0;
  std::size_t straight = 0, corner = 0;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (st[i].line != 10) continue;  // the current pass along y = 0
    if (st[i].end.x() > -15.0 && st[i].end.x() < -5.0) {
      // Down milling from 120 deg: the entry read within 2.05 deg at 0.15 mm rays (1.64 deg
      // with the linear column share before the exact one: the contact is read from the
      // shares' 1/2 level, which a wall crossed by the last step's round front moves), 2.5
      // allowed; d h / d phi = f_z cos(120 deg) -> 1.7 % of h; 3 %.
      CHECK(r.sim.loads[i].hMax == Approx(fz * std::sin(2.0 * kPi / 3.0)).epsilon(0.03));
      CHECK(r.sim.loads[i].entry == Approx(2.0 * kPi / 3.0).margin(2.5 * kPi / 180.0));
      CHECK(r.sim.loads[i].exit == Approx(kPi).margin(2.0 * kPi / 180.0));
      straightH = std::max(straightH, r.sim.loads[i].hMax);
      straightF = std::max(straightF, r.sim.loads[i].peak);
      straightT = std::max(straightT, r.sim.loads[i].torque);
      straightMrr = std::max(straightMrr, st[i].mrr);
      ++straight;
    }
    if (std::abs(st[i].end.x()) < 1e-9) corner = i;  // the step ending at the corner
  }
  REQUIRE(straight > 10);
  REQUIRE(corner > 0);
  const StepLoad& c = r.sim.loads[corner];
  // At the corner the engagement reaches straight ahead: the full feed per tooth.
  CHECK(c.hMax == Approx(fz).epsilon(0.01));
  CHECK(c.hMax > 1.1 * straightH);
  // The MRR, the torque and the peak force rise together there.
  CHECK(st[corner].mrr > 1.3 * straightMrr);
  CHECK(c.torque > 1.3 * straightT);
  // Two flutes: mostly one tooth in the cut, whose largest chip grows from 0.866 f_z to f_z;
  // the edge forces, which do not grow, take a share of the rise: about +10 %.
  CHECK(c.peak > 1.05 * straightF);
  // No force in the air of the rapids.
  for (std::size_t i = 0; i < st.size(); ++i)
    if (st[i].kind == MoveKind::Rapid) CHECK(r.sim.loads[i].peak == 0.0);
}

TEST_CASE("a schedule to a chip thickness target holds it when re-simulated", "[run][physics]") {
  test::TempFolder dir("pipeline_chip_schedule");
  const std::string program = dir.write("corner.ngc", quarterCorner());
  OptionValues o = cornerJob(program);
  o["max-chip"] = "0.04mm";
  o["out"] = (dir.path() / "out").string();
  const RunResult r = runJob(makeJob(JobCommand::Schedule, o));
  REQUIRE_FALSE(r.refed.empty());
  CHECK(std::count(r.plan.binding.begin(), r.plan.binding.end(), Binding::Chip) > 50);
  // The re-fed program, simulated again: every step within the target (the feed levels are
  // rounded down, F (1 + 5 %)^k: at most 5 % below it where the chip limit binds; 1 % above
  // for the measurement's noise), and within 5 % of it on the straight parts.
  OptionValues again = cornerJob(dir.write("refed.ngc", r.refed));
  const RunResult s = runJob(makeJob(JobCommand::Simulate, again));
  std::size_t straight = 0;
  for (std::size_t i = 0; i < s.sim.steps.size(); ++i) {
    const double h = s.sim.loads[i].hMax;
    if (std::isnan(h)) continue;  // plunges
    CHECK(h <= 0.04 * 1.01);
    const StepRecord& st = s.sim.steps[i];
    if (std::abs(st.end.y()) < 1e-9 && st.end.x() > -15.0 && st.end.x() < -5.0) {
      CHECK(h == Approx(0.04).epsilon(0.05));
      ++straight;
    }
  }
  CHECK(straight > 10);
}

TEST_CASE("a 4th-axis wrap re-fed in inverse time holds its chip limit", "[run][physics]") {
  // A 6 mm flat end mill turns a 20 x 20 mm square bar round on A (table-a, no tip control),
  // 4 mm of X a turn, in G93; a chip limit 1.4 times the programmed chip (0.0057 mm).
  test::TempFolder dir("pipeline_wrap_schedule");
  const std::string program =
      dir.write("wrap.ngc",
                "G21 G90 G94\nG0 X-3.5 Y0 Z20 A0\nG0 Z9\nG93\nG1 X0.5 A360 F2\nG1 X4.5 A720 F2\n"
                "G1 X8.5 A1080 F2\nG94\nG0 Z20\nM2\n");
  OptionValues o = {{"program", program},
                    {"machine", ENGAGE_SOURCE_DIR "/data/machines/table_a.json"},
                    {"tool", "flat"},
                    {"diameter", "6mm"},
                    {"stock", "box:0,-10,-10,8,10,10"},
                    {"start", "-5,0,40"},
                    {"voxel", "0.5mm"},
                    {"material", "aluminium-7075-t6"},
                    {"spindle", "10000rpm"},
                    {"max-chip", "0.008mm"},
                    {"out", (dir.path() / "out").string()}};
  const RunResult r = runJob(makeJob(JobCommand::Schedule, o));
  REQUIRE_FALSE(r.refed.empty());
  CHECK(std::count(r.plan.binding.begin(), r.plan.binding.end(), Binding::Chip) > 50);
  // Re-simulated: the chip within the limit (1 % for the measurement's noise), the same
  // removal (the same swept path in other steps: to the cell's rounding, 0.1 %).
  REQUIRE(r.verified.done);
  for (const LimitCheck& c : r.verified.checks)
    CHECK(c.holds);
  CHECK(r.verified.removed == Approx(r.sim.removed).epsilon(1e-3));
  // The re-fed moves: inverse time, each piece's A where the line from (X-3.5, A0) to
  // (X8.5, A1080) has it (A = 90 (X + 3.5)), and their minutes add up to the scheduled time.
  const Toolpath back = readProgramText(r.refed, program, r.job.reader);
  double minutes = 0.0;
  std::size_t pieces = 0;
  for (const Move& m : back.moves) {
    if (m.kind == MoveKind::Rapid) continue;
    ++pieces;
    CHECK(m.feedMode == FeedMode::InverseTime);
    CHECK(m.rotaryEnd.x() == Approx(90.0 * (m.end.x() + 3.5)).margin(1e-5));
    minutes += m.minutes;
  }
  CHECK(pieces > 3);
  CHECK(pieces == r.plan.fWords);
  // Each step at its scheduled feed, its speed on the part, as long as the F words say (the
  // F words to 6 decimals; Schedule::timeAfter averages successive speeds instead).
  double seconds = 0.0;
  for (std::size_t i = 0; i < r.sim.steps.size(); ++i)
    if (r.sim.steps[i].kind != MoveKind::Rapid && r.sim.steps[i].feed > 0.0)
      seconds += r.sim.steps[i].length / r.plan.feed[i] * 60.0;
  CHECK(minutes * 60.0 == Approx(seconds).epsilon(1e-6));
  CHECK(r.plan.timeAfter < 0.9 * r.plan.timeBefore);
}

TEST_CASE("a job's memory estimate follows its stock's closed-form bounds", "[run]") {
  test::TempFolder dir("pipeline_memory");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  OptionValues v = {{"program", program},     {"tool", "flat"},
                    {"diameter", "6mm"},      {"stock", "box:0,0,-10,10,10,0"},
                    {"stock-model", "voxel"}, {"voxel", "1mm"}};
  // Voxels (VoxelStock::memoryBound), on 64 MB for the rest. The box's faces fall halfway
  // through voxels (centred on whole mm): X and Y hold voxels 0 .. 10, leaves of 8 voxels 0 .. 1
  // (2), Z -10 .. 0, leaves -2 .. 0 (3), so the faces take 2 (2 x 3) + 2 (3 x 2) + 2 (2 x 2) =
  // 32 leaves of 2.5 kB. The slot (D 6 along Y 0, 2 deep: Y 0 .. 3, Z -2 .. 0, a voxel beyond,
  // within the box) reaches leaves 0 .. 1 along X, 0 along Y, -1 .. 0 along Z: 4 leaves of 512
  // voxels of 40 bytes.
  const double voxels = 32 * 2.5e3 + 4 * 512 * 40.0;
  MemoryEstimate e = memoryEstimate(makeJob(JobCommand::Simulate, v));
  CHECK(e.fixed == 64e6);
  CHECK(e.stocks == Approx(voxels));
  CHECK(e.outputs == Approx(voxels));  // the stock files: as much again (--outputs all)
  // The slot's 10 mm at steps of at most 2.5 voxels (2.5 mm), plus its plunge and rapids: at
  // least 4 steps of a record each.
  CHECK(e.steps >= 4 * sizeof(StepRecord));
  v["outputs"] = "summary";
  CHECK(memoryEstimate(makeJob(JobCommand::Simulate, v)).outputs == 0.0);
  // Dexels: 10 x 10 rays of 100 bytes each, the stock files 160 bytes a ray.
  v["stock-model"] = "dexel";
  v["outputs"] = "all";
  e = memoryEstimate(makeJob(JobCommand::Simulate, v));
  CHECK(e.stocks == Approx(100 * 100.0));
  CHECK(e.outputs == Approx(100 * 160.0));
  // A board whose stock.vdb is made at a coarser cell (its faces alone: 7 (2 (4001 x 3001 +
  // 3001 x 161 + 161 x 4001) + 2 x 4000 x 3000) = 3.4e8 band voxels at 0.01 mm, over the 2e7
  // of VoxelStock::kFileBandVoxels): 12 million rays, the files 60 bytes a ray (measured 27).
  {
    OptionValues board = v;
    board["stock"] = "box:0,0,-1.6,40,30,0";
    board["voxel"] = "0.01mm";
    const MemoryEstimate b = memoryEstimate(makeJob(JobCommand::Simulate, board));
    CHECK(b.stocks == Approx(12e6 * 100.0).epsilon(1e-3));  // (a ray more or less a side)
    CHECK(b.outputs == Approx(12e6 * 60.0).epsilon(1e-3));
  }
  // A cross-check holds both stocks.
  v["cross-check"] = "true";
  CHECK(memoryEstimate(makeJob(JobCommand::Simulate, v)).stocks == Approx(100 * 100.0 + voxels));
  // A run that needs more than --max-memory is refused before it starts, with its estimate.
  v["max-memory"] = "10MB";
  try {
    prepareRun(makeJob(JobCommand::Simulate, v));
    FAIL("a run of about 64 MB under --max-memory 10MB was not refused");
  } catch (const ParameterError& err) {
    const std::string m = err.what();
    CHECK(m.find("this run needs about 64 MB of memory") != std::string::npos);
    CHECK(m.find("may use 10 MB (--max-memory)") != std::string::npos);
  }
  v["max-memory"] = "1GB";
  CHECK_NOTHROW(prepareRun(makeJob(JobCommand::Simulate, v)));
}

TEST_CASE("without a machine the tool starts above a stock that reaches above Z0", "[run]") {
  // The program's Z0 is the stock's bottom (a 10 mm block from Z0 up): the tool, taken to start
  // at the program's origin, would start inside it and its first rapid to Z15 would be a
  // crash. It starts at the stock's top instead: no collision, and the slot (15 x 6 x 2 mm)
  // with its plunge's disc (pi 3^2 x 2) is all that is removed: 236.55 mm^3 (0.2 %: the
  // dexels' rim, as the slot test above).
  test::TempFolder dir("pipeline_start_above");
  OptionValues v = {
      {"program",
       dir.write("p.ngc", "G21 G90\nG0 Z15\nG0 X5 Y5\nG1 Z8 F100\nG1 X20\nG0 Z15\nM2\n")},
      {"tool", "flat"},
      {"diameter", "6mm"},
      {"stock", "box:0,0,0,30,30,10"}};
  const RunResult r = runJob(makeJob(JobCommand::Simulate, v));
  CHECK(r.sim.collisions.empty());
  CHECK(r.sim.removed == Approx(180.0 + 18.0 * kPi).epsilon(0.002));
  CHECK(r.job.path.moves.front().start.z() == 10.0);
}
