#pragma once
/// \file Manifest.h
/// A batch manifest: JSON with a "defaults" object and a "jobs" array; each job has
/// "program", optional "name" and "command", and options named as in OptionTable.h. Read and
/// checked whole before any job runs (Batch.h runs them). A job's "stock" may be
/// "job:NAME": the stock.vdb an earlier job of the manifest leaves (rough, then finish).

#include "engine/run/OptionTable.h"

#include <cstddef>
#include <string>
#include <vector>

namespace engage {

/// One job of a manifest: its options merged over the defaults, checked against the table.
struct ManifestJob {
  std::size_t index = 0;  ///< 0-based place in the manifest
  std::string name;       ///< folder name under OUT/jobs
  JobCommand command = JobCommand::Simulate;
  OptionValues values;   ///< the options as typed, files resolved against the manifest
  std::string specJson;  ///< the spec as recorded in job.json (compact JSON)
  /// With "stock": "job:NAME", that earlier job: its stock.vdb is this job's stock, and this
  /// job runs after it, in its shard.
  std::string stockFrom;
  std::size_t group = 0;    ///< the shard key: the index of the first job of its chain
  std::size_t depth = 0;    ///< jobs before it in its chain of stocks (0: its own stock)
  bool feedsStock = false;  ///< a later job takes its stock.vdb: written whatever the outputs
};

/// The prefix of a "stock" value that names an earlier job's final stock.
constexpr const char* kStockFromJob = "job:";

/// Read and check a manifest: every structural problem (not JSON, unknown or misplaced keys,
/// duplicate names) is reported here, before any job runs. Relative files are relative to the
/// manifest. Throws Error naming the manifest and the job.
std::vector<ManifestJob> readManifest(const std::string& path);

}  // namespace engage
