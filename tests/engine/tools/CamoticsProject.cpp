// Tests of engine/tools/CamoticsProject.h: a CAMotics project's files, tools and workpiece,
// and CAMotics' automatic workpiece rule checked on boxes computed by hand.

#include "engine/tools/CamoticsProject.h"

#include "cutters/Error.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/run/Job.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>

using namespace engage;
using Catch::Matchers::Contains;

namespace {

void checkBox(const Box3& b, Eigen::Vector3d lo, Eigen::Vector3d hi) {
  for (int a = 0; a < 3; ++a) {
    CHECK(b.min[a] == Approx(lo[a]).margin(1e-9));
    CHECK(b.max[a] == Approx(hi[a]).margin(1e-9));
  }
}

}  // namespace

TEST_CASE("a CAMotics project gives its programs, tools and workpiece box", "[tools]") {
  const CamoticsProject p =
      readCamoticsProject(ENGAGE_SOURCE_DIR "/data/tools/three_tools.camotics");
  REQUIRE(p.files.size() == 1);
  CHECK(p.files[0] == ENGAGE_SOURCE_DIR "/data/gcode/multitool/three_tools.ngc");
  CHECK_FALSE(p.automatic);
  checkBox(p.bounds, {0, 0, -10}, {60, 40, 0});
  CHECK(p.tools.require(2).cutter->shape() == CutterShape::Ball);
  CHECK(isCamoticsProject("a/b.CAMotics"));
  CHECK_FALSE(isCamoticsProject("a/b.ngc"));

  test::TempFolder dir("camotics_project");
  auto errorOf = [&](const std::string& text) {
    try {
      readCamoticsProject(dir.write("p.camotics", text));
    } catch (const ParameterError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string tools = R"("tools": {"1": {"units": "metric", "shape": "cylindrical",
                                 "length": 10, "diameter": 2}})";
  dir.write("a.ngc", "G0 X0\n");
  CHECK_THAT(errorOf("{" + tools + R"(, "files": ["logo.tpl"]})"),
             Contains("\"logo.tpl\" is a TPL program"));
  CHECK_THAT(errorOf("{" + tools + R"(, "files": ["gone.ngc"]})"), Contains("no program"));
  CHECK_THAT(errorOf("{" + tools + R"(})"), Contains("\"files\": expected the list"));
  CHECK_THAT(errorOf(R"({"files": ["a.ngc"]})"),
             Contains("has a \"tools\" object; this file has none"));
  CHECK_THAT(errorOf("{" + tools + R"(, "files": ["a.ngc"],
                      "workpiece": {"automatic": false, "bounds": {"min": [0, 0]}}})"),
             Contains("workpiece.bounds.min: expected [x, y, z]"));
  // CAMotics' default workpiece is automatic with a 5 % margin.
  const std::string ok = dir.write("ok.camotics", "{" + tools + R"(, "files": ["a.ngc"]})");
  const CamoticsProject d = readCamoticsProject(ok);
  CHECK(d.automatic);
  CHECK(d.marginPercent == 5.0);
}

TEST_CASE("CAMotics' automatic workpiece, by hand", "[tools]") {
  // A plunge from Z5 to Z-1 at the origin and a 10 mm line along X at Z-1.
  const Toolpath path = readProgramText("G0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nG0 Z5\nM2\n", "p.ngc");
  const AptCutter flat = AptCutter::flat(2.0, 10.0);
  // Flat D2: the moves' boxes x [-1, 11], y [-1, 1], z [-1, 5 + 10]; below Z0, so the top is
  // lowered to 0; 1 mm thick, less than 2: 2 mm more below (-3); a 10 % margin of (12, 2, 3)
  // on every side but the top.
  checkBox(camoticsAutomaticWorkpiece(
               path, [&](int) -> const AptCutter& { return flat; }, 10.0),
           {-2.2, -1.2, -3.3}, {12.2, 1.2, 0.0});
  // A ball D2: its box starts one radius below the tip (z -2), 2 mm thick: no more added;
  // margin (1.2, 0.2, 0.2).
  const AptCutter ball = AptCutter::ball(2.0, 10.0);
  checkBox(camoticsAutomaticWorkpiece(
               path, [&](int) -> const AptCutter& { return ball; }, 10.0),
           {-2.2, -1.2, -2.2}, {12.2, 1.2, 0.0});
}

TEST_CASE("a project's programs run one after the other, each from where the last stopped",
          "[tools][run]") {
  test::TempFolder dir("camotics_two_files");
  dir.write("a.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nM2\n");
  // The second program names Y only: X and Z stay where the first left them.
  dir.write("b.ngc", "G21 G90\nG1 Y10 F100\nM2\n");
  const std::string project = dir.write("p.camotics", R"({
      "tools": {"1": {"units": "metric", "shape": "cylindrical", "length": 10, "diameter": 2}},
      "workpiece": {"automatic": false, "bounds": {"min": [-5, -5, -3], "max": [15, 15, 0]}},
      "files": ["a.ngc", "b.ngc"]})");
  const Job job = makeJob(JobCommand::Simulate, {{"program", project}});
  REQUIRE(job.path.moves.size() == 4);
  const Move& last = job.path.moves.back();
  CHECK(last.start.isApprox(Eigen::Vector3d(10, 0, -1)));
  CHECK(last.end.isApprox(Eigen::Vector3d(10, 10, -1)));
  CHECK(job.path.files[static_cast<std::size_t>(last.file)] == (dir.path() / "b.ngc").string());
  // No tool is loaded: T1, as CAMotics selects it; the workpiece is the project's box.
  CHECK(job.startTool == 1);
  CHECK(job.cutters.of(0).radius() == Approx(1.0).margin(1e-12));
  REQUIRE(job.stock.box);
  checkBox(*job.stock.box, {-5, -5, -3}, {15, 15, 0});
  // schedule re-feeds one program: a project of two is refused.
  try {
    makeJob(JobCommand::Schedule, {{"program", project}});
    FAIL("a two-program project was scheduled");
  } catch (const ParameterError& e) {
    CHECK_THAT(std::string(e.what()), Contains("schedule re-feeds one program"));
  }
}

TEST_CASE("a project without T1 starts with the tool its program loads", "[tools][run]") {
  // As CAMotics' genes-encoder example: a rapid, then M06 T7, and the project has T7 alone.
  test::TempFolder dir("camotics_no_t1");
  dir.write("a.ngc", "G21 G90\nG0 X0 Y0\nM06 T7\nG0 Z5\nG1 Z-1 F100\nG1 X10\nM2\n");
  const std::string project = dir.write("p.camotics", R"({
      "tools": {"7": {"units": "metric", "shape": "cylindrical", "length": 10, "diameter": 3}},
      "workpiece": {"automatic": false, "bounds": {"min": [-5, -5, -3], "max": [15, 15, 0]}},
      "files": ["a.ngc"]})");
  const Job job = makeJob(JobCommand::Simulate, {{"program", project}});
  CHECK(job.startTool == 7);
  CHECK(job.cutters.of(0).radius() == Approx(1.5).margin(1e-12));
}
