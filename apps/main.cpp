/// \file main.cpp
/// The `engage` command line: one executable, subcommands. Library errors are caught here,
/// printed as one line on stderr, and turned into a non-zero exit status:
/// 0 success, 1 invalid input (a parameter, a unit, a file), 2 command-line usage,
/// 3 internal error, 4 a batch ran but some of its jobs failed (their records hold the errors),
/// 5 a simulate, schedule or batch run completed but a rapid, a shank or a holder met material,
/// 6 a schedule's limit cannot be met, 7 a simulate, schedule or batch run completed but gouged
/// its --part deeper than --tolerance (5 where both),
/// 8 out of memory (what was being written is removed; earlier outputs stay),
/// 130 interrupted (SIGINT or SIGTERM: the run stops at its next step and removes what it made,
/// as a failed run does; a stage that does not stop by itself within 0.3 s, such as
/// OpenVDB's meshing, is ended there with what it was writing removed; a second signal ends
/// the process at once).

#include "apps/AnalyzeCommand.h"
#include "apps/BatchCommand.h"
#include "apps/MovesCommand.h"
#include "apps/PaperCommand.h"
#include "apps/PocketCommand.h"
#include "apps/SimulateCommand.h"
#include "cutters/Error.h"
#include "engine/paths/DataDirectory.h"
#include "engine/schedule/FeedScheduler.h"
#include "engine/sim/Simulation.h"

#include "stock/AtomicFile.h"

#include <CLI/CLI.hpp>

#include <link.h>
#include <semaphore.h>
#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iostream>
#include <new>
#include <string>
#include <thread>

namespace {

/// Posted by the first stop signal, for the thread that ends a run that does not stop.
sem_t stopPosted;

/// The first SIGINT or SIGTERM asks the run to stop; the next one ends the process.
extern "C" void onStopSignal(int sig) {
  engage::requestStop();
  sem_post(&stopPosted);
  std::signal(sig, SIG_DFL);
}

/// Writes `text` to stderr without allocating (for the ends below, where memory may be gone).
void say(const char* text) {
  std::size_t n = 0;
  while (text[n] != '\0')
    ++n;
  while (n > 0) {
    const ssize_t w = ::write(2, text, n);
    if (w <= 0) return;
    text += w;
    n -= static_cast<std::size_t>(w);
  }
}

constexpr const char* kInterrupted =
    "engage: interrupted: the run stopped and removed what it had made\n";
constexpr const char* kOutOfMemory =
    "engage: out of memory: the run needed more than this process may use (what it was "
    "writing is removed); use a coarser --voxel, --outputs summary, or more memory "
    "(--max-memory, the job's memory limit)\n";

/// How long a run has after a stop signal to stop by itself: every step and every output
/// checks for it, but a stage inside a library that cannot be asked to stop (OpenVDB's
/// meshing of a large stock takes tens of seconds) is ended then, by this thread: what is
/// being written is removed (removeUnfinished) and the process exits 130 at once.
constexpr auto kStopGrace = std::chrono::milliseconds(300);

void endUnstoppedRun() {
  while (sem_wait(&stopPosted) != 0) {
  }
  std::this_thread::sleep_for(kStopGrace);
  engage::removeUnfinished();
  say(kInterrupted);
  std::_Exit(130);
}

/// Address space held back for the end of a run out of memory: given back at the first failed
/// allocation (which is then tried again), so that the run can unwind, remove what it was
/// writing and say why; the next failure throws std::bad_alloc.
char* memoryReserve = nullptr;
/// And a little more for removing what was being written (removeUnfinished allocates as it
/// walks a folder), given back just before that.
char* cleanupReserve = nullptr;

void removeUnfinishedWithReserve() {
  delete[] cleanupReserve;
  cleanupReserve = nullptr;
  engage::removeUnfinished();
}

void onAllocationFailure() {
  if (memoryReserve) {
    delete[] memoryReserve;
    memoryReserve = nullptr;
    return;
  }
  std::set_new_handler(nullptr);  // the next failure throws
}

/// An exception that could not be thrown on (out of memory in a destructor or a thread
/// without a catch): what was being written is removed; out of memory exits 8, anything else
/// aborts as before.
[[noreturn]] void onTerminate() {
  removeUnfinishedWithReserve();
  if (const std::exception_ptr e = std::current_exception()) {
    try {
      std::rethrow_exception(e);
    } catch (const std::bad_alloc&) {
      say(kOutOfMemory);
      std::_Exit(8);
    } catch (...) {
    }
  }
  say("engage: internal error: the process ended unexpectedly\n");
  std::abort();
}

/// Gives back the pages of a shared library's first read-only segment (its ELF header, symbol
/// names, hash table and relocations), which the dynamic loader read while it relocated the
/// library before main. OpenVDB's symbol names alone are 22 MB, and relocating its 52,000
/// symbol references touches nearly all of them: 26 MB of the process's 35 MB at start, held
/// through the run otherwise. The pages are clean copies of
/// the file, never written (the segment is mapped read-only), so a later lookup (a lazily
/// bound call) reads its page again from the page cache.
int releaseLoaderTables(dl_phdr_info* info, size_t, void*) {
  if (!info->dlpi_name || info->dlpi_name[0] != '/') return 0;  // the program, the vDSO
  // A library with text relocations had read-only pages written by the loader: left alone.
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    if (info->dlpi_phdr[i].p_type != PT_DYNAMIC) continue;
    for (const auto* d =
             reinterpret_cast<const ElfW(Dyn)*>(info->dlpi_addr + info->dlpi_phdr[i].p_vaddr);
         d->d_tag != DT_NULL; ++d)
      if (d->d_tag == DT_TEXTREL || (d->d_tag == DT_FLAGS && (d->d_un.d_val & DF_TEXTREL)))
        return 0;
  }
  const auto page = static_cast<ElfW(Addr)>(sysconf(_SC_PAGESIZE));
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    if (ph.p_type != PT_LOAD || ph.p_flags != PF_R || ph.p_offset != 0) continue;
    const ElfW(Addr) begin = info->dlpi_addr + ph.p_vaddr;
    const ElfW(Addr) end = (begin + ph.p_memsz) / page * page;  // whole pages only
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_DONTNEED);
  }
  return 0;
}

