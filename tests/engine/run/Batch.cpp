// Tests of engine/run/Batch.h: a small batch's records.

#include "engine/run/Batch.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "tests/engine/run/RunTestSupport.h"

#include <fcntl.h>
#include <sched.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace engage;
using Catch::Matchers::Contains;
namespace fs = std::filesystem;

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
  CHECK(record["removed_mm3"].get<double>() == Approx((180.0 + kPi * 9.0) * 2.0).epsilon(0.002));
  CHECK(std::filesystem::exists(dir.path() / "out" / "batch.csv"));
}

TEST_CASE("a batch counts the CPUs it may use, not the machine's", "[run]") {
  cpu_set_t all;
  REQUIRE(sched_getaffinity(0, sizeof all, &all) == 0);
  // As under `taskset -c 0` or a Slurm allocation of one CPU: one (hardware_concurrency()
  // counted every core of the node before).
  cpu_set_t one;
  CPU_ZERO(&one);
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &all)) {
      CPU_SET(c, &one);
      break;
    }
  REQUIRE(sched_setaffinity(0, sizeof one, &one) == 0);
  CHECK(usableCpus() == 1);
  REQUIRE(sched_setaffinity(0, sizeof all, &all) == 0);
  CHECK(usableCpus() <= CPU_COUNT(&all));
  CHECK(usableCpus() >= 1);
}

TEST_CASE("a batch runs a job again when its program changes, not otherwise", "[run]") {
  test::TempFolder dir("batch_resume");
  dir.write("slot.ngc", test::slotProgram());
  const std::string manifest =
      dir.write("m.json", R"({"jobs": [{"program": "slot.ngc", "tool": "flat", "diameter": "6mm",
                              "stock": "box:-10,-10,-10,40,10,0"}]})");
  BatchOptions o;
  o.manifest = manifest;
  o.out = (dir.path() / "out").string();
  o.quiet = true;
  CHECK_THAT(runBatch(o).text, Contains("1 jobs: 1 run (0 failed), 0 already done"));
  CHECK_THAT(runBatch(o).text, Contains("1 jobs: 0 run (0 failed), 1 already done"));
  // The same options, but the program cut 1 mm deeper: its old results must not be reused.
  std::string deeper = test::slotProgram();
  deeper.replace(deeper.find("Z-2"), 3, "Z-3");
  dir.write("slot.ngc", deeper);
  CHECK_THAT(runBatch(o).text, Contains("1 jobs: 1 run (0 failed), 0 already done"));
  std::ifstream in(dir.path() / "out" / "jobs" / "slot" / "job.json");
  const auto record = nlohmann::json::parse(in);
  // 3 mm deep now: (30 x 6 + pi 3^2) x 3 mm^3, within the voxels' 0.2 % on a flat slot.
  CHECK(record["removed_mm3"].get<double>() == Approx((180.0 + kPi * 9.0) * 3.0).epsilon(0.002));
}

TEST_CASE("one job alone, fewer files, and a merge that lists what is missing", "[run]") {
  test::TempFolder dir("batch_job_outputs");
  dir.write("a.ngc", test::slotProgram());
  dir.write("b.ngc", test::slotProgram());
  const std::string manifest =
      dir.write("m.json", R"({"defaults": {"tool": "flat", "diameter": "6mm",
                                 "stock": "box:-10,-10,-10,40,10,0"},
                    "jobs": [{"program": "a.ngc"}, {"program": "b.ngc"}]})");
  BatchOptions o;
  o.manifest = manifest;
  o.out = (dir.path() / "out").string();
  o.quiet = true;
  o.job = "b";
  o.outputs = "summary";
  CHECK_THAT(runBatch(o).text, Contains("1 jobs: 1 run"));
  const auto folder = dir.path() / "out" / "jobs" / "b";
  CHECK(std::filesystem::exists(folder / "summary.json"));
  CHECK(std::filesystem::exists(folder / "job.json"));
  CHECK_FALSE(std::filesystem::exists(folder / "steps.csv"));
  CHECK_FALSE(std::filesystem::exists(folder / "stock.vdb"));
  CHECK_FALSE(std::filesystem::exists(dir.path() / "out" / "jobs" / "a"));
  o.job = "c";
  CHECK_THROWS_WITH(runBatch(o), Contains("--job: no job named 'c'"));
  // Job a has not run: a plain merge refuses, --allow-missing writes b's row and names a.
  o.job.clear();
  CHECK_THROWS_WITH(mergeBatch(o), Contains("1 of 2 jobs have not run"));
  o.allowMissing = true;
  CHECK_THAT(mergeBatch(o), Contains("merged 1 jobs") && Contains("missing from the table: a"));
  std::ifstream in(dir.path() / "out" / "batch.json");
  CHECK(nlohmann::json::parse(in)["missing"] == nlohmann::json::array({"a"}));
}

