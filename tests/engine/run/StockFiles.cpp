// Tests of engine/run/StockFiles.h: the stock's files written side by side.

#include "engine/run/StockFiles.h"

#include "engine/run/Job.h"
#include "engine/run/Pipeline.h"
#include "tests/engine/run/RunTestSupport.h"

#include <tbb/parallel_for.h>
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <thread>

using namespace engage;
using Catch::Matchers::Contains;

TEST_CASE("a stock file that cannot be written does not cut short the work beside it", "[run]") {
  test::TempFolder dir("stock_files_failure");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  const RunResult r = runJob(makeJob(JobCommand::Simulate, {{"program", program},
                                                            {"tool", "flat"},
                                                            {"diameter", "6mm"},
                                                            {"stock-model", "voxel"},
                                                            {"voxel", "0.5mm"},
                                                            {"stock", "box:-10,-10,-10,40,10,0"}}));
  REQUIRE(r.stock);
  const StockView view(r);
  // A folder that does not exist: every file fails at once, while the task beside them (the
  // report's 3D view, here a parallel loop that takes a while) must still run to its end, not
  // stop half-way as a cancelled loop would. Its count is exact: every index once.
  constexpr int kItems = 2000;
  std::atomic<int> visited{0};
  auto slowLoop = [&] {
    tbb::parallel_for(0, kItems, [&](int) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      ++visited;
    });
  };
  // The first file in the documented order is the one named: removed.vdb.
  CHECK_THROWS_WITH(writeStockFiles(r, view, dir.path() / "missing" / "folder", slowLoop),
                    Contains("removed.vdb"));
  CHECK(visited == kItems);
}
