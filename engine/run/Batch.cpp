#include "engine/run/Batch.h"

#include "engine/report/HtmlPage.h"

#include "cutters/Error.h"
#include "engine/run/Job.h"
#include "engine/run/Manifest.h"
#include "engine/run/Memory.h"
#include "engine/run/Output.h"
#include "engine/run/Pipeline.h"
#include "engine/run/RunOutputs.h"
#include "engine/run/Summary.h"

#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sched.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace engage {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::ordered_json;

/// The memory a batch's jobs may hold at once: each job reserves its estimate
/// (memoryEstimate, Pipeline.h) before it runs and waits while the running ones' reservations
/// and its own would exceed the budget, so that workers are fewer where jobs are large. A job
/// runs when nothing else does, whatever its estimate (its stock's own check refuses what
/// cannot fit at all).
class MemoryBudget {
 public:
  explicit MemoryBudget(double bytes) : total_(bytes) {}
  /// A reservation, released when it goes.
  class Ticket {
   public:
    Ticket(MemoryBudget& budget, double bytes, const std::string& job)
        : budget_(budget), bytes_(bytes) {
      std::unique_lock<std::mutex> lock(budget_.mutex_);
      bool said = false;
      while (budget_.running_ > 0 && budget_.used_ + bytes_ > budget_.total_) {
        if (!said)  // in the log too (--quiet): it tells why the batch runs fewer jobs at once
          std::fprintf(stderr,
                       "batch: job %s needs about %.2f GB; waiting for running jobs to free "
                       "memory (%.2f GB for the batch)\n",
                       job.c_str(), bytes_ / 1e9, budget_.total_ / 1e9);
        said = true;
        budget_.freed_.wait(lock);
      }
      budget_.used_ += bytes_;
      ++budget_.running_;
    }
    ~Ticket() {
      {
        std::lock_guard<std::mutex> lock(budget_.mutex_);
        budget_.used_ -= bytes_;
        --budget_.running_;
      }
      budget_.freed_.notify_all();
    }
    Ticket(const Ticket&) = delete;
    Ticket& operator=(const Ticket&) = delete;

   private:
    MemoryBudget& budget_;
    double bytes_;
  };

 private:
  std::mutex mutex_;
  std::condition_variable freed_;
  double total_, used_ = 0.0;
  int running_ = 0;
};

