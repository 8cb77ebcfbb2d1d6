// Tests of engine/run/Memory.h: the amounts of --max-memory and the limit a process has.

#include "engine/run/Memory.h"

#include "cutters/Error.h"

#include <catch2/catch.hpp>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <string>

using namespace engage;

TEST_CASE("memory amounts are read with their units", "[run]") {
  // Decimal and binary prefixes, by their definitions.
  CHECK(parseMemory("8GB", "--max-memory") == 8e9);
  CHECK(parseMemory("512MB", "--max-memory") == 512e6);
  CHECK(parseMemory("2GiB", "--max-memory") == 2.0 * 1024 * 1024 * 1024);
  CHECK(parseMemory("1.5g", "--max-memory") == 1.5e9);
  CHECK(parseMemory("4000000000", "--max-memory") == 4e9);
  for (const char* bad : {"", "GB", "-1GB", "0", "8 furlongs", "nanGB"}) {
    INFO(bad);
    CHECK_THROWS_AS(parseMemory(bad, "--max-memory"), ParameterError);
  }
  try {
    parseMemory("12furlongs", "--max-memory");
  } catch (const ParameterError& e) {
    CHECK(std::string(e.what()) ==
          "--max-memory: expected an amount such as 8GB or 512MB, found '12furlongs'");
  }
  CHECK(memoryText(5.5e9) == "5.5 GB");
  CHECK(memoryText(17.2e6) == "17 MB");
  CHECK(memoryText(10.0) == "1 MB");
}

TEST_CASE("a run may use --max-memory where given, else what the process may use", "[run]") {
  const MemoryLimit given = memoryLimit(3e9);
  CHECK(given.bytes == 3e9);
  CHECK(given.source == "--max-memory");
  // Without it: at most the machine's memory (MemTotal), and more than nothing.
  double total = 0.0;
  {
    std::ifstream in("/proc/meminfo");
    std::string key;
    double kb = 0.0;
    while (in >> key >> kb)
      if (key == "MemTotal:") total = kb * 1024.0;
  }
  const MemoryLimit own = memoryLimit(0.0);
  CHECK(own.bytes > 0.0);
  CHECK(own.bytes <= total * 1.01);  // (plus what the process holds, counted in both)
}

TEST_CASE("an address-space limit bounds what the process may use", "[run]") {
  // In a child (the limit must not bind the test process): ulimit -v of what is mapped now
  // plus 1 GB leaves three quarters of 1 GB for the run, plus what it holds.
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    double mapped = 0.0, held = 0.0;
    std::ifstream in("/proc/self/status");
    std::string key;
    while (in >> key) {
      double kb = 0.0;
      if ((key == "VmSize:" || key == "VmRSS:") && in >> kb)
        (key == "VmSize:" ? mapped : held) = kb * 1024.0;
      in.ignore(1 << 16, '\n');
    }
    const rlimit as{static_cast<rlim_t>(mapped + 1e9), static_cast<rlim_t>(mapped + 1e9)};
    if (setrlimit(RLIMIT_AS, &as) != 0) _exit(2);
    const MemoryLimit m = processMemoryLimit();
    // (The few kB the child maps meanwhile are within the tolerance of 1 %.)
    const bool bound = m.bytes <= 0.75e9 + held + 1e7 && m.bytes >= 0.74e9;
    const bool named = m.source == "the address-space limit, ulimit -v";
    _exit(bound && named ? 0 : 1);
  }
  int status = 0;
  waitpid(child, &status, 0);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}
