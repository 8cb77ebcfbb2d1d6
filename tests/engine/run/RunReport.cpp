// Tests of engine/run/RunReport.h: the run's page carries summary.json whole, every step (or
// every bucket's extremes and every peak), and the stock's surface with the step that cut
// each vertex.

#include "engine/run/RunReport.h"

#include "engine/run/Pipeline.h"
#include "engine/run/StockFiles.h"
#include "engine/run/Summary.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>

using namespace engage;
using nlohmann::json;

namespace {

/// The page's data: the JSON of <script id="engage-data">.
json pageData(const std::string& page) {
  const std::string open = R"(<script id="engage-data" type="application/json">)";
  const auto from = page.find(open);
  REQUIRE(from != std::string::npos);
  const auto to = page.find("</script>", from);
  return json::parse(page.substr(from + open.size(), to - from - open.size()));
}

/// Base64 decoded (written here again, not shared with the code under test).
std::string unbase64(const std::string& text) {
  auto digit = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
  };
  std::string out;
  int bits = 0, value = 0;
  for (char c : text) {
    const int d = digit(c);
    if (d < 0) break;  // padding
    value = (value << 6) | d;
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((value >> bits) & 0xff);
    }
  }
  return out;
}

template <typename T>
std::vector<T> decoded(const json& field) {
  const std::string bytes = unbase64(field.get<std::string>());
  std::vector<T> v(bytes.size() / sizeof(T));
  std::memcpy(v.data(), bytes.data(), v.size() * sizeof(T));
  return v;
}

}  // namespace

TEST_CASE("a run's page carries its summary, its steps and its cut surface", "[run][report]") {
  test::TempFolder dir("run_report_slot");
  const std::string program = dir.write("slot.ngc", test::slotProgram());
  const RunResult r = runJob(makeJob(JobCommand::Simulate, {{"program", program},
                                                            {"tool", "flat"},
                                                            {"diameter", "6mm"},
                                                            {"stock", "box:-10,-10,-10,40,10,0"}}));
  const std::string summary = summaryJson(r);
  const json data = pageData(
      runReportHtml(r, summary, reportSteps(r, summary), WrittenOutputs{}, StockView(r).voxels()));
  CHECK(data["summary"] == json::parse(summary));
  // Fewer steps than kAllSteps: every one, in order, with its line.
  const json& s = data["series"];
  REQUIRE(s["step"].size() == r.sim.steps.size());
  for (std::size_t i = 0; i < r.sim.steps.size(); ++i) {
    CHECK(s["step"][i] == i);
    CHECK(s["line"][i] == r.sim.steps[i].line);
  }
  // The slot's G-code lines are there for the steps.
  CHECK(data["source"]["0:4"] == "G1 X30 F600");

  // The surface: a closed mesh's arrays, each vertex's row in the table of cutting steps.
  const json& surf = data["surface"];
  const auto positions = decoded<float>(surf["positions"]);
  const auto indices = decoded<std::uint32_t>(surf["indices"]);
  const auto rows = decoded<std::int32_t>(surf["vertex_row"]);
  const std::size_t vertices = surf["vertices"].get<std::size_t>();
  REQUIRE(positions.size() == 3 * vertices);
  REQUIRE(rows.size() == vertices);
  CHECK(indices.size() == 3 * surf["triangles"].get<std::size_t>());
  CHECK(*std::max_element(indices.begin(), indices.end()) < vertices);
  const json& table = data["surface_steps"];
  std::size_t floor = 0, top = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    const float x = positions[3 * v], y = positions[3 * v + 1], z = positions[3 * v + 2];
    REQUIRE(rows[v] >= -1);
    REQUIRE(rows[v] < static_cast<std::int32_t>(table["step"].size()));
    // The slot's floor (2 mm deep, away from its ends): cut by the slot's line, 4.
    if (std::abs(z + 2.0f) < 0.05f && x > 5.0f && x < 25.0f && std::abs(y) < 2.0f) {
      ++floor;
      REQUIRE(rows[v] >= 0);
      CHECK(table["line"][static_cast<std::size_t>(rows[v])] == 4);
    }
    // The top face more than a cell from the slot: never cut.
    if (std::abs(z) < 0.05f && std::abs(y) > 3.0f + 2.0f * surf["cell"].get<float>()) {
      ++top;
      CHECK(rows[v] == -1);
    }
  }
  CHECK(floor > 10);
  CHECK(top > 10);
}