/// Run one job into DIR/jobs/NAME (through NAME.partial, renamed when complete) and return
/// its record. A job's failure is its record; it never stops the batch. `blocked` non-empty:
/// the job cannot run (its stock's job failed), and that is its record.
ordered_json runOne(const ManifestJob& job, const fs::path& jobs, const std::string& outputs,
                    MemoryBudget& memory, const std::string& blocked) {
  const fs::path partial = jobs / (job.name + ".partial"), done = jobs / job.name;
  fs::remove_all(partial);
  Unfinished unfinished(partial);
  fs::create_directories(partial);
  const ordered_json spec = ordered_json::parse(job.specJson);
  ordered_json r;
  r["name"] = job.name;
  r["index"] = job.index;
  r["program"] = spec["program"];
  r["command"] = spec["command"];
  const auto start = std::chrono::steady_clock::now();
  try {
    OptionValues values = job.values;
    values["out"] = partial.string();
    values["quiet"] = "true";
    if (!outputs.empty() && !values.count("outputs")) values["outputs"] = outputs;
    if (!blocked.empty()) throw Error(blocked);
    if (!job.stockFrom.empty()) values["stock"] = (jobs / job.stockFrom / "stock.vdb").string();
    Job made = makeJob(job.command, values);
    made.keepStock = job.feedsStock;
    const MemoryBudget::Ticket reserved(memory, memoryEstimate(made).total(), job.name);
    const CompletedRun run = runIntoFolder(std::move(made));
    const RunResult& out = run.result;
    const WrittenOutputs& written = run.written;
    const SimulationResult& sim = out.sim;
    // The run's peak (RunResult::peakStep: the first step at it), as summary.json has it.
    const bool cut = !sim.steps.empty() && sim.steps[out.peakStep].mrr > 0.0;
    const double peak = cut ? sim.steps[out.peakStep].mrr : 0.0;
    const int peakLine = cut ? sim.steps[out.peakStep].line : 0;
    // "collision": the job ran and wrote its files, but a rapid, a shank or a holder met
    // material (the status a run alone exits 5 with); "gouge": it gouged its --part (7).
    r["status"] = !sim.collisions.empty() ? "collision" : out.part.gouges.empty() ? "ok" : "gouge";
    r["error"] = nullptr;
    r["moves"] = out.job.path.moves.size();
    r["steps"] = sim.steps.size();
    r["removed_mm3"] = sim.removed;
    r["peak_mrr_mm3_min"] = peak;
    r["peak_mrr_line"] = peakLine;
    r["cutting_time_s"] = sim.cuttingTime;
    r["collisions"] = sim.collisions.size();
    if (out.part.done) r["gouges"] = out.part.gouges.size();
    const bool scheduled = out.job.scheduling();
    r["feed_time_before_s"] = scheduled ? ordered_json(out.plan.timeBefore) : ordered_json();
    r["feed_time_after_s"] = scheduled ? ordered_json(out.plan.timeAfter) : ordered_json();
    r["saving_relative"] = scheduled && out.plan.timeBefore > 0
                               ? ordered_json(1.0 - out.plan.timeAfter / out.plan.timeBefore)
                               : ordered_json();
    r["warnings"] = runWarnings(out, written);
  } catch (const Interrupted&) {
    // Not the job's failure: no record, so that the next run does it again.
    fs::remove_all(partial);
    throw;
  } catch (const std::exception& e) {
    r["status"] = "failed";
    r["error"] = dynamic_cast<const std::bad_alloc*>(&e)
                     ? "out of memory: the job needed more than the process could give it"
                     : e.what();
    for (const char* key :
         {"moves", "steps", "removed_mm3", "peak_mrr_mm3_min", "peak_mrr_line", "cutting_time_s",
          "collisions", "feed_time_before_s", "feed_time_after_s", "saving_relative"})
      r[key] = nullptr;
    r["warnings"] = ordered_json::array();
    // A failed job keeps nothing but its record.
    fs::remove_all(partial);
    fs::create_directories(partial);
  }
  r["run_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r["spec"] = spec;
  writeAtomically(partial / "job.json", r.dump(2) + "\n");
  fs::remove_all(done);
  fs::rename(partial, done);
  unfinished.release();
  return r;
}

/// This process as a lock's owner: "host pid".
std::string lockOwner() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) std::snprintf(host, sizeof host, "unknown");
  return std::string(host) + " " + std::to_string(::getpid());
}

