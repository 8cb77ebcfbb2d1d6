#pragma once
/// \file StepsTable.h
/// steps.csv: one row per step of a run, in the run's report units (the unit in each column
/// name): where it is, the programmed feed, the measured removal, MRR and engagement, the
/// analytic model's MRR (exact and paper form), and for a schedule the scheduled feed, what
/// bound it and Eq 24's acceleration; for a cross-check the other model's removal.

#include "engine/run/Pipeline.h"

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

namespace engage {

/// The table's text (header and rows); with `rows`, only those steps (ascending indices).
std::string stepsTable(const RunResult& result, const std::vector<std::size_t>* rows = nullptr);
/// The same written to `os` row by row (a long run's table is never whole in memory).
void writeStepsTable(std::ostream& os, const RunResult& result,
                     const std::vector<std::size_t>* rows = nullptr);

/// Step i's scheduled feed over its programmed one (0 for rapids): the MRR and the chip
/// scale with it.
double feedScale(const RunResult& result, std::size_t i);

/// Eq 24's tangential acceleration between step i-1 and step i at the machine's speeds
/// under the scheduled feeds (Schedule::speed), mm/s^2 (0 at the first step and next to rapids).
double scheduledAcceleration(const RunResult& result, std::size_t i);

}  // namespace engage
