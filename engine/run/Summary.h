#pragma once
/// \file Summary.h
/// summary.json: the run's figures in its report units (unit labels under "unit_labels"):
/// program, tool, stock, resolution, volumes, times, peak MRR with its step and line, the
/// agreement of measurement and analytic model per path class, the cross-check and the
/// schedule. Also the handful of lines `engage simulate` prints.

#include "engine/run/Pipeline.h"

#include <string>
#include <vector>

namespace engage {

/// The JSON text of summary.json (two-space indent, a final newline).
std::string summaryJson(const RunResult& result);

/// What writing the outputs made, for the report lines.
struct WrittenOutputs {
  std::vector<std::string> plots;  ///< PNG files drawn (names without the folder)
  std::size_t openEdges = 0;       ///< open edges of stock.stl (0: closed)
  bool refedProgram = false;       ///< the re-fed program was written
  bool steps = true;               ///< steps.csv was written
  bool stockFiles = false;         ///< removed.vdb, stock.vdb and stock.stl were written
  bool report = false;             ///< report.html was written
  bool partTables = false;         ///< gouges.csv and leftovers.csv were written (--part)
  bool deviationVdb = false;       ///< deviation.vdb was written (--part)
};

/// The lines `engage simulate` prints (each ending in a newline; warnings start "warning: ").
std::string runReport(const RunResult& result, const WrittenOutputs& written);

/// The warnings of a run, without the "warning: " prefix (rapids that cut, an open mesh).
std::vector<std::string> runWarnings(const RunResult& result, const WrittenOutputs& written);

/// The schedule's unmet limits (Schedule::unmet) in one message, per limit: how many steps on
/// which lines, and the largest load left at the lowest feed allowed; "" when all are met.
std::string unmetLimits(const RunResult& result);

}  // namespace engage
