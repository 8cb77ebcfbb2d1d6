#include "apps/SimulateCommand.h"

#include "apps/JobOptions.h"
#include "engine/run/Job.h"
#include "engine/run/RunOutputs.h"

#include <cstdio>
#include <memory>

namespace engage::app {
namespace {

int runSimulate(JobCommand command, const OptionValues& values) {
  const CompletedRun run = runIntoFolder(makeJob(command, values));
  std::fputs(runReport(run.result, run.written).c_str(), stdout);
  // 5: the run is complete and written, but a rapid, a shank or a holder met material;
  // 7: likewise, but the stock is gouged deeper than --tolerance into the --part.
  if (!run.result.sim.collisions.empty()) return 5;
  return run.result.part.gouges.empty() ? 0 : 7;
}

void addCommand(CLI::App& app, std::function<int()>& run, JobCommand command, const char* help) {
  auto values = std::make_shared<OptionValues>();
  CLI::App* cmd = app.add_subcommand(commandName(command), help);
  addJobOptions(*cmd, *values, command);
  cmd->callback([values, command, &run] {
    run = [values, command] { return runSimulate(command, *values); };
  });
}

}  // namespace

void addSimulateCommand(CLI::App& app, std::function<int()>& run) {
  addCommand(
      app, run, JobCommand::Simulate,
      "sweep the cutter through the stock (dexel or voxel) step by step: measured removal and "
      "engagement beside the analytic model");
  addCommand(app, run, JobCommand::Schedule,
             "simulate, then re-feed the program to hold the MRR at a target within the "
             "machine's feed and acceleration limits");
}

}  // namespace engage::app
