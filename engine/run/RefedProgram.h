#pragma once
/// \file RefedProgram.h
/// The re-fed program of a schedule job: the user's program with the scheduled F words,
/// written under the program's own file name into the output folder.

#include "engine/run/Pipeline.h"

#include <filesystem>
#include <string>

namespace engage {

/// The re-fed program's header: one comment line naming what the schedule held (the target,
/// the limits, the feed bounds), placed after a leading `%` and a Fanuc program number
/// (`O1234`), which must stay first.
std::string withScheduleHeader(const std::string& program, const Job& job);

/// Where the re-fed program goes: `dir` / the program's file name.
std::filesystem::path refedProgramPath(const RunResult& result, const std::filesystem::path& dir);

/// Write it (schedule jobs; nothing otherwise). Throws Error naming the file.
void writeRefedProgram(const RunResult& result, const std::filesystem::path& dir);

}  // namespace engage
