// Tests of engine/run/PartCheck.h through the pipeline: a facing program of eleven passes with
// one pass 0.3 mm too deep gouges the part by a strip that pass alone made, known in closed
// form; the option checks of --part.

#include "engine/run/PartCheck.h"

#include "cutters/Error.h"
#include "engine/run/Pipeline.h"
#include "engine/run/RunOutputs.h"
#include "engine/run/Summary.h"
#include "tests/engine/run/RunTestSupport.h"
#include "tests/support/PartMeshes.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <string>

using namespace engage;

namespace {

/// Facing the block [0, 60]^2 from Z0 to Z-3 with a 10 mm end mill: passes along X at
/// Y0, 6, ..., 60, entering and leaving beside the stock; the pass at Y24 runs at `deepZ`.
/// `deepLine` gets that pass's line.
std::string facingProgram(double deepZ, int& deepLine) {
  std::string p = "G21 G90 G17\nG0 Z5\nG0 X-6 Y0\n";
  int line = 3;
  for (int k = 0; k <= 10; ++k) {
    const double y = 6.0 * k, z = k == 4 ? deepZ : -3.0;
    const double from = k % 2 == 0 ? -6.0 : 66.0, to = k % 2 == 0 ? 66.0 : -6.0;
    char text[160];
    std::snprintf(text, sizeof text, "G1 X%g Y%g F1000\nG1 Z%g F300\nG1 X%g F1000\nG1 Z0\n", from,
                  y, z, to);
    p += text;
    line += 3;
    if (k == 4) deepLine = line;
    line += 1;
  }
  return p + "G0 Z5\nM2\n";
}

OptionValues facingJob(const std::string& program, const std::string& part) {
  return {{"program", program}, {"tool", "flat"},
          {"diameter", "10mm"}, {"stock", "box:0,0,-10,60,60,0"},
          {"voxel", "0.5mm"},   {"part", part}};
}

}  // namespace

TEST_CASE("a gouge made by one line of a long program is attributed to that line alone",
          "[part][run]") {
  // The part is the block below Z-3. The pass at Y24 cuts y in [19, 29] down to Z-3.3, the
  // others go no deeper than Z-3: the gouge is that strip, 60 x 10 mm, 0.3 mm deep, 180 mm^3,
  // and the ends of the cut on the part's sides X0 and X60 (10 x 0.25 mm each deeper than the
  // 0.05 mm tolerance): 605 mm^2. Depth within a tenth of the 0.5 mm cell, volume within 1 %;
  // the area counts whole samples, so within half a sample's width (0.18 mm) along the
  // outline (140 mm): 25 mm^2.
  test::TempFolder dir("part_check_facing");
  int deepLine = 0;
  const std::string program = dir.write("facing.ngc", facingProgram(-3.3, deepLine));
  const std::string part = dir.write("part.obj", test::objText(test::block(0, 0, -10, 60, 60, -3)));
  for (const std::string model : {"dexel", "voxel"}) {
    INFO(model);
    OptionValues v = facingJob(program, part);
    v["stock-model"] = model;
    const RunResult r = runJob(makeJob(JobCommand::Simulate, v));
    const PartCheck& c = r.part;
    REQUIRE(c.done);
    REQUIRE(c.gouges.size() == 1);
    const DeviationRegion& g = c.gouges[0];
    CHECK(g.extreme == Approx(0.3).margin(0.05));
    CHECK(g.area == Approx(605.0).margin(25.0));
    CHECK(g.volume == Approx(180.0).epsilon(0.01));
    CHECK(g.at.z() == Approx(-3.0).margin(1e-4));
    CHECK((g.at.y() > 19.0 && g.at.y() < 29.0));
    const std::vector<GougeLine> lines = gougeLines(g, r.job.path, r.sim.steps);
    REQUIRE(lines.size() == 1);
    CHECK(lines[0].line == deepLine);
    CHECK(c.leftovers.empty());
    // summary.json and gouges.csv name the line.
    const auto summary = nlohmann::json::parse(summaryJson(r));
    CHECK(summary["part"]["gouges"]["count"] == 1);
    CHECK(summary["part"]["gouges"]["regions"][0]["lines"][0]["line"] == deepLine);
    const std::string csv = regionTable(c, true, r.job.path, r.sim.steps, r.job.units);
    CHECK(csv.find("facing.ngc:" + std::to_string(deepLine) + "\"") != std::string::npos);
  }
}