/// An exclusive, non-blocking lock on a job, taken while the job runs, so that two processes
/// never run one job. flock on a lock file beside the job's folder, which then names its
/// owner ("host pid", so that the one that skips the job can say who runs it); flock works on
/// local file systems and on NFS with a lock manager, and the kernel releases it when the
/// process dies. Where the file system refuses flock (ENOLCK, EOPNOTSUPP: NFS without a lock
/// manager) or ENGAGE_LOCK_FILES=1 asks for it: an owner file created exclusively
/// (LOCKFILE.owner, O_EXCL), removed when the job ends; one left by a process of this host that
/// is gone (killed) is stale and taken over. (A dead owner on another host cannot be told from
/// a live one: its file stays until removed by hand, and the log names it.)
class JobLock {
 public:
  explicit JobLock(const fs::path& file) : file_(file) {
    const char* forced = std::getenv("ENGAGE_LOCK_FILES");
    const bool ownerFiles = forced && std::string(forced) == "1";
    if (!ownerFiles) {
      fd_ = ::open(file.c_str(), O_CREAT | O_RDWR, 0644);
      if (fd_ < 0) return;
      if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) {
        held_ = true;
        const std::string me = lockOwner() + "\n";
        if (::ftruncate(fd_, 0) == 0 && ::pwrite(fd_, me.data(), me.size(), 0) < 0) {
        }  // (the owner's name is for messages only)
        return;
      }
      if (errno != ENOLCK && errno != EOPNOTSUPP && errno != ENOSYS) {
        owner_ = readOwner(file);
        return;
      }
      ::close(fd_);
      fd_ = -1;
    }
    takeOwnerFile();
  }
  ~JobLock() {
    if (fd_ >= 0) ::close(fd_);
    if (ownerFile_) ::unlink((file_.string() + ".owner").c_str());
  }
  JobLock(const JobLock&) = delete;
  JobLock& operator=(const JobLock&) = delete;
  bool acquired() const { return held_; }
  /// Who holds the lock when this one did not get it ("host pid"; "" when unknown).
  const std::string& owner() const { return owner_; }
  /// What this one did about a stale owner file ("" when nothing).
  const std::string& note() const { return note_; }

 private:
  static std::string readOwner(const fs::path& file) {
    std::ifstream in(file);
    std::string host, pid;
    in >> host >> pid;
    return host.empty() ? std::string() : host + " " + pid;
  }
  void takeOwnerFile() {
    const std::string path = file_.string() + ".owner";
    for (int attempt = 0; attempt < 2; ++attempt) {
      const int fd = ::open(path.c_str(), O_CREAT | O_EXCL | O_WRONLY, 0644);
      if (fd >= 0) {
        const std::string me = lockOwner() + "\n";
        const bool written = ::write(fd, me.data(), me.size()) == static_cast<ssize_t>(me.size());
        ::close(fd);
        held_ = ownerFile_ = written;
        return;
      }
      owner_ = readOwner(path);
      // Stale: its owner ran on this host and is gone.
      std::istringstream parts(owner_);
      std::string host;
      long pid = 0;
      parts >> host >> pid;
      std::istringstream mine(lockOwner());
      std::string myHost;
      mine >> myHost;
      if (host != myHost || pid <= 0 || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)
        return;
      note_ = "a stale lock of process " + owner_ + " (gone) taken over";
      ::unlink(path.c_str());
    }
  }

  fs::path file_;
  int fd_ = -1;
  bool held_ = false;
  bool ownerFile_ = false;
  std::string owner_, note_;
};

/// Whether a job's record is of a run that went to its end and wrote its files ("ok", or
/// "collision": its tool met material; "gouge": it gouged its --part), not a failed one.
bool ranToEnd(const ordered_json& record) {
  return record["status"] == "ok" || record["status"] == "collision" || record["status"] == "gouge";
}

/// The record of a finished job, or null when it has not run with these options.
ordered_json recordOf(const ManifestJob& job, const fs::path& jobs) {
  const fs::path file = jobs / job.name / "job.json";
  if (!fs::exists(file)) return nullptr;
  try {
    ordered_json r = ordered_json::parse(readFile(file));
    if (json(r["spec"]) != json::parse(job.specJson)) return nullptr;  // the manifest changed
    return r;
  } catch (const std::exception&) {
    return nullptr;  // unreadable: run it again
  }
}

/// Wait until `source`, whose final stock a job takes, has finished: in this process (it is in
/// `pending` until then) or in another (which holds its lock while it runs). Returns "" when
/// its stock is there, else why the job cannot run.
std::string awaitStock(const ManifestJob& source, const fs::path& jobs, std::mutex& mutex,
                       std::condition_variable& finished, const std::set<std::string>& pending) {
  {
    std::unique_lock<std::mutex> lock(mutex);
    finished.wait(lock, [&] { return !pending.count(source.name); });
  }
  const std::string why = "its stock is the final stock of job " + source.name + ", which ";
  for (;;) {
    ordered_json r = recordOf(source, jobs);
    if (r.is_null()) {
      const JobLock probe(jobs / ("." + source.name + ".lock"));
      if (probe.acquired()) {
        r = recordOf(source, jobs);  // (it may have ended between the two looks)
        if (r.is_null()) return why + "has not run with its options (run its shard first)";
      }
    }
    if (!r.is_null()) return ranToEnd(r) ? "" : why + "failed: " + r["error"].get<std::string>();
    if (stopRequested()) throw Interrupted();
    std::this_thread::sleep_for(std::chrono::seconds(1));  // another process runs it
  }
}

