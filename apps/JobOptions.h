#pragma once
/// \file JobOptions.h
/// The command-line face of OptionTable.h: every option of a simulate or schedule job
/// registered on a subcommand by walking the table (names, help, defaults, choices), and the
/// cutter options alone for the commands that need only a tool (analyze), and the G-code
/// reader's alone for the command that only reads a program (moves).

#include "engine/run/CutterOptions.h"
#include "engine/run/OptionTable.h"

#include <CLI/CLI.hpp>

namespace engage::app {

/// Register the program and every option of `command` on `cmd`, storing the typed text in
/// `values` (flags as "true"). `values` must outlive the parse.
void addJobOptions(CLI::App& cmd, OptionValues& values, JobCommand command);

/// Register the cutter options (the table's Tool group) bound to `options`. `required` makes
/// --tool and --diameter required.
void addToolOptions(CLI::App& cmd, ToolOptions& options, bool required);

/// Register the options that say how a program is read (readerOptions in Job.h: --dialect,
/// --machine, --start, --startup-units, --tool-table, --tool-table-units, --block-delete,
/// --cutter-comp, --max-moves), storing the typed text in `values`.
void addReaderOptions(CLI::App& cmd, OptionValues& values);

}  // namespace engage::app