/// CLI11's message of a usage error in plain words where its own are terse: an option given
/// more often than once ("--stock: At Most 1 required but received 2").
std::string usageMessage(const CLI::ParseError& e) {
  const std::string m = e.what();
  const std::string atMost = ": At Most 1 required but received ";
  const std::size_t at = m.find(atMost);
  if (at != std::string::npos)
    return m.substr(0, at) + " is given " + m.substr(at + atMost.size()) + " times: give it once";
  return m;
}

/// `engage --version`: the version and the data folder this engage uses (DataDirectory.h).
std::string versionText() {
  std::string data;
  try {
    data = engage::dataDirectory();
  } catch (const engage::Error&) {
    data = "none found: set ENGAGE_DATA";
  }
  return "engage 0.1.0 (data: " + data + ")";
}

/// The exit statuses, shown at the end of every command's help.
constexpr const char* kExitStatuses =
    "Exit status: 0 success; 1 invalid input (one line on stderr, nothing written); 2 usage; "
    "3 internal error; 4 a batch ran but some of its jobs failed; 5 the run completed but a "
    "rapid, a shank or a holder met material; 6 a schedule's limit cannot be met at the lowest "
    "feed (nothing written); 7 the run completed but gouged its --part deeper than --tolerance "
    "(5 where both); 8 out of memory; 130 interrupted.\n";

}  // namespace

int main(int argc, char** argv) {
  dl_iterate_phdr(releaseLoaderTables, nullptr);
  CLI::App app{
      "engage: material-engagement simulator and adaptive feedrate scheduler for CNC "
      "milling"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::function<std::string()>(versionText));
  std::function<int()> run;
  engage::app::addAnalyzeCommand(app, run);
  engage::app::addMovesCommand(app, run);
  engage::app::addSimulateCommand(app, run);
  engage::app::addPocketCommand(app, run);
  engage::app::addPaperCommand(app, run);
  engage::app::addBatchCommands(app, run);
  app.footer(kExitStatuses);
  for (CLI::App* sub : app.get_subcommands({}))
    sub->footer(kExitStatuses);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version print and exit 0; every other usage error is one line and exit 2.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << "engage: usage: " << usageMessage(e) << " (see engage"
              << (argc > 1 && argv[1][0] != '-' ? std::string(" ") + argv[1] : std::string())
              << " --help)\n";
    return 2;
  }
  memoryReserve = new char[64 << 20];
  cleanupReserve = new char[8 << 20];
  std::set_new_handler(onAllocationFailure);
  std::set_terminate(onTerminate);
  sem_init(&stopPosted, 0, 0);
  std::thread(endUnstoppedRun).detach();
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
  try {
    return run ? run() : 2;
  } catch (const engage::Interrupted&) {
    say(kInterrupted);
    return 130;
  } catch (const std::bad_alloc&) {
    removeUnfinishedWithReserve();  // (what unwinding could not remove without memory)
    say(kOutOfMemory);
    return 8;
  } catch (const engage::UnmetLimitError& e) {
    std::cerr << "engage: error: " << e.what() << '\n';
    return 6;
  } catch (const engage::Error& e) {
    std::cerr << "engage: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "engage: internal error: " << e.what() << '\n';
    return 3;
  }
}