TEST_CASE("a job another process holds is left to it, a stale lock of a dead process is not",
          "[run]") {
  test::TempFolder dir("batch_locks");
  dir.write("slot.ngc", test::slotProgram());
  BatchOptions o;
  o.manifest =
      dir.write("m.json", R"({"jobs": [{"program": "slot.ngc", "tool": "flat", "diameter": "6mm",
                              "stock": "box:-10,-10,-10,40,10,0", "voxel": "1mm"}]})");
  o.out = (dir.path() / "out").string();
  o.quiet = true;
  const fs::path jobs = dir.path() / "out" / "jobs";
  fs::create_directories(jobs);
  char host[256] = {};
  REQUIRE(::gethostname(host, sizeof host - 1) == 0);
  {
    // flock: a lock this test holds through its own open file is another holder.
    const int fd = ::open((jobs / ".slot.lock").c_str(), O_CREAT | O_RDWR, 0644);
    REQUIRE(fd >= 0);
    REQUIRE(::flock(fd, LOCK_EX | LOCK_NB) == 0);
    CHECK_THAT(runBatch(o).text, Contains("1 jobs: 0 run (0 failed), 1 already done"));
    ::close(fd);
  }
  // Owner files (a file system without flock): a live owner on this host keeps the job; one
  // whose process is gone is stale and taken over.
  ::setenv("ENGAGE_LOCK_FILES", "1", 1);
  const fs::path owner = jobs / ".slot.lock.owner";
  std::ofstream(owner) << host << " " << ::getppid() << "\n";
  CHECK_THAT(runBatch(o).text, Contains("1 jobs: 0 run (0 failed), 1 already done"));
  CHECK(fs::exists(owner));
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  REQUIRE(::waitpid(child, nullptr, 0) == child);
  std::ofstream(owner) << host << " " << child << "\n";
  CHECK_THAT(runBatch(o).text, Contains("1 jobs: 1 run (0 failed), 0 already done"));
  CHECK_FALSE(fs::exists(owner));  // released when the job ended
  ::unsetenv("ENGAGE_LOCK_FILES");
}

TEST_CASE("a batch job that gouges its part ran to its end: status gouge, counted apart",
          "[run][part]") {
  // The slot program cuts 2 mm deep; the part (relative to the manifest) is the box below
  // Z-1.9: its floor is gouged 0.1 mm, deeper than the 0.05 mm tolerance.
  test::TempFolder dir("batch_part");
  dir.write("slot.ngc", test::slotProgram());
  dir.write("part.obj",
            "v -10 -10 -10\nv 40 -10 -10\nv 40 10 -10\nv -10 10 -10\nv -10 -10 -1.9\n"
            "v 40 -10 -1.9\nv 40 10 -1.9\nv -10 10 -1.9\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\n"
            "f 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  const std::string manifest = dir.write("m.json", R"({
    "defaults": {"tool": "flat", "diameter": "6mm", "stock": "box:-10,-10,-10,40,10,0",
                 "outputs": "summary"},
    "jobs": [{"name": "gouged", "program": "slot.ngc", "part": "part.obj"},
             {"name": "plain", "program": "slot.ngc"}]})");
  BatchOptions o;
  o.manifest = manifest;
  o.out = (dir.path() / "out").string();
  o.quiet = true;
  const BatchReport report = runBatch(o);
  CHECK(report.failures.empty());
  REQUIRE(report.gouges.size() == 1);
  CHECK_THAT(report.gouges[0], Contains("job gouged: 1 gouge(s)"));
  CHECK_THAT(report.text, Contains("(1 ok, 0 with collisions, 1 gouged their part, 0 failed)"));
  std::ifstream in(dir.path() / "out" / "jobs" / "gouged" / "job.json");
  const auto record = nlohmann::json::parse(in);
  CHECK(record["status"] == "gouge");
  CHECK(record["gouges"] == 1);
}
