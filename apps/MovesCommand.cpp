#include "apps/MovesCommand.h"

#include "engine/gcode/GcodeReader.h"
#include "engine/run/Machine.h"
#include "engine/run/MovesTable.h"
#include "engine/units/Quantity.h"

#include <cstdio>
#include <memory>
#include <string>

namespace engage::app {
namespace {

struct MovesOptions {
  std::string program;
  std::string toolTable;
  std::string toolTableUnits = "mm";
  std::string dialect = "linuxcnc";
  std::string machine;
  bool blockDelete = false;
};

int runMoves(const MovesOptions& o) {
  ReaderOptions reader;
  reader.toolTable = o.toolTable;
  reader.toolTableInch = unitSystemNamed(o.toolTableUnits) == UnitSystem::Inch;
  reader.blockDelete = o.blockDelete;
  reader.dialect = dialectOf(o.dialect);
  if (!o.machine.empty()) reader.machine = readMachine(o.machine);
  const Toolpath path = readProgram(o.program, reader);
  // The whole table is made before printing: an error leaves no partial output.
  const std::string out = movesTable(path);
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}

}  // namespace

void addMovesCommand(CLI::App& app, std::function<int()>& run) {
  auto o = std::make_shared<MovesOptions>();
  CLI::App* cmd = app.add_subcommand(
      "moves", "print the interpreted moves of a G-code program as CSV (mm, machine coordinates)");
  cmd->add_option("program", o->program, "G-code program (.ngc, .nc, .tap, .gcode)")->required();
  cmd->add_option("--tool-table", o->toolTable, "LinuxCNC tool table for G43");
  cmd->add_option("--tool-table-units", o->toolTableUnits, "units of the tool table: mm or in")
      ->check(CLI::IsMember({"mm", "in", "inch"}))
      ->capture_default_str();
  cmd->add_flag("--block-delete", o->blockDelete, "skip lines starting with '/'");
  cmd->add_option("--dialect", o->dialect, "the controller: linuxcnc, fanuc or grbl")
      ->check(CLI::IsMember({"linuxcnc", "fanuc", "grbl"}))
      ->capture_default_str();
  cmd->add_option("--machine", o->machine,
                  "machine description (JSON): work offset, G28/G30, start, travel");
  cmd->callback([o, &run] { run = [o] { return runMoves(*o); }; });
}

}  // namespace engage::app
