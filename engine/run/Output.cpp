#include "engine/run/Output.h"

#include "cutters/Error.h"

#include <fstream>
#include <sstream>

namespace engage {

void writeAtomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".part";
  {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw Error("cannot write '" + path.string() + "'");
    f << text;
    if (!f) throw Error("cannot write '" + path.string() + "'");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw Error("cannot write '" + path.string() + "'");
  }
}

OutputDirectory::OutputDirectory(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // The topmost missing folder: the one to remove if the run fails.
  for (fs::path p = fs::absolute(dir, ec); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created_ = p;
    if (p == p.parent_path()) break;
  }
  auto fail = [&](const std::string& why) {
    if (!created_.empty()) fs::remove_all(created_, ec);
    throw Error("cannot write to the output folder '" + dir.string() + "': " + why);
  };
  fs::create_directories(dir, ec);
  if (ec) fail(ec.message());
  if (!fs::is_directory(dir, ec)) fail("not a folder");
  const fs::path probe = dir / ".engage-write-test";
  {
    std::ofstream f(probe, std::ios::binary);
    if (!(f << 'x') || !f.flush()) fail("a file cannot be written there");
  }
  fs::remove(probe, ec);
}

OutputDirectory::~OutputDirectory() {
  std::error_code ec;
  if (!keep_ && !created_.empty()) std::filesystem::remove_all(created_, ec);
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read '" + path.string() + "'");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace engage
