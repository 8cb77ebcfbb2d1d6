#pragma once
/// \file Manifest.h
/// A batch manifest: JSON with a "defaults" object and a "jobs" array; each job has
/// "program", optional "name" and "command", and options named as in OptionTable.h. Read and
/// checked whole before any job runs (Batch.h runs them).

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
};

/// Read and check a manifest: every structural problem (not JSON, unknown or misplaced keys,
/// duplicate names) is reported here, before any job runs. Relative files are relative to the
/// manifest. Throws Error naming the manifest and the job.
std::vector<ManifestJob> readManifest(const std::string& path);

}  // namespace engage
