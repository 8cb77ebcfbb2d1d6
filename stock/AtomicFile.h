#pragma once
/// \file AtomicFile.h
/// Writing a file so that it is never lost or half-written: the content goes through a stream
/// checked at every stage (a full disk shows at the flush or the close, which the writers of
/// OpenVDB and OpenMesh do not check) into PATH.part, renamed to PATH when complete; on any
/// failure the .part file is removed and Error names PATH and the system's reason ("No space
/// left on device").

#include <functional>
#include <ostream>
#include <string>

namespace engage {

/// Write PATH through `write`, which puts the content into the stream. Throws Error.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace engage