struct Shard {
  std::size_t index = 0, count = 1;
};

Shard parseShard(const std::string& s) {
  if (s.empty()) return {};
  const auto slash = s.find('/');
  try {
    if (slash == std::string::npos) throw std::invalid_argument(s);
    std::size_t a = 0, b = 0;
    const long i = std::stol(s.substr(0, slash), &a);
    const long n = std::stol(s.substr(slash + 1), &b);
    if (a != slash || b != s.size() - slash - 1 || n < 1 || i < 0 || i >= n)
      throw std::invalid_argument(s);
    return {static_cast<std::size_t>(i), static_cast<std::size_t>(n)};
  } catch (const std::exception&) {
    throw ParameterError("--shard: expected i/N with 0 <= i < N, found '" + s + "'");
  }
}

/// report.html of a batch: one row per job (the merged records, then the jobs that have not
/// run) with its status, figures in the batch's units, error, and a link to its own report.
std::string batchReportHtml(const std::vector<ordered_json>& records,
                            const std::vector<std::string>& missing, const fs::path& out,
                            UnitSystem sys) {
  auto display = [&](const ordered_json& v, Dimension d) {
    return v.is_null() ? ordered_json() : ordered_json(toDisplay(v.get<double>(), d, sys));
  };
  ordered_json jobs = ordered_json::array();
  for (const ordered_json& r : records) {
    const std::string name = r["name"].get<std::string>();
    const bool hasReport = fs::exists(out / "jobs" / name / "report.html");
    jobs.push_back(
        {{"name", name},
         {"status", r["status"]},
         {"program", r["program"]},
         {"error", r["error"]},
         {"warnings", r["warnings"]},
         {"report", hasReport ? ordered_json("jobs/" + name + "/report.html") : ordered_json()},
         {"figures",
          {{"removed", display(r["removed_mm3"], Dimension::Volume)},
           {"peak_mrr", display(r["peak_mrr_mm3_min"], Dimension::VolumeRate)},
           {"peak_mrr_line", r["peak_mrr_line"]},
           {"cutting_time_s", r["cutting_time_s"]},
           {"feed_time_before_s", r["feed_time_before_s"]},
           {"feed_time_after_s", r["feed_time_after_s"]},
           {"collisions", r["collisions"]}}}});
  }
  for (const std::string& name : missing)
    jobs.push_back({{"name", name}, {"status", "not run"}, {"error", nullptr}});
  ordered_json data;
  data["kind"] = "batch";
  data["title"] = "engage batch: " + out.filename().string();
  data["batch"] = {
      {"subtitle", out.string() + " · " + std::to_string(records.size() + missing.size()) +
                       " jobs · figures in " + std::string(systemName(sys))},
      {"jobs", jobs},
      {"units",
       {{"volume", std::string(unitLabel(Dimension::Volume, sys))},
        {"mrr", std::string(unitLabel(Dimension::VolumeRate, sys))}}},
      {"files", {"batch.csv", "batch.json"}}};
  return htmlPage(PageKind::Batch, data["title"].get<std::string>(),
                  data.dump(-1, ' ', false, ordered_json::error_handler_t::replace));
}

