#include "apps/Output.h"

#include "cutters/Error.h"

#include <fstream>
#include <sstream>

namespace engage::app {

void writeAtomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".part";
  {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw Error("cannot write '" + path.string() + "'");
    f << text;
    if (!f) throw Error("cannot write '" + path.string() + "'");
  }
  std::filesystem::rename(tmp, path);
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read '" + path.string() + "'");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace engage::app
