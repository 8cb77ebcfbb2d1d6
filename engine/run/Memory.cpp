#include "engine/run/Memory.h"

#include "cutters/Error.h"

#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace engage {
namespace {

/// A `key:` line's number from a /proc file (kB there), bytes; negative if absent.
double procField(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string k;
  double kb = 0.0;
  while (in >> k) {
    if (k == key && in >> kb) return kb * 1024.0;
    in.ignore(1 << 16, '\n');
  }
  return -1.0;
}

/// A file's first number ("max" and unreadable: none, negative).
double fileNumber(const std::string& path) {
  std::string text;
  if (!(std::ifstream(path) >> text) || text == "max") return -1.0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end != text.c_str() && std::isfinite(v) ? v : -1.0;
}

}  // namespace

MemoryLimit processMemoryLimit() {
  const double held = std::max(0.0, procField("/proc/self/status", "VmRSS:"));
  MemoryLimit m;
  const double available = procField("/proc/meminfo", "MemAvailable:");
  m.bytes = available > 0.0 ? available + held : 8e9;
  m.source = "the memory available on this machine";
  // The cgroup's limit, less what the cgroup's other processes use (v2, then v1, whose "no
  // limit" is a huge number).
  for (const auto& [limitFile, usageFile] :
       {std::pair<const char*, const char*>{"/sys/fs/cgroup/memory.max",
                                            "/sys/fs/cgroup/memory.current"},
        {"/sys/fs/cgroup/memory/memory.limit_in_bytes",
         "/sys/fs/cgroup/memory/memory.usage_in_bytes"}}) {
    const double limit = fileNumber(limitFile), used = fileNumber(usageFile);
    if (limit <= 0.0 || limit > 1e17) continue;
    const double mine = std::max(0.0, limit - std::max(0.0, used - held));
    if (mine < m.bytes) {
      m.bytes = mine;
      m.source = "the cgroup's memory limit";
    }
    break;
  }
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    const double mapped = std::max(0.0, procField("/proc/self/status", "VmSize:"));
    const double room = 0.75 * std::max(0.0, static_cast<double>(as.rlim_cur) - mapped) + held;
    if (room < m.bytes) {
      m.bytes = room;
      m.source = "the address-space limit, ulimit -v";
    }
  }
  return m;
}

MemoryLimit memoryLimit(double maxMemory) {
  if (maxMemory > 0.0) return {maxMemory, "--max-memory"};
  return processMemoryLimit();
}

double parseMemory(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  std::string unit = text.substr(used);
  std::transform(unit.begin(), unit.end(), unit.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  static const std::pair<const char*, double> units[] = {{"", 1.0},
                                                         {"B", 1.0},
                                                         {"K", 1e3},
                                                         {"KB", 1e3},
                                                         {"KIB", 1024.0},
                                                         {"M", 1e6},
                                                         {"MB", 1e6},
                                                         {"MIB", 1048576.0},
                                                         {"G", 1e9},
                                                         {"GB", 1e9},
                                                         {"GIB", 1073741824.0},
                                                         {"T", 1e12},
                                                         {"TB", 1e12},
                                                         {"TIB", 1099511627776.0}};
  for (const auto& [name, factor] : units)
    if (used > 0 && unit == name && std::isfinite(v) && v > 0.0) return v * factor;
  throw ParameterError(option + ": expected an amount such as 8GB or 512MB, found '" + text + "'");
}

std::string memoryText(double bytes) {
  char buf[32];
  if (bytes >= 1e9)
    std::snprintf(buf, sizeof buf, "%.1f GB", bytes / 1e9);
  else
    std::snprintf(buf, sizeof buf, "%.0f MB", std::max(1.0, std::round(bytes / 1e6)));
  return buf;
}

}  // namespace engage
