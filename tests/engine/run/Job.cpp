// Tests of engine/run/Job.h: the typed job that makeJob reads from option values, and its one
// validation, whose errors name the option and the value.

#include "engine/run/Job.h"

#include "cutters/Error.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>

#include <string>

using namespace engage;

namespace {

OptionValues slotJob(const std::string& program) {
  return {{"program", program},
          {"tool", "flat"},
          {"diameter", "6mm"},
          {"stock", "box:-10,-10,-10,40,10,0"}};
}

/// The message makeJob throws for these values, or "" when it accepts them.
std::string errorOf(JobCommand command, const OptionValues& values) {
  try {
    makeJob(command, values);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("makeJob types every option in internal units", "[run]") {
  test::TempFolder dir("job_typed");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  OptionValues v = slotJob(program);
  Job job = makeJob(JobCommand::Simulate, v);
  CHECK(job.units == UnitSystem::Metric);
  CHECK(job.cutter.radius() == Approx(3.0).epsilon(1e-12));
  // Default voxel: D / 20 = 0.3 mm; default flutes 2.
  CHECK(job.voxel == Approx(0.3).epsilon(1e-12));
  CHECK(job.cutter.fluteCount() == 2);
  REQUIRE(job.stock.box);
  CHECK(job.stock.box->min.x() == -10.0);
  CHECK(job.stock.box->max.x() == 40.0);
  CHECK(job.stock.box->min.z() == -10.0);
  CHECK(job.stock.box->max.z() == 0.0);
  CHECK(job.path.moves.size() == 4);
  CHECK_FALSE(job.scheduling());

  // Suffixed numbers keep their unit (0.01 in = 0.254 mm); --units sets the reports' units.
  v["units"] = "in";
  v["voxel"] = "0.01in";
  v["step"] = "0.5mm";
  job = makeJob(JobCommand::Simulate, v);
  CHECK(job.units == UnitSystem::Inch);
  CHECK(job.voxel == Approx(0.254).epsilon(1e-12));
  CHECK(job.simulation.stepLength == Approx(0.5).epsilon(1e-12));

  // Schedule settings: 0.3 g = 0.3 * 9806.65 mm/s^2; 1000 mm3/min; the default min-change.
  OptionValues s = slotJob(program);
  s["target-mrr"] = "1000mm3/min";
  s["accel"] = "0.3g";
  s["jerk"] = "50000mm/s3";
  s["rapid-feed"] = "10000mm/min";
  job = makeJob(JobCommand::Schedule, s);
  CHECK(job.schedule.targetMrr == Approx(1000.0).epsilon(1e-12));
  CHECK(job.schedule.acceleration == Approx(0.3 * 9806.65).epsilon(1e-12));
  CHECK(job.schedule.jerk == Approx(50000.0).epsilon(1e-12));
  CHECK(job.schedule.rapidFeed == Approx(10000.0).epsilon(1e-12));
  CHECK(job.schedule.minChange == Approx(0.05).epsilon(1e-12));
}

TEST_CASE("makeJob refuses bad values, naming the option and the value", "[run]") {
  test::TempFolder dir("job_errors");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  auto with = [&](const std::string& key, const std::string& value) {
    OptionValues v = slotJob(program);
    v[key] = value;
    return v;
  };
  using Catch::Matchers::Contains;
  const JobCommand sim = JobCommand::Simulate, sched = JobCommand::Schedule;
  CHECK(errorOf(sim, slotJob(program)).empty());
  CHECK_THAT(errorOf(sim, with("voxle", "1")), Contains("unknown option \"voxle\""));
  CHECK_THAT(errorOf(sim, with("voxel", "abc")), Contains("--voxel: expected a length"));
  CHECK_THAT(errorOf(sim, with("voxel", "abc")), Contains("'abc'"));
  CHECK_THAT(errorOf(sim, with("voxel", "-1mm")), Contains("--voxel must be positive"));
  CHECK_THAT(errorOf(sim, with("stock-model", "cubes")),
             Contains("--stock-model: expected voxel or dexel, found 'cubes'"));
  CHECK_THAT(errorOf(sim, with("flutes", "2.5")),
             Contains("--flutes: expected a whole number, found '2.5'"));
  CHECK_THAT(errorOf(sim, with("cross-check", "yes")),
             Contains("--cross-check: expected true or false, found 'yes'"));
  CHECK_THAT(errorOf(sim, with("target-mrr", "5")),
             Contains("--target-mrr applies to schedule jobs only"));
  CHECK_THAT(errorOf(sched, with("min-change", "2")),
             Contains("--min-change: expected a fraction in (0, 1), found 2"));
  CHECK_THAT(errorOf(sched, with("jerk", "-5mm/s3")),
             Contains("--jerk must not be negative, found '-5mm/s3'"));
  CHECK_THAT(errorOf(sched, with("feed-min", "-1")),
             Contains("--feed-min must not be negative, found '-1'"));
  CHECK_THAT(errorOf(sim, with("stock", "box:0,0,-10")),
             Contains("expected box:X0,Y0,Z0,X1,Y1,Z1 (six numbers), found 3"));
  // A box the other way round is refused, naming the axis and the values as typed.
  CHECK(errorOf(sim, with("stock", "box:30,5,0,-5,-5,-5")) ==
        "--stock box: expected X0 below X1 (box:X0,Y0,Z0,X1,Y1,Z1, the low corner first), found "
        "X0 = 30 mm and X1 = -5 mm in 'box:30,5,0,-5,-5,-5'");
  CHECK_THAT(errorOf(sim, with("stock", "box:0,0,0,10,10,0")), Contains("expected Z0 below Z1"));
  // Several missing options are named together.
  OptionValues bare{{"program", program}};
  CHECK(errorOf(sim, bare) == "--tool (or --tools) and --stock are required");
  bare["tool"] = "flat";
  CHECK(errorOf(sim, bare) == "--diameter and --stock are required");
  CHECK_THAT(errorOf(sim, with("diameter", "")), Contains("--diameter is required"));
  CHECK_THAT(errorOf(sim, with("corner-radius", "1mm")),
             Contains("--corner-radius does not apply to a flat cutter"));
  OptionValues noStock = slotJob(program);
  noStock.erase("stock");
  CHECK_THAT(errorOf(sim, noStock), Contains("--stock is required"));
  // Without a stock only the analytic schedule runs, and then the stock's side may be given.
  noStock["model"] = "analytic";
  noStock["material-side"] = "left";
  CHECK(errorOf(sched, noStock).empty());
  CHECK_THAT(errorOf(sched, with("material-side", "left")),
             Contains("--material-side applies without --stock"));
  CHECK_THAT(errorOf(sim, with("program", dir.path().string() + "/none.ngc")),
             Contains("none.ngc"));
  // A lathe program is read, not simulated as if it were milling.
  CHECK_THAT(errorOf(sim, with("program", dir.write("lathe.ngc", "G18 G21 G7\nG0 X20 Z2\nM2\n"))),
             Contains("lathe.ngc:1: a lathe program (G7, lathe diameter mode)"));
  // A target of 0 or below is an error, not "auto".
  CHECK_THAT(errorOf(sched, with("target-mrr", "0")),
             Contains("--target-mrr must be positive (or auto), found '0'"));
  CHECK_THAT(errorOf(sched, with("target-mrr", "-5mm3/min")), Contains("must be positive"));
  // schedule writes the re-fed program into --out under the program's name: never over it.
  CHECK_THAT(errorOf(sched, with("out", dir.path().string())),
             Contains("would replace the program"));
  CHECK(errorOf(sched, with("out", (dir.path() / "out").string())).empty());
}

TEST_CASE("the report units change the reports only, not how bare numbers are read", "[run]") {
  test::TempFolder dir("job_units");
  const std::string program = dir.write("slot.ngc", test::slotProgram());  // G21: mm
  OptionValues v = slotJob(program);
  v["units"] = "in";
  v["voxel"] = "0.25";
  const Job job = makeJob(JobCommand::Simulate, v);
  CHECK(job.units == UnitSystem::Inch);
  // The box and the voxel in the program's mm, as without --units (they were read in inches).
  REQUIRE(job.stock.box);
  CHECK(job.stock.box->max.x() == 40.0);
  CHECK(job.voxel == Approx(0.25).epsilon(1e-12));
  CHECK(job.cutter.radius() == Approx(3.0).epsilon(1e-12));
  // "inch" is a name of the unit here as everywhere else.
  v["units"] = "inch";
  CHECK(makeJob(JobCommand::Simulate, v).units == UnitSystem::Inch);
  v["units"] = "furlong";
  CHECK_THROWS_WITH(makeJob(JobCommand::Simulate, v),
                    Catch::Matchers::Contains("--units: expected mm, in or inch"));
}

TEST_CASE("makeJob gives each tool of a program its cutter, or says which one it lacks",
          "[run][tools]") {
  const std::string program = ENGAGE_SOURCE_DIR "/data/gcode/multitool/three_tools.ngc";
  const std::string tools = ENGAGE_SOURCE_DIR "/data/tools/";
  using Catch::Matchers::Contains;
  const JobCommand sim = JobCommand::Simulate;
  OptionValues one = slotJob(program);
  // One --tool for a program that changes tools would sweep the wrong cutter silently.
  CHECK_THAT(errorOf(sim, one),
             Contains("the program changes tools (T1 from line 6, T2 from line 14, T3 from "
                      "line 22) and --tool gives one cutter"));
  OptionValues lib = {
      {"program", program}, {"tools", tools + "three_tools.tbl"}, {"stock", "box:0,0,-10,60,40,0"}};
  const Job job = makeJob(sim, lib);
  REQUIRE(job.cutters.byTool.size() == 4);  // T1-T3 and tool 0, before the first change
  CHECK(job.cutters.of(2).shape() == CutterShape::Ball);
  CHECK(job.startTool == 1);
  // The narrowest engagement sets the default cell, a twentieth of it: T3's 90 deg V-bit 1 mm
  // deep engages 2 mm (T2's 4 mm ball 1 mm deep 2 sqrt(3) = 3.46 mm, T1's 6 mm flat 6 mm).
  CHECK(job.voxel == Approx(0.1).margin(1e-12));
  CHECK(job.cellChoice.engagement.tool == 3);
  CHECK(job.cellChoice.limit == CellLimit::Engaged);
  CHECK(job.tools.at(3).origin == tools + "three_tools.tbl:3");

  test::TempFolder dir("job_tools");
  lib["tools"] = dir.write("two.tbl", "T1 D6 ;flat\nT2 D4 ;ball\n");
  CHECK_THAT(errorOf(sim, lib), Contains("three_tools.ngc:22: T3: " + dir.path().string() +
                                         "/two.tbl: no tool T3 (it has T1, T2)"));
  lib["tools"] = dir.write("bad.tbl", "T1 D6 ;flat\nT2 D4 ;ball\nT3 D6 ;vbit\n");
  CHECK_THAT(errorOf(sim, lib), Contains("three_tools.ngc:22: T3: tool T3 (vbit) at"));
  CHECK_THAT(errorOf(sim, lib), Contains("without angle="));
  // A program that loads no tool runs with --tool; --tools alone cannot say which.
  const std::string plain = dir.write("slot.ngc", test::slotProgram());
  OptionValues noChange = {{"program", plain},
                           {"tools", tools + "three_tools.tbl"},
                           {"stock", "box:-10,-10,-10,40,10,0"}};
  CHECK_THAT(errorOf(sim, noChange), Contains("the program loads no tool"));
  noChange["tool"] = "flat";
  CHECK_THAT(errorOf(sim, noChange), Contains("--diameter is required with --tool"));
  noChange["diameter"] = "6mm";
  CHECK(errorOf(sim, noChange).empty());
  OptionValues stray = slotJob(plain);
  stray.erase("tool");
  CHECK_THAT(errorOf(sim, stray), Contains("--diameter describes the --tool cutter"));
}

TEST_CASE("G41 takes its radius from a tool library of any format", "[run][tools]") {
  // data/tools/three_tools.json (Fusion 360): T1 is a 6 mm flat end mill. The entry from the
  // origin to X20 with the tool on the left ends a radius (3 mm) left of X20 Y0.
  test::TempFolder dir("job_comp_library");
  const std::string program =
      dir.write("comp.ngc",
                "G21 G17 G90\nT1 M6\nF300\nG0 X0 Y0 Z5\nG1 Z-1\nG41 D1 G1 X20 Y0\nG1 X40\n"
                "G40 G1 X50 Y-10\nG0 Z5\nM2\n");
  const OptionValues v = {{"program", program},
                          {"tools", ENGAGE_SOURCE_DIR "/data/tools/three_tools.json"},
                          {"stock", "box:-10,-10,-10,60,40,0"}};
  const Job job = makeJob(JobCommand::Simulate, v);
  bool found = false;
  for (const Move& m : job.path.moves)
    if (m.line == 6) {
      CHECK(m.end.x() == Approx(20.0).margin(1e-9));
      CHECK(m.end.y() == Approx(3.0).margin(1e-9));
      found = true;
    }
  CHECK(found);
}

TEST_CASE("a LinuxCNC tool table is read in the program's units", "[run]") {
  // The program's first G20 or G21 outside comments: a "(G21 ...)" comment and a "; G21"
  // remark do not count. A 0.25 in flat read in inches is 6.35 mm across; read in mm, 0.25 mm.
  test::TempFolder dir("job_table_units");
  const std::string table = dir.write("tools.tbl", "T1 P1 D0.25 ;flat\n");
  const std::string program =
      dir.write("p.ngc",
                "(G21 would be metric) ; G21\nG20 G90\nT1 M6\nG0 X0 Y0 Z0.1\nG1 Z-0.05 F10\n"
                "G1 X1\nM2\n");
  OptionValues v = {{"program", program}, {"tools", table}, {"stock", "box:-1,-1,-1,2,1,0"}};
  CHECK(makeJob(JobCommand::Simulate, v).cutters.byTool.at(1).radius() ==
        Approx(3.175).margin(1e-12));
  v["tool-table-units"] = "mm";
  CHECK(makeJob(JobCommand::Simulate, v).cutters.byTool.at(1).radius() ==
        Approx(0.125).margin(1e-12));
  // Neither G20 nor G21: the start-up units.
  const std::string bare =
      dir.write("bare.ngc", "G90\nT1 M6\nG0 X0 Y0 Z0.1\nG1 Z-0.05 F10\nG1 X1\nM2\n");
  OptionValues b = {{"program", bare},
                    {"tools", table},
                    {"stock", "box:-1,-1,-1,2,1,0"},
                    {"startup-units", "in"}};
  CHECK(makeJob(JobCommand::Simulate, b).cutters.byTool.at(1).radius() ==
        Approx(3.175).margin(1e-12));
}

TEST_CASE("the start position (--start): where the tool tip is when the program starts", "[run]") {
  test::TempFolder dir("job_start");
  const std::string inch = dir.write("p.ngc", "G20 G90\nG0 X1 Y1\nG1 Z-0.05 F10\nG1 X2\nM2\n");
  OptionValues v = {{"program", inch},
                    {"tool", "flat"},
                    {"diameter", "0.25"},
                    {"stock", "box:-1,-1,-1,3,2,0"},
                    {"start", "0.5,0.25,2"}};
  const Job job = makeJob(JobCommand::Simulate, v);
  // Hand conversion: 0.5, 0.25, 2 in.
  CHECK(job.reader.start.x() == Approx(12.7).margin(1e-12));
  CHECK(job.reader.start.y() == Approx(6.35).margin(1e-12));
  CHECK(job.reader.start.z() == Approx(50.8).margin(1e-12));
  CHECK(job.reader.startKnown);
  // The first rapid starts there (not at the origin raised to the stock's top).
  REQUIRE(!job.path.moves.empty());
  CHECK(job.path.moves.front().start.z() == Approx(50.8).margin(1e-12));
  v["start"] = "1,2";
  CHECK_THAT(errorOf(JobCommand::Simulate, v),
             Catch::Matchers::Contains("--start: expected X,Y,Z (three lengths), found '1,2'"));
}