std::string mergeRecords(const std::vector<ManifestJob>& all, const fs::path& out, UnitSystem sys,
                         bool allowMissing = false) {
  const fs::path jobs = out / "jobs";
  std::vector<ordered_json> records;
  std::vector<std::string> missing;
  for (const ManifestJob& j : all) {
    ordered_json r = recordOf(j, jobs);
    if (r.is_null())
      missing.push_back(j.name);
    else
      records.push_back(std::move(r));
  }
  std::string list;
  for (std::size_t i = 0; i < missing.size() && i < 10; ++i)
    list += (i ? ", " : "") + missing[i];
  if (missing.size() > 10) list += ", ...";
  if (!missing.empty() && !allowMissing) {
    throw Error(std::to_string(missing.size()) + " of " + std::to_string(all.size()) +
                " jobs have not run in '" + out.string() + "': " + list +
                " (run their shards, then merge again)");
  }
  const std::string V(unitTag(Dimension::Volume, sys)), Q(unitTag(Dimension::VolumeRate, sys));
  auto value = [&](const ordered_json& v, Dimension d) {
    return v.is_null() ? std::string() : formatNumber(toDisplay(v.get<double>(), d, sys));
  };
  auto plain = [](const ordered_json& v) {
    return v.is_null() ? std::string() : formatNumber(v.get<double>());
  };
  // A gouges column where some job compared its stock with a --part (a batch without one
  // keeps its table as it was).
  bool parts = false;
  for (const ordered_json& r : records)
    parts = parts || (r.contains("gouges") && !r["gouges"].is_null());
  std::string csv = "job,name,command,program,status,run_time_s,moves,steps,removed_" + V +
                    ",peak_mrr_" + Q +
                    ",peak_mrr_line,cutting_time_s,feed_time_before_s,feed_time_after_s,"
                    "saving_relative,collisions," +
                    std::string(parts ? "gouges," : "") + "warnings,error\n";
  ordered_json summary = ordered_json::array();
  std::size_t ok = 0, collided = 0, gouged = 0;
  for (const ordered_json& r : records) {
    std::string warnings;
    for (const auto& w : r["warnings"])
      warnings += (warnings.empty() ? "" : "; ") + w.get<std::string>();
    ok += r["status"] == "ok";
    collided += r["status"] == "collision";
    gouged += r["status"] == "gouge";
    csv += std::to_string(r["index"].get<std::size_t>() + 1) + "," + csvQuoted(r["name"]) + "," +
           r["command"].get<std::string>() + "," + csvQuoted(r["program"]) + "," +
           r["status"].get<std::string>() + "," + plain(r["run_time_s"]) + "," + plain(r["moves"]) +
           "," + plain(r["steps"]) + "," + value(r["removed_mm3"], Dimension::Volume) + "," +
           value(r["peak_mrr_mm3_min"], Dimension::VolumeRate) + "," + plain(r["peak_mrr_line"]) +
           "," + plain(r["cutting_time_s"]) + "," + plain(r["feed_time_before_s"]) + "," +
           plain(r["feed_time_after_s"]) + "," + plain(r["saving_relative"]) + "," +
           plain(r["collisions"]) + "," +
           (parts ? plain(r.value("gouges", ordered_json())) + "," : std::string()) +
           csvQuoted(warnings) + "," +
           csvQuoted(r["error"].is_null() ? "" : r["error"].get<std::string>()) + "\n";
    ordered_json s = r;
    s.erase("spec");
    summary.push_back(s);
  }
  ordered_json j;
  j["jobs"] = records.size();
  j["ok"] = ok;
  j["collision"] = collided;
  j["gouge"] = gouged;
  j["failed"] = records.size() - ok - collided - gouged;
  j["missing"] = missing;
  j["units_of_csv"] = {{"volume", std::string(unitLabel(Dimension::Volume, sys))},
                       {"mrr", std::string(unitLabel(Dimension::VolumeRate, sys))}};
  j["records"] = summary;
  writeAtomically(out / "batch.csv", csv);
  writeAtomically(out / "batch.json", j.dump(2) + "\n");
  writeAtomically(out / "report.html", batchReportHtml(records, missing, out, sys));
  char line[256];
  const std::string gougedText =
      gouged > 0 ? ", " + std::to_string(gouged) + " gouged their part" : std::string();
  std::snprintf(line, sizeof line,
                "merged %zu jobs (%zu ok, %zu with collisions%s, %zu failed) into %s/batch.csv, "
                "batch.json, report.html\n",
                records.size(), ok, collided, gougedText.c_str(),
                records.size() - ok - collided - gouged, out.string().c_str());
  std::string text = line;
  if (!missing.empty())
    text += std::to_string(missing.size()) + " of " + std::to_string(all.size()) +
            " jobs have not run and are missing from the table: " + list + "\n";
  return text;
}

