#pragma once
/// \file Output.h
/// Writing output files so that nothing is ever half-written: the text goes to a temporary
/// name beside the target and is renamed when complete; a CSV field quoted.

#include "stock/AtomicFile.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace engage {

/// Write `text` to `path` through `path.part`; throws Error naming the file when it fails.
void writeAtomically(const std::filesystem::path& path, const std::string& text);

/// A CSV field: `text` in double quotes, its quotes doubled (RFC 4180).
std::string csvQuoted(const std::string& text);

/// An output folder, made with its missing parents when a run starts (so that a folder that
/// cannot be made or written fails before any work, with one clear line). If the run then
/// fails (the object is destroyed without keep()), the folders it made are removed again with
/// whatever went into them: a failing run leaves nothing. A folder that existed is never
/// removed.
class OutputDirectory {
 public:
  /// Throws Error naming the folder when it cannot be made or a file cannot be written in it.
  explicit OutputDirectory(const std::filesystem::path& dir);
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;
  /// The run succeeded: keep the folder.
  void keep();

 private:
  std::filesystem::path created_;           ///< the topmost folder this made; empty if none
  std::unique_ptr<Unfinished> unfinished_;  ///< created_, while the run has not succeeded
  bool keep_ = false;
};

/// A run's files, written into a staging folder inside the output folder
/// (OUT/.engage-partial-HOST-PID) and moved into OUT only when every one is complete (publish). The
/// files of an earlier run in OUT (listed in its OUT/.engage-files, and engage's own file names)
/// are removed first, summary.json is removed first and moved in last: a folder with a
/// summary.json holds one complete run, never a mix and never a half-written file, whatever
/// kills the process when. Publishing holds a lock on OUT (flock), so two runs into one folder
/// publish one after the other. Staging folders of this host's runs that died are removed.
class StagedOutputs {
 public:
  /// Makes the staging folder in `out` (which exists). Throws Error.
  explicit StagedOutputs(const std::filesystem::path& out);
  ~StagedOutputs();
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;
  /// Where the files go meanwhile.
  const std::filesystem::path& staging() const { return staging_; }
  /// Move the staged files into the output folder as described above. Throws Error.
  void publish();

 private:
  std::filesystem::path out_, staging_;
  std::unique_ptr<Unfinished> unfinished_;  ///< staging_, until it is published
  bool published_ = false;
};

/// Read a whole file; throws Error naming it when it cannot be read.
std::string readFile(const std::filesystem::path& path);

}  // namespace engage
