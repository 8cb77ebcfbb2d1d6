#include "apps/BatchCommand.h"

#include "engine/run/Batch.h"

#include <cstdio>
#include <memory>

namespace engage::app {
namespace {

int runBatchCommand(const BatchOptions& o) {
  const BatchReport report = runBatch(o);
  std::fputs(report.text.c_str(), stdout);
  for (const std::string& f : report.failures)
    std::fprintf(stderr, "engage: %s\n", f.c_str());
  for (const std::string& c : report.collisions)
    std::fprintf(stderr, "engage: %s\n", c.c_str());
  for (const std::string& g : report.gouges)
    std::fprintf(stderr, "engage: %s\n", g.c_str());
  // 4: the batch ran, some jobs failed (their records hold the errors); not a crash (3).
  // 5: all ran, and some met material with what must not cut (as simulate's 5); 7: all ran,
  // and some gouged their --part (as simulate's 7).
  if (!report.failures.empty()) return 4;
  if (!report.collisions.empty()) return 5;
  return report.gouges.empty() ? 0 : 7;
}

}  // namespace

void addBatchCommands(CLI::App& app, std::function<int()>& run) {
  auto o = std::make_shared<BatchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "batch",
      "run the simulate/schedule jobs of a JSON manifest, side by side, resumable, sharded for "
      "cluster job arrays");
  cmd->add_option("manifest", o->manifest, "JSON manifest of jobs")->required();
  cmd->add_option("--out", o->out, "output folder (jobs/NAME per job)")->capture_default_str();
  cmd->add_option("--shard", o->shard, "run the i-th of N shares of the jobs, e.g. 0/4");
  cmd->add_option("--workers", o->workers, "jobs side by side (default: one per usable CPU)");
  cmd->add_option("--threads", o->threads,
                  "CPUs to use in all (default: those this process may use: its affinity "
                  "mask and cgroup quota)");
  cmd->add_option("--max-memory,--memory", o->memory,
                  "memory the jobs side by side may hold, e.g. 8GB (default: 80 % of what this "
                  "process may use: the available memory, the cgroup's limit, ulimit -v)");
  cmd->add_flag("--retry-failed", o->retryFailed, "run failed jobs again");
  cmd->add_option("--job", o->job,
                  "run this job alone (by name; for workflow rules, then `engage merge`)");
  cmd->add_option("--outputs", o->outputs,
                  "the jobs' files unless a job says: all, tables (steps.csv, summary.json) or "
                  "summary (summary.json)");
  cmd->add_option("--units", o->units, "units of batch.csv: mm or in")->capture_default_str();
  cmd->add_flag("--quiet", o->quiet, "no progress on the terminal");
  cmd->callback([o, &run] { run = [o] { return runBatchCommand(*o); }; });

  auto m = std::make_shared<BatchOptions>();
  CLI::App* merge = app.add_subcommand(
      "merge", "join the job records of a (sharded) batch into batch.csv and batch.json");
  merge->add_option("manifest", m->manifest, "the batch's JSON manifest")->required();
  merge->add_option("--out", m->out, "the batch's output folder")->capture_default_str();
  merge->add_option("--units", m->units, "units of batch.csv: mm or in")->capture_default_str();
  merge->add_flag("--allow-missing", m->allowMissing,
                  "write the table of the jobs that ran and list the missing ones");
  merge->add_flag("--quiet", m->quiet,
                  "accepted for symmetry with batch (merge shows no progress)");
  merge->callback([m, &run] {
    run = [m] {
      std::fputs(mergeBatch(*m).c_str(), stdout);
      return 0;
    };
  });
}

}  // namespace engage::app
