#include "engine/paths/DataDirectory.h"

#include "cutters/Error.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#ifndef ENGAGE_SOURCE_DATA_DIR
#define ENGAGE_SOURCE_DATA_DIR ""
#endif

namespace engage {
namespace {

namespace fs = std::filesystem;

/// The file of the program or shared object this function is linked into.
fs::path ownFile() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&ownFile), &info) != 0 && info.dli_fname) {
    const fs::path p(info.dli_fname);
    if (p.extension() == ".so") return fs::weakly_canonical(p);
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe;
}

bool holdsData(const fs::path& dir) {
  std::error_code ec;
  return !dir.empty() && fs::is_directory(dir / "materials", ec);
}

}  // namespace

std::string dataDirectory() {
  std::vector<fs::path> tried;
  if (const char* env = std::getenv("ENGAGE_DATA"); env && *env) {
    if (holdsData(env)) return env;
    tried.emplace_back(env);
  }
  const fs::path own = ownFile().parent_path();
  if (!own.empty())
    for (const char* up : {"..", "../../..", "../.."}) {
      const fs::path dir = (own / up / "share" / "engage" / "data").lexically_normal();
      if (holdsData(dir)) return dir.string();
      tried.push_back(dir);
    }
  const fs::path source(ENGAGE_SOURCE_DATA_DIR);
  if (holdsData(source)) return source.string();
  if (!source.empty()) tried.push_back(source);
  std::string list;
  for (const fs::path& p : tried)
    list += (list.empty() ? "" : ", ") + p.string();
  throw Error("cannot find engage's data folder (with materials/): looked in " + list +
              "; set ENGAGE_DATA to it");
}

}  // namespace engage
