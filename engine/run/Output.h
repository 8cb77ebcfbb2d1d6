#pragma once
/// \file Output.h
/// Writing output files so that nothing is ever half-written: the text goes to a temporary
/// name beside the target and is renamed when complete.

#include <filesystem>
#include <string>

namespace engage {

/// Write `text` to `path` through `path.part`; throws Error naming the file when it fails.
void writeAtomically(const std::filesystem::path& path, const std::string& text);

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
  void keep() { keep_ = true; }

 private:
  std::filesystem::path created_;  ///< the topmost folder this made; empty if none
  bool keep_ = false;
};

/// Read a whole file; throws Error naming it when it cannot be read.
std::string readFile(const std::filesystem::path& path);

}  // namespace engage
