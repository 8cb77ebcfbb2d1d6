// Tests of engine/report/Plots.h: the pictures gnuplot draws, each from the table it is given.

#include "engine/report/Plots.h"

#include "cutters/Error.h"

#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

using namespace engage;

namespace {

void write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

}  // namespace

TEST_CASE("a long run's plots: the curves from one table, the top view from another", "[report]") {
  // Each shorter table lacks the other plot's columns: a plot that read the wrong table would
  // make gnuplot fail, and writePlots throw.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("engage_plots_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  write(dir / "steps.csv",
        "arc_length_mm,mrr_mm3_min,mrr_exact_mm3_min,mrr_paper_mm3_min,kind,x_mm,y_mm\n"
        "0,0,0,0,feed,0,0\n1,10,11,12,feed,1,0\n2,20,21,22,feed,2,1\n");
  write(dir / "lines.csv",
        "arc_length_mm,mrr_mm3_min,mrr_exact_mm3_min,mrr_paper_mm3_min\n0,0,0,0\n2,20,21,22\n");
  write(dir / "top.csv", "kind,x_mm,y_mm,mrr_mm3_min\nfeed,1,0,10\nfeed,2,1,20\n");
  PlotSpec p;
  p.folder = dir.string();
  p.length = "mm";
  p.rate = "mm3_min";
  p.lengthLabel = "mm";
  p.rateLabel = "mm^3/min";
  p.data = "lines.csv";
  p.topData = "top.csv";
  const std::vector<std::string> files = writePlots(p);
  // The script, and mrr and topview as PNG and SVG.
  CHECK(files.size() == 5);
  for (const char* f : {"plots.gp", "mrr.png", "mrr.svg", "topview.png", "topview.svg"})
    CHECK(std::find(files.begin(), files.end(), f) != files.end());
  // The pictures are kPlotWidth x kPlotWidth / 2 (the PNG header's width and height,
  // big-endian at bytes 16 and 20).
  for (const char* f : {"mrr.png", "topview.png"}) {
    std::ifstream png(dir / f, std::ios::binary);
    unsigned char head[24] = {};
    png.read(reinterpret_cast<char*>(head), sizeof head);
    auto word = [&](int at) {
      return (std::size_t(head[at]) << 24) | (std::size_t(head[at + 1]) << 16) |
             (std::size_t(head[at + 2]) << 8) | std::size_t(head[at + 3]);
    };
    INFO(f);
    CHECK(word(16) == kPlotWidth);
    CHECK(word(20) == kPlotWidth / 2);
  }
  // The MRR plot names its axes with their units and its three curves, and its MRR axis
  // reaches the table's largest value (22: the paper form at 2 mm).
  std::ifstream svgIn(dir / "mrr.svg");
  const std::string svg((std::istreambuf_iterator<char>(svgIn)), std::istreambuf_iterator<char>());
  for (const char* text : {"arc length (mm)", "MRR (mm", "analytic, exact", "analytic, paper"}) {
    INFO(text);
    CHECK(svg.find(text) != std::string::npos);
  }
  double largestTick = 0.0;
  for (std::size_t at = svg.find("font-family=\"sans\" > "); at != std::string::npos;
       at = svg.find("font-family=\"sans\" > ", at + 1)) {
    const std::size_t from = at + std::string("font-family=\"sans\" > ").size();
    char* end = nullptr;
    const double v = std::strtod(svg.c_str() + from, &end);
    if (end != svg.c_str() + from && *end == '<') largestTick = std::max(largestTick, v);
  }
  CHECK(largestTick >= 22.0);
  CHECK(largestTick <= 30.0);
  // By hand (`gnuplot plots.gp`), both read steps.csv.
  std::ifstream in(dir / "plots.gp");
  const std::string script((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK(script.find("if (!exists(\"data\")) data = 'steps.csv'") != std::string::npos);
  CHECK(script.find("if (!exists(\"top\")) top = data") != std::string::npos);
  // Swapped, both plots read a table without their columns.
  std::swap(p.data, p.topData);
  CHECK_THROWS_AS(writePlots(p), Error);
  std::filesystem::remove_all(dir);
}
