#pragma once
/// \file Output.h
/// Writing output files so that nothing is ever half-written: the text goes to a temporary
/// name beside the target and is renamed when complete.

#include <filesystem>
#include <string>

namespace engage::app {

/// Write `text` to `path` through `path.part`; throws Error naming the file when it fails.
void writeAtomically(const std::filesystem::path& path, const std::string& text);

/// Read a whole file; throws Error naming it when it cannot be read.
std::string readFile(const std::filesystem::path& path);

}  // namespace engage::app