TEST_CASE("an inch run's page has its surface and its steps both in inches", "[run][report]") {
  test::TempFolder dir("run_report_inch");
  const std::string program =
      dir.write("slot.ngc", "G20 G90 G17\nG0 X0 Y0 Z0.2\nG1 Z-0.08 F4\nG1 X1.2 F24\nG0 Z0.2\nM2\n");
  // Bare numbers in the program's units: the stock is 2 x 0.8 x 0.4 in.
  const RunResult r =
      runJob(makeJob(JobCommand::Simulate, {{"program", program},
                                            {"tool", "flat"},
                                            {"diameter", "0.25in"},
                                            {"stock", "box:-0.4,-0.4,-0.4,1.6,0.4,0"}}));
  const std::string summary = summaryJson(r);
  const json data = pageData(
      runReportHtml(r, summary, reportSteps(r, summary), WrittenOutputs{}, StockView(r).voxels()));
  const auto positions = decoded<float>(data["surface"]["positions"]);
  REQUIRE(positions.size() >= 3);
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (std::size_t i = 0; i < positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], positions[i]);
    hi[i % 3] = std::max(hi[i % 3], positions[i]);
  }
  // The mesh spans the stock box in inches, to a cell (D/20 = 0.0125 in) on each side.
  const float cell = data["surface"]["cell"].get<float>();
  CHECK(cell == Approx(0.0125).epsilon(1e-6));
  const float box[2][3] = {{-0.4f, -0.4f, -0.4f}, {1.6f, 0.4f, 0.0f}};
  for (int a = 0; a < 3; ++a) {
    CHECK(std::abs(lo[a] - box[0][a]) <= cell);
    CHECK(std::abs(hi[a] - box[1][a]) <= cell);
  }
  // The steps' positions are in inches too: the slot runs from X0 to X1.2.
  const json& x = data["series"]["x"];
  const auto [xmin, xmax] = std::minmax_element(
      x.begin(), x.end(),
      [](const json& p, const json& q) { return p.get<double>() < q.get<double>(); });
  CHECK(xmin->get<double>() == Approx(0.0).margin(1e-9));
  CHECK(xmax->get<double>() == Approx(1.2).epsilon(1e-9));
}

TEST_CASE("a long run's plots keep every bucket's extremes and the peaks", "[run][report]") {
  // 300 moves of 1 mm at feeds that jump about, cut into 0.01 mm steps: 30,000 steps, more
  // than kAllSteps. Without a stock (schedule --model analytic) the analytic MRR is stepover x
  // depth x feed per step.
  test::TempFolder dir("run_report_long");
  std::string text = "G21 G90 G17\nG0 X0 Y0 Z0\n";
  for (int i = 1; i <= 300; ++i)
    text += "G1 X" + std::to_string(i) + " F" + std::to_string(100 + (i * 37) % 500) + "\n";
  text += "M2\n";
  const std::string program = dir.write("long.ngc", text);
  const RunResult r = runJob(makeJob(JobCommand::Schedule, {{"program", program},
                                                            {"model", "analytic"},
                                                            {"tool", "flat"},
                                                            {"diameter", "6mm"},
                                                            {"stepover", "3mm"},
                                                            {"depth", "1mm"},
                                                            {"step", "0.01mm"}}));
  const std::size_t n = r.sim.steps.size();
  REQUIRE(n > kAllSteps);
  const std::vector<std::size_t> kept = reportSteps(r, summaryJson(r));
  CHECK(std::is_sorted(kept.begin(), kept.end()));
  CHECK(kept.size() < 3 * kBuckets);  // about two a bucket here (highest and lowest MRR)
  CHECK(kept.front() == 0);
  CHECK(kept.back() == n - 1);
  // In every bucket, the highest and lowest analytic MRR of its steps are among the kept ones
  // (no stock: nothing measured).
  for (std::size_t b = 0; b < kBuckets; ++b) {
    const std::size_t from = b * n / kBuckets, to = (b + 1) * n / kBuckets;
    double hi = -1.0, lo = 1e300, keptHi = -1.0, keptLo = 1e300;
    for (std::size_t i = from; i < to; ++i) {
      hi = std::max(hi, r.sim.steps[i].mrrExact);
      lo = std::min(lo, r.sim.steps[i].mrrExact);
    }
    for (std::size_t i : kept)
      if (i >= from && i < to) {
        keptHi = std::max(keptHi, r.sim.steps[i].mrrExact);
        keptLo = std::min(keptLo, r.sim.steps[i].mrrExact);
      }
    REQUIRE(keptHi == hi);
    REQUIRE(keptLo == lo);
  }
}
