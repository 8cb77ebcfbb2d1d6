#include "apps/PaperCommand.h"

#include "engine/paths/DataDirectory.h"
#include "engine/run/PaperExamples.h"

#include <cstdio>
#include <memory>

namespace engage::app {

void addPaperCommand(CLI::App& app, std::function<int()>& run) {
  auto o = std::make_shared<PaperOptions>();
  // (--data's default is found when the command runs: the installed data, else the source's.)
  CLI::App* cmd = app.add_subcommand(
      "paper",
      "reproduce the paper's examples (Figs 8, 9, 10-12, 13-14): programs, simulations, CSV files, "
      "plots and paper.json");
  cmd->add_option("--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--data", o->data,
                  "the data/ folder with paper/ (default: the installed data, or the source "
                  "tree's; $ENGAGE_DATA)");
  cmd->add_option("--voxel", o->voxel, "voxel size of the pocket simulations (Figs 9-14)")
      ->capture_default_str();
  cmd->add_option("--steady-voxel", o->steadyVoxel, "voxel size of the Fig 8 steady cuts")
      ->capture_default_str();
  cmd->add_flag("--quiet", o->quiet, "no progress on the terminal");
  cmd->callback([o, &run] {
    run = [o] {
      if (o->data.empty()) o->data = dataDirectory();
      std::fputs(runPaper(*o).c_str(), stdout);
      return 0;
    };
  });
}

}  // namespace engage::app