UnitSystem unitsOf(const std::string& u) {
  if (const auto named = unitSystemNamed(u)) return *named;
  throw ParameterError("--units: expected mm or in, found '" + u + "'");
}

}  // namespace

int usableCpus() {
  int cpus = static_cast<int>(std::thread::hardware_concurrency());
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) cpus = CPU_COUNT(&set);
  // cgroup v2 "QUOTA PERIOD" (or "max"), else v1's two files: CPUs = ceil(quota / period).
  double quota = -1.0, period = 0.0;
  if (std::ifstream v2("/sys/fs/cgroup/cpu.max"); v2) {
    std::string q;
    v2 >> q >> period;
    if (q != "max") quota = std::atof(q.c_str());
  } else {
    std::ifstream("/sys/fs/cgroup/cpu/cpu.cfs_quota_us") >> quota;
    std::ifstream("/sys/fs/cgroup/cpu/cpu.cfs_period_us") >> period;
  }
  if (quota > 0.0 && period > 0.0)
    cpus = std::min(cpus, static_cast<int>(std::ceil(quota / period)));
  return std::max(1, cpus);
}

/// A batch's progress on stderr: on a terminal one line redrawn (line()); otherwise (a
/// cluster's log) or with --quiet one line per job as it ends (jobEnded()), so that a shard's
/// log shows its progress before the shard ends.
struct BatchProgress {
  bool tty;
  std::chrono::steady_clock::time_point start;
  std::size_t jobs;
  const std::atomic<std::size_t>& finished;
  const std::atomic<std::size_t>& failed;

  void jobEnded(const ManifestJob& job, const ordered_json& r) const {
    if (tty) return;
    std::fprintf(stderr, "batch: [%zu/%zu] %s %s (%.1f s)\n", finished.load(), jobs,
                 job.name.c_str(), r["status"].get<std::string>().c_str(),
                 r["run_time_s"].get<double>());
    std::fflush(stderr);
  }
  void line() const {
    if (!tty) return;
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "\rbatch: %zu / %zu jobs done, %zu failed (%.0f s)   ", finished.load(),
                 jobs, failed.load(), s);
  }
};

/// The batch options that need the manifest checked, before any job runs.
void checkBatchOptions(const BatchOptions& o, const std::vector<ManifestJob>& all) {
  if (o.workers < 0) throw ParameterError("--workers must not be negative");
  if (!o.job.empty()) {
    if (!o.shard.empty()) throw ParameterError("give either --job or --shard");
    if (std::none_of(all.begin(), all.end(), [&](const ManifestJob& j) { return j.name == o.job; }))
      throw ParameterError("--job: no job named '" + o.job + "' in " + o.manifest);
  }
  if (!o.outputs.empty() && o.outputs != "all" && o.outputs != "tables" && o.outputs != "summary")
    throw ParameterError("--outputs: expected all, tables or summary, found '" + o.outputs + "'");
}

/// This shard's jobs that are to run, in the order workers take them: every N-th of the
/// manifest, starting at i (a job whose stock is an earlier job's goes with that job's shard);
/// those with a record for the same options are done (failed ones too, unless
/// --retry-failed) and counted in `skipped`; `mine` counts the shard's jobs.
std::vector<const ManifestJob*> shardJobs(const std::vector<ManifestJob>& all, const Shard& shard,
                                          const BatchOptions& o, const fs::path& jobs,
                                          std::size_t& skipped, std::size_t& mine) {
  std::vector<const ManifestJob*> todo;
  for (const ManifestJob& j : all) {
    if (!o.job.empty() ? j.name != o.job : j.group % shard.count != shard.index) continue;
    ++mine;
    const ordered_json r = recordOf(j, jobs);
    if (!r.is_null() && (ranToEnd(r) || !o.retryFailed)) {
      ++skipped;
      continue;
    }
    todo.push_back(&j);
  }

  // Longest first, so that a long job does not start last and run alone (the program's size
  // stands for its length; the order does not change any result).
  std::stable_sort(todo.begin(), todo.end(), [](const ManifestJob* a, const ManifestJob* b) {
    auto size = [](const ManifestJob* j) {
      std::error_code ec;
      const auto n = fs::file_size(j->values.at("program"), ec);
      return ec ? std::uintmax_t(0) : n;
    };
    return size(a) > size(b);
  });
  // A job whose stock is an earlier job's comes after it (workers take jobs in this order, so
  // a job waits only for one that a worker already holds).
  std::stable_sort(todo.begin(), todo.end(),
                   [](const ManifestJob* a, const ManifestJob* b) { return a->depth < b->depth; });
  return todo;
}

