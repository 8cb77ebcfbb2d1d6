// Benchmark (not a test): time to read a 100,000-line program of lines and arcs.
// Prints one JSON object: {"lines":..., "moves":..., "seconds_min":..., "seconds_median":...,
// "lines_per_second":...}. Run: build/tests/bench/bench_gcode_reader [lines]

#include "engine/gcode/GcodeReader.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const int lines = argc > 1 ? std::atoi(argv[1]) : 100000;
  // A spiral-ish finishing pass: 6 lines for every arc, Z stepping, feeds changing.
  std::string text = "G21 G90 G17\nG0 X10 Y0 Z5\nS12000 M3\nG1 Z-1 F300\n";
  double angle = 0.0;
  char buf[160];
  for (int i = 4; i < lines - 1; ++i) {
    if (i % 7 == 0) {
      const double next = angle + 0.05;
      std::snprintf(buf, sizeof buf, "G3 X%.6f Y%.6f I%.6f J%.6f F%d\n", 10 * std::cos(next),
                    10 * std::sin(next), -10 * std::cos(angle), -10 * std::sin(angle),
                    1000 + i % 50);
      angle = next;
    } else {
      angle += 0.01;
      std::snprintf(buf, sizeof buf, "G1 X%.6f Y%.6f Z%.4f\n", 10 * std::cos(angle),
                    10 * std::sin(angle), -1 - 0.0001 * (i % 100));
    }
    text += buf;
  }
  text += "M2\n";
  std::vector<double> seconds;
  std::size_t moves = 0;
  for (int run = 0; run < 5; ++run) {
    const auto t0 = std::chrono::steady_clock::now();
    const engage::Toolpath path = engage::readProgramText(text, "bench.ngc");
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    moves = path.moves.size();
  }
  std::sort(seconds.begin(), seconds.end());
  std::printf(
      "{\"lines\": %d, \"moves\": %zu, \"seconds_min\": %.4f, \"seconds_median\": %.4f, "
      "\"lines_per_second\": %.0f}\n",
      lines, moves, seconds.front(), seconds[2], lines / seconds[2]);
  return 0;
}
