#pragma once
/// \file OptionTable.h
/// The one table of the options of a simulate or schedule job: name (as on the command line,
/// without the leading --, and as a manifest key), what kind of value it takes and in which
/// unit, its default, its help text, and which front ends take it. The command line registers
/// its options by walking this table and the manifest reader checks its keys against it, so
/// the two cannot drift apart; makeJob (Job.h) is the one place that reads the values.

#include "engine/units/Quantity.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace engage {

/// The two job commands.
enum class JobCommand { Simulate, Schedule };

/// What an option's value is.
enum class OptionKind {
  Quantity,  ///< a number with an optional unit suffix (OptionInfo::dimension)
  Choice,    ///< one of OptionInfo::choices
  Text,      ///< free text: a file path or a stock description
  Flag,      ///< true or false; on the command line given without a value
  Fraction,  ///< a plain number in (0, 1)
  Count,     ///< a whole number
};

/// Which part of the job an option belongs to (the order of the help text).
enum class OptionGroup { Tool, Stock, Simulation, Schedule, Output };

/// One option.
struct OptionInfo {
  std::string name;  ///< e.g. "target-mrr": --target-mrr on the command line
  OptionKind kind = OptionKind::Text;
  OptionGroup group = OptionGroup::Simulation;
  Dimension dimension = Dimension::Length;  ///< of a Quantity
  std::vector<std::string> choices;         ///< of a Choice
  std::string defaultText;                  ///< as typed; empty: none (unset)
  std::string help;
  bool required = false;      ///< the job cannot run without it
  bool scheduleOnly = false;  ///< only `schedule` takes it
  /// Taken by the command line only: it controls the run, not the job (a batch writes each
  /// job into its own folder and shows progress per batch, so a manifest refuses these).
  bool commandLineOnly = false;
};

/// Every option of simulate and schedule, in help order.
const std::vector<OptionInfo>& jobOptions();

/// The option called `name`, or nullptr.
const OptionInfo* findJobOption(const std::string& name);

/// Whether `command` takes the option.
bool appliesTo(const OptionInfo& option, JobCommand command);

/// "simulate" or "schedule".
const char* commandName(JobCommand command);

/// The values of a job's options as typed, by name (flags "true"/"false"); options not in the
/// map take the table's default. The program is the value of "program".
using OptionValues = std::map<std::string, std::string>;

}  // namespace engage
