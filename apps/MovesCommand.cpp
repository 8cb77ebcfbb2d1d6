#include "apps/MovesCommand.h"

#include "apps/JobOptions.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/run/Job.h"
#include "engine/run/MovesTable.h"

#include <cstdio>
#include <memory>
#include <string>

namespace engage::app {
namespace {

int runMoves(const OptionValues& values) {
  const std::string& program = values.at("program");
  const Toolpath path = readProgram(program, readerOptions(values, program));
  // The whole table is made before printing: an error leaves no partial output.
  const std::string out = movesTable(path);
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}

}  // namespace

void addMovesCommand(CLI::App& app, std::function<int()>& run) {
  auto values = std::make_shared<OptionValues>();
  CLI::App* cmd = app.add_subcommand(
      "moves", "print the interpreted moves of a G-code program as CSV (mm, machine coordinates)");
  cmd->add_option("program", (*values)["program"], "G-code program (.ngc, .nc, .tap, .gcode)")
      ->required();
  addReaderOptions(*cmd, *values);
  cmd->callback([values, &run] { run = [values] { return runMoves(*values); }; });
}

}  // namespace engage::app