TEST_CASE("a program that makes its part has no gouge and no leftover", "[part][run]") {
  test::TempFolder dir("part_check_exact");
  int deepLine = 0;
  const std::string program = dir.write("facing.ngc", facingProgram(-3.0, deepLine));
  const std::string part = dir.write("part.obj", test::objText(test::block(0, 0, -10, 60, 60, -3)));
  const RunResult r = runJob(makeJob(JobCommand::Simulate, facingJob(program, part)));
  CHECK(r.part.gouges.empty());
  CHECK(r.part.leftovers.empty());
  // With the allowance 0 everything left counts: still nothing (the top is read at Z-3 within
  // 1e-4 of a cell), and the tolerance 0 finds no gouge.
  OptionValues strict = facingJob(program, part);
  strict["tolerance"] = "0.001mm";
  strict["allowance"] = "0.001mm";
  const RunResult s = runJob(makeJob(JobCommand::Simulate, strict));
  CHECK(s.part.gouges.empty());
  CHECK(s.part.leftovers.empty());
}

TEST_CASE("the part option refuses what it cannot compare", "[part][run]") {
  test::TempFolder dir("part_check_errors");
  int deepLine = 0;
  const std::string program = dir.write("facing.ngc", facingProgram(-3.0, deepLine));
  const std::string part = dir.write("part.obj", test::objText(test::block(0, 0, -10, 60, 60, -3)));
  OptionValues v = facingJob(program, part);
  v.erase("part");
  v["tolerance"] = "0.1mm";
  CHECK_THROWS_WITH(makeJob(JobCommand::Simulate, v), "--tolerance applies with --part");
  v = facingJob(program, dir.path().string() + "/missing.stl");
  CHECK_THROWS_WITH(makeJob(JobCommand::Simulate, v), Catch::Contains("--part: file not found"));
  v = facingJob(program, part);
  v["allowance"] = "-1";
  CHECK_THROWS_WITH(makeJob(JobCommand::Simulate, v), Catch::Contains("must not be negative"));
  // A part far from the stock: wrong units or frame.
  const std::string far =
      dir.write("far.obj", test::objText(test::block(100, 0, -10, 160, 60, -3)));
  CHECK_THROWS_WITH(runJob(makeJob(JobCommand::Simulate, facingJob(program, far))),
                    Catch::Contains("lies outside the stock"));
  // An open mesh: its inside is not defined.
  TriangleMesh open = test::block(0, 0, -10, 60, 60, -3);
  open.triangles.pop_back();
  const std::string openFile = dir.write("open.obj", test::objText(open));
  CHECK_THROWS_WITH(runJob(makeJob(JobCommand::Simulate, facingJob(program, openFile))),
                    Catch::Contains("not closed"));
}

TEST_CASE("a part from a .vdb level set: a run's own final stock is its part", "[part][run]") {
  // The facing run's stock.vdb holds its surface as a level set (within 0.2 of a cell of the
  // fractions' surface away from edges, docs/outputs.md): taken as the part, the same run's
  // final stock deviates from it by less than a third of the 0.5 mm cell on its faces, the
  // deep pass's strip included: no gouge, and no leftover at 0.17 mm but along the block's
  // edges, which the level set rounds (0.37 mm there).
  test::TempFolder dir("part_check_vdb");
  int deepLine = 0;
  const std::string program = dir.write("facing.ngc", facingProgram(-3.3, deepLine));
  OptionValues first = facingJob(program, "");
  first.erase("part");
  first["stock-model"] = "voxel";
  first["out"] = (dir.path() / "first").string();
  runIntoFolder(makeJob(JobCommand::Simulate, first));
  OptionValues again = facingJob(program, (dir.path() / "first" / "stock.vdb").string());
  again["stock-model"] = "voxel";
  again["tolerance"] = "0.17mm";
  again["allowance"] = "0.17mm";
  const RunResult r = runJob(makeJob(JobCommand::Simulate, again));
  REQUIRE(r.part.done);
  CHECK(r.part.gouges.empty());
  for (const DeviationRegion& left : r.part.leftovers) {
    const Eigen::Vector3d& p = left.at;
    const double fromSide = std::min({p.x(), 60 - p.x(), p.y(), 60 - p.y(), p.z() + 10});
    CHECK(fromSide < 0.5);
  }
  // The part's volume: the block below Z-3 less the deep pass's strip, 60 x 60 x 7 mm less
  // 0.3 x 600 mm^3 (the mesh of the level set within a cell's rounding: 0.5 %).
  CHECK(r.part.partVolume == Approx(60 * 60 * 7 - 0.3 * 600).epsilon(0.005));
}
