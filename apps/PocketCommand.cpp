#include "apps/PocketCommand.h"

#include "engine/run/PocketJob.h"

#include <cstdio>
#include <memory>

namespace engage::app {

void addPocketCommand(CLI::App& app, std::function<int()>& run) {
  auto o = std::make_shared<PocketJobOptions>();
  CLI::App* cmd = app.add_subcommand(
      "pocket",
      "write a contour-parallel pocket program (inside out, arcs kept) for a boundary given as "
      "closed G1/G2/G3 loops");
  cmd->add_option("boundary", o->boundary,
                  "G-code boundary: the first closed loop is the pocket, loops inside it islands")
      ->required();
  cmd->add_option("-o,--output", o->output, "program to write")->required();
  cmd->add_option("--diameter", o->diameter, "tool diameter at the floor")->required();
  cmd->add_option("--stepover", o->stepover, "distance between rings")->required();
  cmd->add_option("--depth", o->depth, "pocket depth below --top")->required();
  cmd->add_option("--step-down", o->stepDown, "depth per level (default: all at once)");
  cmd->add_option("--top", o->top, "Z of the stock top")->capture_default_str();
  cmd->add_option("--safe-z", o->safeZ, "retract height (default: top + 5 mm or 0.2 in)");
  cmd->add_option("--feed", o->feed, "cutting feed, e.g. 100ipm or 2500mm/min")->required();
  cmd->add_option("--plunge-feed", o->plungeFeed, "feed of the entries (default: half --feed)");
  cmd->add_option("--tolerance", o->tolerance, "arc fitting tolerance (default 0.002 mm)");
  cmd->add_option("--units", o->units, "program units: mm or in (default: the boundary's)")
      ->check(CLI::IsMember({"mm", "in", "inch"}));
  cmd->add_flag("--conventional", o->conventional,
                "conventional instead of climb milling (M3 spindle)");
  cmd->callback([o, &run] {
    run = [o] {
      std::fputs(writePocketJob(*o).c_str(), stdout);
      return 0;
    };
  });
}

}  // namespace engage::app
