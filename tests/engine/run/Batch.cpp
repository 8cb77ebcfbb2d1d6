// Tests of engine/run/Batch.h: the manifest reader's refusals and a small batch's records.

#include "engine/run/Batch.h"

#include "cutters/Error.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace engage;
using Catch::Matchers::Contains;

TEST_CASE("a manifest is refused whole before any job runs", "[run]") {
  test::TempFolder dir("manifest_refused");
  // A key given twice in one object kept only its last value before.
  const std::string twice = dir.write(
      "twice.json", R"({"jobs": [{"program": "p.ngc", "tool": "flat", "tool": "ball"}]})");
  CHECK_THROWS_WITH(readManifest(twice), Contains("the key \"tool\" is given twice"));
  const std::string unknown =
      dir.write("unknown.json", R"({"jobs": [{"program": "p.ngc", "voxle": "1"}]})");
  CHECK_THROWS_WITH(readManifest(unknown), Contains("job 1: unknown option \"voxle\""));
  const std::string out = dir.write("out.json", R"({"jobs": [{"program": "p.ngc", "out": "x"}]})");
  CHECK_THROWS_WITH(readManifest(out), Contains("\"out\" is not a job option"));
  const std::string names =
      dir.write("names.json", R"({"jobs": [{"program": "a/p.ngc"}, {"program": "b/p.ngc"}]})");
  CHECK_THROWS_WITH(readManifest(names), Contains("the name \"p\" is taken by job 1"));
  // The same key in two different objects is no duplicate.
  const std::string ok = dir.write(
      "ok.json",
      R"({"defaults": {"tool": "flat"}, "jobs": [{"program": "p.ngc", "tool": "ball"}]})");
  const auto jobs = readManifest(ok);
  REQUIRE(jobs.size() == 1);
  CHECK(jobs[0].values.at("tool") == "ball");
}

TEST_CASE("a batch runs its jobs and records a failure without stopping", "[run]") {
  test::TempFolder dir("batch_small");
  dir.write("slot.ngc", test::slotProgram());
  dir.write("broken.ngc", "G1 G2 X1 F1\n");
  const std::string manifest = dir.write("m.json", R"({
    "defaults": {"tool": "flat", "diameter": "6mm", "stock": "box:-10,-10,-10,40,10,0"},
    "jobs": [{"program": "slot.ngc", "command": "schedule", "target-mrr": "3600mm3/min",
              "jerk": "50000mm/s3", "rapid-feed": "10000mm/min"},
             {"program": "broken.ngc"}]})");
  BatchOptions o;
  o.manifest = manifest;
  o.out = (dir.path() / "out").string();
  o.quiet = true;
  const BatchReport report = runBatch(o);
  REQUIRE(report.failures.size() == 1);
  CHECK_THAT(report.failures[0], Contains("job broken failed") && Contains("1:4:"));
  std::ifstream in(dir.path() / "out" / "jobs" / "slot" / "job.json");
  const auto record = nlohmann::json::parse(in);
  CHECK(record["status"] == "ok");
  // The slot: (30 x 6 + pi 3^2) x 2 mm^3 within the voxels' 0.2 % on a flat slot.
  CHECK(record["removed_mm3"].get<double>() ==
        Approx((180.0 + 3.14159265358979 * 9.0) * 2.0).epsilon(0.002));
  CHECK(std::filesystem::exists(dir.path() / "out" / "batch.csv"));
}
