// Tests of engine/run/Output.h: files written whole, and a run's files staged and published so
// that an output folder holds one complete run.

#include "engine/run/Output.h"

#include "cutters/Error.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>

using namespace engage;
namespace fs = std::filesystem;

TEST_CASE("publishing replaces an earlier run's files and moves summary.json last", "[run]") {
  test::TempFolder dir("staged_outputs");
  const fs::path out = dir.path();
  // An earlier run: its list names its re-fed program; a file of the user's is not listed.
  dir.write("summary.json", "old");
  dir.write("feed.png", "old plot");
  dir.write("part.ngc", "old re-fed program");
  dir.write(".engage-files", "feed.png\npart.ngc\nsummary.json\n");
  dir.write("notes.txt", "the user's own file");
  // The staging folder of a run on this host that died (no process has this pid: above
  // pid_max's default), and one of another host's run, which only that host can judge.
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  std::string name(host);
  for (char& c : name)
    if (c == '/' || c == '-') c = '_';
  const std::string dead = ".engage-partial-" + name + "-2147483646";
  fs::create_directories(out / dead);
  fs::create_directories(out / ".engage-partial-otherhost-1");
  {
    StagedOutputs staged(out);
    CHECK_FALSE(fs::exists(out / dead));
    CHECK(fs::exists(out / ".engage-partial-otherhost-1"));
    fs::remove_all(out / ".engage-partial-otherhost-1");
    writeAtomically(staged.staging() / "steps.csv", "step\n");
    writeAtomically(staged.staging() / "summary.json", "new");
    // Before publishing, the folder still holds the earlier run, whole.
    CHECK(readFile(out / "summary.json") == "old");
    staged.publish();
  }
  CHECK(readFile(out / "summary.json") == "new");
  CHECK(readFile(out / "steps.csv") == "step\n");
  CHECK_FALSE(fs::exists(out / "feed.png"));
  CHECK_FALSE(fs::exists(out / "part.ngc"));
  CHECK(fs::exists(out / "notes.txt"));
  CHECK(readFile(out / ".engage-files") == "steps.csv\nsummary.json\n");
  for (const auto& e : fs::directory_iterator(out))
    CHECK(e.path().filename().string().rfind(".engage-partial", 0) != 0);
}

TEST_CASE("a run that is not published leaves the folder as it was", "[run]") {
  test::TempFolder dir("staged_unpublished");
  dir.write("summary.json", "old");
  {
    StagedOutputs staged(dir.path());
    writeAtomically(staged.staging() / "summary.json", "new");
  }  // destroyed without publish(): the run failed
  CHECK(readFile(dir.path() / "summary.json") == "old");
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    (void)e;
    ++entries;
  }
  CHECK(entries == 1);
}

TEST_CASE("a file that cannot be written is an error naming it", "[run]") {
  // /proc/version is read-only: the open fails, and nothing is left beside it.
  CHECK_THROWS_WITH(writeAtomically("/proc/engage-test", "x"),
                    Catch::Matchers::Contains("cannot write '/proc/engage-test'"));
}
