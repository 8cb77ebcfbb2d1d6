// libFuzzer targets for the readers of inputs other than G-code: any input must either read
// or throw engage::Error with a message; never crash, hang or leak. One source, four targets
// (ENGAGE_FUZZ_TARGET): units (the quantity parser), manifest (the batch manifest reader),
// mesh (the stock mesh reader: binary and ASCII STL, OBJ, OFF, PLY by the first byte), tools
// (the tool library reader, every format, and the cutter of every tool number it lists).
//
//   cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DENGAGE_FUZZ=ON -DENGAGE_TESTS=OFF
//   cmake --build build-fuzz --target fuzz_units fuzz_manifest fuzz_mesh fuzz_tools
//   build-fuzz/tests/fuzz/fuzz_manifest -max_total_time=600 corpus-manifest data/batch
//   (seeds: data/batch for manifests, data/stock and tests/data for meshes, data/tools and
//   data/gcode/linuxcnc for tools, none for units)

#include "cutters/Error.h"
#include "engine/run/Manifest.h"
#include "engine/tools/ToolLibrary.h"
#include "engine/units/Quantity.h"
#include "stock/TriangleMesh.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

namespace {

/// The input in a file of its own (the readers take paths), named with `ext`.
std::string toFile(const std::string& bytes, const char* ext) {
  const std::string path = "/tmp/engage-fuzz-" + std::to_string(::getpid()) + ext;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
#if ENGAGE_FUZZ_TARGET == 1
    for (int d = 0; d <= static_cast<int>(engage::Dimension::Time); ++d)
      (void)engage::parseQuantity(bytes, static_cast<engage::Dimension>(d),
                                  engage::UnitSystem::Metric, "--fuzz");
#elif ENGAGE_FUZZ_TARGET == 2
    (void)engage::readManifest(toFile(bytes, ".json"));
#elif ENGAGE_FUZZ_TARGET == 4
    engage::ToolLibraryOptions inch;
    inch.linuxcncInch = size > 0 && data[0] % 2 == 1;
    const engage::ToolLibrary lib = engage::parseToolLibrary(bytes, "/tmp/fuzz.tbl", inch);
    for (const engage::ToolEntry& e : lib.tools) {
      try {
        (void)lib.require(e.number).cutter->radius();
      } catch (const engage::Error&) {
        // Expected for a tool that cannot be built.
      }
    }
#else
    static const char* const kExt[] = {".stl", ".obj", ".off", ".ply"};
    const char* ext = kExt[size > 0 ? data[0] % 4 : 0];
    (void)engage::readMesh(toFile(size > 0 ? bytes.substr(1) : bytes, ext));
#endif
  } catch (const engage::Error&) {
    // Expected for invalid input.
  }
  return 0;
}
