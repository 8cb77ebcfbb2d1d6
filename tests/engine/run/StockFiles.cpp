// Tests of engine/run/StockFiles.h: the stock's files written side by side.

#include "engine/run/StockFiles.h"

#include "engine/run/Job.h"
#include "engine/run/Pipeline.h"
#include "stock/DexelMesh.h"
#include "tests/engine/run/RunTestSupport.h"

#include <tbb/parallel_for.h>
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <optional>
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

TEST_CASE("a dexel run's surfaces for stock.stl and the report are made together, each the same",
          "[run]") {
  // The view's two budgets (stock.stl's and the report's) made from one reading of the rays:
  // each the mesh the budget alone gives (heightfieldMesh), handed out once; asked again, or
  // for another budget, it is made anew, the same.
  test::TempFolder dir("stock_view_budgets");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  const RunResult r = runJob(makeJob(JobCommand::Simulate, {{"program", program},
                                                            {"tool", "flat"},
                                                            {"diameter", "6mm"},
                                                            {"voxel", "0.5mm"},
                                                            {"stock", "box:-10,-10,-10,40,10,0"}}));
  REQUIRE(r.stock);
  const StockView view(r, {2000000, 200});
  REQUIRE(view.dexels());
  for (const std::size_t budget : {200, 2000000, 200, 500}) {
    double cell = 0.0, alone = 0.0;
    const TriangleMesh mesh = view.surface(budget, &cell);
    const std::optional<TriangleMesh> one = heightfieldMesh(*view.dexels(), budget, &alone);
    REQUIRE(one);
    INFO("budget " << budget);
    CHECK(cell == alone);
    CHECK(mesh.triangles == one->triangles);
    CHECK(mesh.points == one->points);
    CHECK(mesh.triangles.size() <= budget);
  }
}
