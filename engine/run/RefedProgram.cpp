#include "engine/run/RefedProgram.h"

#include "engine/run/Output.h"

namespace engage {

std::filesystem::path refedProgramPath(const RunResult& result, const std::filesystem::path& dir) {
  return dir / std::filesystem::path(result.job.mainProgram()).filename();
}

void writeRefedProgram(const RunResult& result, const std::filesystem::path& dir) {
  if (result.job.scheduling()) writeAtomically(refedProgramPath(result, dir), result.refed);
}

}  // namespace engage
