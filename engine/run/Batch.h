#pragma once
/// \file Batch.h
/// Many simulate/schedule jobs from a JSON manifest, side by side on one machine, or one shard
/// of them per node of a cluster job array. The manifest's keys are the option names of
/// OptionTable.h (a "defaults" object, then one object per job with "program", optional
/// "name" and "command"); each job runs through the same pipeline as `engage simulate` into
/// its own folder OUT/jobs/NAME with its record job.json, written last (a rerun skips jobs
/// whose record is there and whose options are unchanged). A merge joins the records into
/// OUT/batch.csv and batch.json.

#include "engine/run/Manifest.h"
#include "engine/run/OptionTable.h"
#include "engine/units/Quantity.h"

#include <cstddef>
#include <string>
#include <vector>

namespace engage {

/// The CPUs this process may use: its affinity mask (taskset, a Slurm allocation), bounded by
/// a cgroup CPU quota (containers, Slurm with cgroups) where one is set; at least 1.
int usableCpus();

/// The settings of a batch or merge.
struct BatchOptions {
  std::string manifest;
  std::string out = "out/batch";
  std::string shard;  ///< "i/N" or empty (all)
  int workers = 0;    ///< 0: one per usable CPU (at most the jobs)
  int threads = 0;    ///< CPUs to use in all; 0: usableCpus()
  /// Memory the jobs side by side may hold (--max-memory: "8GB", "512MB", "2GiB"); empty: 80 %
  /// of what the process may use (Memory.h). Each job reserves its estimate (memoryEstimate,
  /// Pipeline.h) and waits while the running jobs' reservations would not leave room for it.
  std::string memory;
  bool retryFailed = false;
  bool quiet = false;
  std::string units = "mm";   ///< of batch.csv
  std::string outputs;        ///< the jobs' files (all, tables, summary) unless a job says
  std::string job;            ///< run this job alone (by name), e.g. from a workflow rule
  bool allowMissing = false;  ///< merge: write the table of the jobs that ran, list the others
};

/// What a batch run tells its user.
struct BatchReport {
  std::string text;                   ///< the lines for stdout
  std::vector<std::string> failures;  ///< "job NAME failed: ERROR", one per failed job
  /// "job NAME: N collision(s) ...", one per job whose rapids, shank or holder met material.
  std::vector<std::string> collisions;
  /// "job NAME: N gouge(s) ...", one per job that gouged its --part deeper than --tolerance.
  std::vector<std::string> gouges;
};

/// Run the shard's jobs that have no record yet (and failed ones with retryFailed); with
/// one shard, merge too. A job's failure is its record, never the batch's. Throws Error for a
/// bad manifest, shard or output folder.
BatchReport runBatch(const BatchOptions& options);

/// Join the records of every job of the manifest into batch.csv and batch.json; returns the
/// line to print. Throws Error naming the jobs that have not run (nothing is written then).
std::string mergeBatch(const BatchOptions& options);

}  // namespace engage
