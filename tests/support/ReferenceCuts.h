#pragma once
/// \file ReferenceCuts.h
/// The thin- and grazing-cut programs of data/gcode/thin with their cutters and stock, the
/// exact per-move removal of each (ExactSweep.h, computed once per process), and what a stock
/// model measures per move. Shared by tests/stock/ReferenceCuts.cpp and
/// tests/bench/bench_thin_cuts.cpp.

#include "cutters/AptCutter.h"
#include "engine/gcode/Toolpath.h"
#include "stock/Stock.h"

#include <string>
#include <vector>

namespace engage::test {

struct ReferenceCase {
  std::string name;     ///< program file name (data/gcode/thin) and cutter, e.g. "floor_recut flat"
  std::string program;  ///< path of the program
  AptCutter cutter;
  Box3 stock;
};

/// The reference programs, each with its cutter (6 mm across) and its stock box.
std::vector<ReferenceCase> referenceCases(const std::string& sourceDir);

/// The exact removal per move of a case (mm^3), computed on the first call for the case.
const std::vector<double>& exactPerMove(const ReferenceCase& c);

/// The case's tool path.
Toolpath casePath(const ReferenceCase& c);

/// Per move of `path` (the case's, casePath()), the removal a stock model measures running it
/// with the case's cutter (simulate(), default step).
std::vector<double> measuredPerMove(const ReferenceCase& c, const Toolpath& path, Stock& stock);

}  // namespace engage::test
