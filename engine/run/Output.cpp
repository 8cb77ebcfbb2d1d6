#include "engine/run/Output.h"

#include "cutters/Error.h"
#include "stock/AtomicFile.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace engage {

std::string csvQuoted(const std::string& text) {
  std::string out = "\"";
  for (char ch : text)
    out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return out + "\"";
}

void writeAtomically(const std::filesystem::path& path, const std::string& text) {
  writeFileAtomically(path.string(), [&](std::ostream& os) { os << text; });
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
  if (!created_.empty()) unfinished_ = std::make_unique<Unfinished>(created_);
}

void OutputDirectory::keep() {
  keep_ = true;
  if (unfinished_) unfinished_->release();
  unfinished_.reset();
}

OutputDirectory::~OutputDirectory() {
  std::error_code ec;
  if (!keep_ && !created_.empty()) std::filesystem::remove_all(created_, ec);
}

namespace {

namespace fs = std::filesystem;

/// The files engage writes into an output folder; removed before a new run's are moved in even
/// where no .engage-files lists them (a folder of an earlier version).
const char* const kOwnFiles[] = {
    "steps.csv",   "summary.json", "removed.vdb",      "stock.vdb",       "stock.stl",
    "plots.gp",    "mrr.png",      "mrr.svg",          "feed.png",        "feed.svg",
    "topview.png", "topview.svg",  "acceleration.png", "acceleration.svg"};

/// An exclusive lock on a folder, released on destruction (flock on the folder itself, so that
/// no lock file is left behind).
class FolderLock {
 public:
  explicit FolderLock(const fs::path& folder)
      : fd_(::open(folder.c_str(), O_RDONLY | O_DIRECTORY)) {
    if (fd_ < 0) throw Error("cannot lock '" + folder.string() + "': " + std::strerror(errno));
    while (::flock(fd_, LOCK_EX) != 0)
      if (errno != EINTR)
        throw Error("cannot lock '" + folder.string() + "': " + std::strerror(errno));
  }
  ~FolderLock() { ::close(fd_); }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_;
};

/// The prefix of this host's staging folders: ".engage-partial-HOST-" (a folder shared by
/// several hosts holds each one's; only this host's processes can be checked for life).
std::string stagingPrefix() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  std::string name(host);
  for (char& c : name)
    if (c == '/' || c == '-') c = '_';
  return ".engage-partial-" + name + "-";
}

/// Remove this host's staging folders whose process is gone (killed before publishing).
void removeDeadStagings(const fs::path& out) {
  std::error_code ec;
  const std::string prefix = stagingPrefix();
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)
      fs::remove_all(e.path(), ec);
  }
}

}  // namespace

StagedOutputs::StagedOutputs(const fs::path& out) : out_(out) {
  removeDeadStagings(out);
  staging_ = out / (stagingPrefix() + std::to_string(::getpid()));
  std::error_code ec;
  fs::remove_all(staging_, ec);
  unfinished_ = std::make_unique<Unfinished>(staging_);
  fs::create_directories(staging_, ec);
  if (ec) throw Error("cannot write to the output folder '" + out.string() + "': " + ec.message());
}

StagedOutputs::~StagedOutputs() {
  std::error_code ec;
  if (!published_) fs::remove_all(staging_, ec);
}

void StagedOutputs::publish() {
  const FolderLock lock(out_);
  std::error_code ec;
  auto fail = [&](const std::string& what) {
    throw Error("cannot move the outputs into '" + out_.string() + "': " + what);
  };
  // The earlier run's files go first, its summary.json before anything else.
  std::vector<std::string> old(std::begin(kOwnFiles), std::end(kOwnFiles));
  if (fs::exists(out_ / ".engage-files")) {
    std::istringstream listed(readFile(out_ / ".engage-files"));
    for (std::string name; std::getline(listed, name);)
      if (!name.empty() && name.find('/') == std::string::npos && name[0] != '.')
        old.push_back(name);
  }
  fs::remove(out_ / "summary.json", ec);
  for (const std::string& name : old)
    fs::remove(out_ / name, ec);
  // The new files, summary.json last.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(staging_, ec))
    if (!e.path().filename().string().empty()) names.push_back(e.path().filename().string());
  if (ec) fail(ec.message());
  std::sort(names.begin(), names.end());
  std::string list;
  for (const std::string& name : names) {
    list += name + "\n";
    if (name == "summary.json") continue;
    fs::rename(staging_ / name, out_ / name, ec);
    if (ec) fail(name + ": " + ec.message());
  }
  writeAtomically(out_ / ".engage-files", list);
  if (fs::exists(staging_ / "summary.json")) {
    fs::rename(staging_ / "summary.json", out_ / "summary.json", ec);
    if (ec) fail("summary.json: " + ec.message());
  }
  fs::remove_all(staging_, ec);
  published_ = true;
  unfinished_.reset();
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read '" + path.string() + "'");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace engage
