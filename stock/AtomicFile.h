#pragma once
/// \file AtomicFile.h
/// Writing a file so that it is never lost or half-written: the content goes through a stream
/// checked at every stage (a full disk shows at the flush or the close, which the writers of
/// OpenVDB and OpenMesh do not check) into PATH.part, renamed to PATH when complete; on any
/// failure the .part file is removed and Error names PATH and the system's reason ("No space
/// left on device"). The files and folders being made are registered while they are
/// unfinished, so that a process that must end at once (`engage`'s stop on a signal, its out
/// of memory) removes them first.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace engage {

/// Write PATH through `write`, which puts the content into the stream. Throws Error (and what
/// `write` throws), the .part file removed.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// A file or folder being made, registered for its lifetime (or until release()) as one to
/// remove should the process end before it is complete (removeUnfinished). It removes nothing
/// itself: its owner does that on the normal paths.
class Unfinished {
 public:
  explicit Unfinished(std::filesystem::path path);
  /// Unregisters the path, unless it is still there and was not released: its owner could not
  /// remove it (out of memory), and removeUnfinished is to.
  ~Unfinished();
  Unfinished(const Unfinished&) = delete;
  Unfinished& operator=(const Unfinished&) = delete;
  /// The path is complete (or its owner removed it): no longer registered.
  void release();

 private:
  std::filesystem::path path_;
  bool registered_ = true;
};

/// Remove every path registered as unfinished, with what is in it; errors are ignored. For a
/// process about to end without unwinding (std::_Exit); the registrations stay.
void removeUnfinished() noexcept;

}  // namespace engage
