#include "stock/AtomicFile.h"

#include "cutters/Error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace engage {

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".part";
  std::ofstream os(tmp, std::ios::binary);
  const auto fail = [&](int error) {
    os.close();
    std::remove(tmp.c_str());
    throw Error("cannot write '" + path + "': " + std::strerror(error));
  };
  if (!os) fail(errno);
  write(os);
  os.flush();
  if (!os) fail(errno ? errno : EIO);
  os.close();
  if (!os) fail(errno ? errno : EIO);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(ec.value());
}

}  // namespace engage
