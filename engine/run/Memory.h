#pragma once
/// \file Memory.h
/// The memory a run may use: the least of what this machine has available, its cgroup's
/// limit and the process's address-space limit, or `--max-memory`. The run's estimate
/// (memoryEstimate, Pipeline.h) is checked against it before any work.

#include <string>

namespace engage {

/// The bytes a process may use and where that bound comes from, for the messages.
struct MemoryLimit {
  double bytes = 0.0;
  std::string source;  ///< "--max-memory", "the memory available on this machine", ...
};

/// What this process may still use: the machine's available memory (MemAvailable) and what
/// this process already holds, bounded by the cgroup's limit (v2 memory.max, v1
/// memory.limit_in_bytes; the cgroup's other use taken off) and by the address-space limit
/// (RLIMIT_AS, ulimit -v; the address space already mapped taken off, and a quarter kept for
/// the threads' stacks and heaps, which reserve address space they may not use).
MemoryLimit processMemoryLimit();

/// `--max-memory BYTES` where it is given (> 0), else processMemoryLimit().
MemoryLimit memoryLimit(double maxMemory);

/// "8GB", "512MB", "2GiB", "1.5G", "4000000000" as bytes; `option` names the option in the
/// error. Throws ParameterError.
double parseMemory(const std::string& text, const std::string& option);

/// Bytes as "1.2 GB" or "350 MB".
std::string memoryText(double bytes);

}  // namespace engage
