#pragma once
/// \file RefedProgram.h
/// The re-fed program of a schedule job: the user's program with the scheduled F words,
/// written under the program's own file name into the output folder.

#include "engine/run/Pipeline.h"

#include <filesystem>

namespace engage {

/// Where the re-fed program goes: `dir` / the program's file name.
std::filesystem::path refedProgramPath(const RunResult& result, const std::filesystem::path& dir);

/// Write it (schedule jobs; nothing otherwise). Throws Error naming the file.
void writeRefedProgram(const RunResult& result, const std::filesystem::path& dir);

}  // namespace engage