/// The shard's failed jobs (this run's or earlier ones: their errors are in their records) and
/// its jobs whose tool met material, into `result`.
void shardOutcomes(const std::vector<ManifestJob>& all, const Shard& shard, const fs::path& jobs,
                   BatchReport& result) {
  for (const ManifestJob& j : all)
    if (j.group % shard.count == shard.index) {
      const ordered_json r = recordOf(j, jobs);
      if (!r.is_null() && !ranToEnd(r))
        result.failures.push_back("job " + j.name + " failed: " + r["error"].get<std::string>());
      else if (!r.is_null() && r.contains("collisions") && r["collisions"].is_number() &&
               r["collisions"].get<std::size_t>() > 0)
        result.collisions.push_back("job " + j.name + ": " +
                                    std::to_string(r["collisions"].get<std::size_t>()) +
                                    " collision(s), in its summary.json");
      else if (!r.is_null() && r.contains("gouges") && r["gouges"].is_number() &&
               r["gouges"].get<std::size_t>() > 0)
        result.gouges.push_back("job " + j.name + ": " +
                                std::to_string(r["gouges"].get<std::size_t>()) +
                                " gouge(s) of its --part, in its gouges.csv");
    }
}

BatchReport runBatch(const BatchOptions& o) {
  const std::vector<ManifestJob> all = readManifest(o.manifest);
  const Shard shard = parseShard(o.shard);
  const double memoryLimit = o.memory.empty() ? 0.0 : parseMemory(o.memory, "--max-memory");
  const UnitSystem sys = unitsOf(o.units);
  checkBatchOptions(o, all);
  const fs::path out(o.out), jobs = out / "jobs";
  // Checked before any job runs; kept whatever happens next: a batch resumes from what its
  // jobs left.
  OutputDirectory(out).keep();
  fs::create_directories(jobs);

  std::size_t skipped = 0, mine = 0;
  std::vector<const ManifestJob*> todo = shardJobs(all, shard, o, jobs, skipped, mine);
  std::map<std::string, const ManifestJob*> byName;
  for (const ManifestJob& j : all)
    byName[j.name] = &j;
  std::set<std::string> pending;  // this process's jobs not finished yet
  for (const ManifestJob* j : todo)
    pending.insert(j->name);
  std::condition_variable finishedOne;

  // Workers: jobs side by side, each with its share of the threads (results do not depend
  // on the thread count). Measured on 2 cores: 2 jobs side by side beat 1 job on 2 threads
  // (docs/batches.md), so the default is one job per usable CPU.
  if (o.threads < 0) throw ParameterError("--threads must not be negative");
  const int cores = o.threads > 0 ? o.threads : usableCpus();
  const int workers =
      std::max(1, std::min<int>(o.workers > 0 ? o.workers : cores, static_cast<int>(todo.size())));
  const int threadsPerJob = std::max(1, cores / workers);
  std::atomic<std::size_t> next{0}, finished{0}, failed{0};
  std::mutex mutex;
  std::exception_ptr fatal;
  std::size_t elsewhere = 0;  // jobs another process held or finished meanwhile
  const bool tty = isatty(2) && !o.quiet;
  const auto start = std::chrono::steady_clock::now();
  const BatchProgress progress{tty, start, todo.size(), finished, failed};
  auto logJob = [&](const ManifestJob& job, const ordered_json& r) { progress.jobEnded(job, r); };
  auto report = [&]() { progress.line(); };
  report();
  // Jobs side by side hold at most --max-memory, else 80 % of what the process may use now.
  MemoryBudget memory(memoryLimit > 0.0 ? memoryLimit : 0.8 * processMemoryLimit().bytes);
  std::vector<std::thread> pool;
  for (int w = 0; w < workers; ++w)
    pool.emplace_back([&]() {
      tbb::task_arena arena(threadsPerJob);
      for (std::size_t k; (k = next++) < todo.size();) {
        ordered_json r;
        // One process per job: another batch on the same folder (a resubmitted shard, a
        // second batch started by hand) runs it, or has run it since this one looked.
        const JobLock held(jobs / ("." + todo[k]->name + ".lock"));
        if (!held.note().empty()) {
          std::lock_guard<std::mutex> lock(mutex);
          std::fprintf(stderr, "batch: job %s: %s\n", todo[k]->name.c_str(), held.note().c_str());
        }
        const bool done = [&] {
          if (!held.acquired()) return true;
          const ordered_json now = recordOf(*todo[k], jobs);
          return !now.is_null() && (ranToEnd(now) || !o.retryFailed);
        }();
        if (done) {
          std::lock_guard<std::mutex> lock(mutex);
          pending.erase(todo[k]->name);
          finishedOne.notify_all();
          ++elsewhere;
          std::fprintf(stderr, "batch: job %s runs or ran in another process%s: skipped here\n",
                       todo[k]->name.c_str(),
                       held.owner().empty() ? "" : (" (" + held.owner() + ")").c_str());
          continue;
        }
        try {
          const std::string blocked =
              todo[k]->stockFrom.empty()
                  ? std::string()
                  : awaitStock(*byName.at(todo[k]->stockFrom), jobs, mutex, finishedOne, pending);
          arena.execute([&] { r = runOne(*todo[k], jobs, o.outputs, memory, blocked); });
        } catch (...) {
          // A job's own failure is its record; this is the batch's (its record cannot be
          // written: a full disk, say). The batch stops and reports it, it does not crash.
          std::lock_guard<std::mutex> lock(mutex);
          if (!fatal) fatal = std::current_exception();
          next = todo.size();
          pending.clear();  // (nobody waits for a job that will not run)
          finishedOne.notify_all();
          return;
        }
        std::lock_guard<std::mutex> lock(mutex);
        pending.erase(todo[k]->name);
        finishedOne.notify_all();
        ++finished;
        if (!ranToEnd(r)) ++failed;
        logJob(*todo[k], r);
        report();
      }
    });
  for (std::thread& t : pool)
    t.join();
  if (fatal) {
    if (tty) std::fprintf(stderr, "\n");
    std::rethrow_exception(fatal);
  }
  if (tty) std::fprintf(stderr, "\n");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  BatchReport result;
  char line[256];
  std::snprintf(line, sizeof line,
                "batch: shard %zu/%zu: %zu jobs: %zu run (%zu failed), %zu already done; %d "
                "worker(s) x %d thread(s), %.1f s\n",
                shard.index, shard.count, mine, todo.size() - elsewhere, failed.load(),
                skipped + elsewhere, workers, threadsPerJob, seconds);
  result.text = line;
  if (shard.count == 1 && o.job.empty()) {
    try {
      result.text += mergeRecords(all, out, sys);
    } catch (const Error&) {
      // Jobs still running in another batch on this folder: that one merges when it ends.
      if (elsewhere == 0) throw;
      result.text += "batch: not merged: " + std::to_string(elsewhere) +
                     " job(s) run in another process on this folder, which merges at its end\n";
    }
  }
  shardOutcomes(all, shard, jobs, result);
  return result;
}

std::string mergeBatch(const BatchOptions& o) {
  return mergeRecords(readManifest(o.manifest), o.out, unitsOf(o.units), o.allowMissing);
}

}  // namespace engage
