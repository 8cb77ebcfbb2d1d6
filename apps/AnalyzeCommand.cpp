#include "apps/AnalyzeCommand.h"

#include "apps/JobOptions.h"
#include "engine/run/Analysis.h"

#include <iostream>
#include <memory>

namespace engage::app {

void addAnalyzeCommand(CLI::App& app, std::function<int()>& run) {
  auto o = std::make_shared<AnalyzeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "analyze",
      "analytic cross-section, MRR, force and adaptive feed of a steady-state pass "
      "(paper Eq 1-24)");
  addToolOptions(*cmd, o->tool, false);
  cmd->add_option("--stepover", o->stepover, "stepover s between passes, e.g. 0.5in");
  cmd->add_option("--depth", o->depth, "axial depth of cut d, e.g. 0.3in");
  cmd->add_option("--feed", o->feed, "programmed feed at the tool tip, e.g. 100ipm");
  cmd->add_option("--path-radius", o->pathRadius, "radius of the tool-centre path of an arc");
  cmd->add_option("--side", o->side, "stock side of the arc: concave or convex")
      ->check(CLI::IsMember({"concave", "convex"}));
  cmd->add_option("--target-mrr", o->targetMrr, "target MRR for the adaptive feed, e.g. 10in3/min");
  cmd->add_option("--specific-energy", o->specificEnergy,
                  "specific cutting energy E of the material, e.g. 0.7J/mm3 or 0.3hp*min/in3");
  cmd->add_option("--spindle", o->spindle, "spindle speed N, e.g. 10000rpm");
  cmd->add_option("--transition", o->transition,
                  "arc length over which the adaptive feed changes (Eq 24 acceleration)");
  cmd->add_option("--units", o->units, "report units: mm or in (default: those you typed)")
      ->check(CLI::IsMember({"mm", "in", "inch"}));
  cmd->add_flag("--json", o->json, "print one JSON object");
  auto* sweep = cmd->add_flag("--sweep-radius", o->sweep,
                              "print the paper's Fig 8 table as CSV: MRR against R/D for r_tc/D "
                              "from 0 to 0.5 (D 1in, d 0.3in, s 0.5in, 100ipm unless given)");
  sweep->excludes("--json")->excludes("--tool")->excludes("--path-radius")->excludes("--side");
  cmd->callback([o, &run] {
    run = [o] {
      std::cout << analyzeReport(*o);
      return 0;
    };
  });
}

}  // namespace engage::app
