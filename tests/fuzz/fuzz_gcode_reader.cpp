// libFuzzer target for the G-code reader: any input must either interpret or throw
// engage::Error (a GcodeError with file:line:col); never crash, hang or leak.
//
//   cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DENGAGE_FUZZ=ON -DENGAGE_TESTS=OFF
//   cmake --build build-fuzz --target fuzz_gcode_reader
//   mkdir -p build-fuzz/corpus && build-fuzz/tests/fuzz/fuzz_gcode_reader -max_total_time=600 \
//       -max_len=4096 build-fuzz/corpus data/gcode/dialects data/gcode/compensation

#include "engine/gcode/GcodeReader.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  engage::ReaderOptions options;
  options.maxExecutedLines = 20000;  // loops in fuzzed programs end quickly
  options.maxMoves = 200000;         // and lathe cycles in them stay small
  // The last byte picks the dialect (LinuxCNC, Fanuc, Haas, grbl): all four paths are fuzzed.
  if (size > 0) options.dialect = static_cast<engage::Dialect>(data[size - 1] % 4);
  try {
    (void)engage::readProgramText(text, "fuzz.ngc", options);
  } catch (const engage::Error&) {
    // Expected for invalid programs.
  }
  return 0;
}
