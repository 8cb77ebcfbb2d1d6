#include "stock/AtomicFile.h"

#include "cutters/Error.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <vector>

namespace engage {
namespace {

// Never destroyed: a thread that ends the process (removeUnfinished, then std::_Exit) may
// run while the main thread's exit destroys static objects.
std::mutex& registryMutex() {
  static auto* m = new std::mutex;
  return *m;
}

std::vector<std::filesystem::path>& registry() {
  static auto* paths = new std::vector<std::filesystem::path>;
  return *paths;
}

}  // namespace

Unfinished::Unfinished(std::filesystem::path path) : path_(std::move(path)) {
  const std::lock_guard<std::mutex> lock(registryMutex());
  registry().push_back(path_);
}

Unfinished::~Unfinished() {
  // A path its owner could not remove (out of memory while unwinding: the removal allocates)
  // stays registered, for removeUnfinished once the run's memory is given back.
  std::error_code ec;
  if (registered_ && std::filesystem::exists(path_, ec)) return;
  release();
}

void Unfinished::release() {
  if (!registered_) return;
  registered_ = false;
  const std::lock_guard<std::mutex> lock(registryMutex());
  auto& paths = registry();
  const auto it = std::find(paths.rbegin(), paths.rend(), path_);
  if (it != paths.rend()) paths.erase(std::next(it).base());
}

void removeUnfinished() noexcept {
  const std::lock_guard<std::mutex> lock(registryMutex());
  for (const std::filesystem::path& p : registry()) {
    std::error_code ec;
    // A file may still be appearing in a folder being removed: a second pass takes it.
    for (int pass = 0; pass < 3 && std::filesystem::exists(p, ec); ++pass)
      std::filesystem::remove_all(p, ec);
  }
}

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".part";
  const Unfinished unfinished(tmp);
  std::ofstream os(tmp, std::ios::binary);
  const auto discard = [&] {
    os.close();
    std::remove(tmp.c_str());
  };
  const auto fail = [&](int error) {
    discard();
    throw Error("cannot write '" + path + "': " + std::strerror(error));
  };
  if (!os) fail(errno);
  try {
    write(os);
  } catch (...) {
    discard();
    throw;
  }
  os.flush();
  if (!os) fail(errno ? errno : EIO);
  os.close();
  if (!os) fail(errno ? errno : EIO);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(ec.value());
}

}  // namespace engage
