// Tests of engine/run/Manifest.h: a manifest is read and checked whole before any job runs.

#include "engine/run/Manifest.h"

#include "cutters/Error.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>

#include <filesystem>

using namespace engage;
using Catch::Matchers::Contains;

TEST_CASE("a manifest is refused whole before any job runs", "[run]") {
  test::TempFolder dir("manifest_refused");
  // A key given twice in one object kept only its last value before.
  const std::string twice = dir.write(
      "twice.json", R"({"jobs": [{"program": "p.ngc", "tool": "flat", "tool": "ball"}]})");
  CHECK_THROWS_WITH(readManifest(twice), Contains("the key \"tool\" is given twice"));
  // A number beyond a double (found by fuzzing: it terminated the program).
  const std::string huge =
      dir.write("huge.json", R"({"jobs": [{"program": "p.ngc", "voxel": 9e9999}]})");
  CHECK_THROWS_WITH(readManifest(huge), Contains("not valid JSON") && Contains("number overflow"));
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

TEST_CASE("a manifest's jobs are the same however its path is typed", "[run]") {
  test::TempFolder dir("manifest_paths");
  std::filesystem::create_directories(dir.path() / "sub");
  const std::string m =
      dir.write("sub/m.json", R"({"jobs": [{"program": "p.ngc", "tool": "flat"}]})");
  std::filesystem::create_directory_symlink(dir.path() / "sub", dir.path() / "link");
  const auto absolute = readManifest(m);
  const auto linked = readManifest((dir.path() / "link" / "m.json").string());
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  const auto relative = readManifest("sub/../sub/m.json");
  std::filesystem::current_path(cwd);
  REQUIRE(absolute.size() == 1);
  CHECK(absolute[0].specJson == linked[0].specJson);
  CHECK(absolute[0].specJson == relative[0].specJson);
  CHECK(absolute[0].values.at("program") ==
        std::filesystem::weakly_canonical(dir.path() / "sub" / "p.ngc").string());
}

TEST_CASE("a manifest's tool library is relative to it and part of its jobs", "[run][tools]") {
  test::TempFolder dir("manifest_tools");
  std::filesystem::create_directories(dir.path() / "sub");
  const std::string m = dir.write("sub/m.json", R"({"jobs": [{"program": "p.ngc",
      "tools": "shop.tbl", "stock": "box:0,0,-10,60,40,0"}]})");
  dir.write("sub/shop.tbl", "T1 D6 ;flat\n");
  const auto before = readManifest(m);
  REQUIRE(before.size() == 1);
  CHECK(std::filesystem::path(before[0].values.at("tools")) ==
        (dir.path() / "sub" / "shop.tbl").lexically_normal());
  // An edited library makes another job (a batch runs it again).
  dir.write("sub/shop.tbl", "T1 D8 ;flat\n");
  CHECK(readManifest(m)[0].specJson != before[0].specJson);
}
