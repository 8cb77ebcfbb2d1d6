// Tests of engine/run/OptionTable.h: the table is the one schema of both front ends. Every
// job option is walked and given once on the command line (apps/JobOptions.h) and once in a
// batch manifest (engine/run/Batch.h); both must take it, with the same text.

#include "engine/run/OptionTable.h"

#include "apps/JobOptions.h"
#include "cutters/Error.h"
#include "engine/run/Batch.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <set>

using namespace engage;

namespace {

/// A value of the option's kind that the front ends must take.
std::string sampleValue(const OptionInfo& o) {
  switch (o.kind) {
    case OptionKind::Choice:
      return o.choices.back();
    case OptionKind::Flag:
      return "true";
    case OptionKind::Fraction:
      return "0.1";
    case OptionKind::Count:
      return "3";
    case OptionKind::Quantity:
      return "1.5";
    case OptionKind::Text:
      break;
  }
  if (o.name == "stock") return "box:0,0,-1,1,1,0";
  if (o.name == "target-mrr") return "1000mm3/min";
  return "/tmp/some-file";
}

/// What the command line stored for `--name value` after a schedule command.
std::string viaCommandLine(const OptionInfo& o, const std::string& value) {
  CLI::App app;
  OptionValues values;
  CLI::App* cmd = app.add_subcommand("schedule");
  app::addJobOptions(*cmd, values, JobCommand::Schedule);
  std::vector<std::string> args = {"engage", "schedule", "p.ngc"};
  if (o.name != "tool") args.insert(args.end(), {"--tool", "ball"});
  if (o.name != "diameter") args.insert(args.end(), {"--diameter", "6mm"});
  args.push_back("--" + o.name);
  if (o.kind != OptionKind::Flag) args.push_back(value);
  std::vector<char*> argv;
  for (std::string& a : args)
    argv.push_back(a.data());
  app.parse(static_cast<int>(argv.size()), argv.data());
  return values.at(o.name);
}

}  // namespace

TEST_CASE("every job option is taken by the command line and by a manifest", "[run]") {
  test::TempFolder dir("option_table");
  std::set<std::string> names;
  for (const OptionInfo& o : jobOptions()) {
    INFO("option " << o.name);
    CHECK(names.insert(o.name).second);  // no name twice
    CHECK_FALSE(o.help.empty());
    const std::string value = sampleValue(o);
    CHECK(viaCommandLine(o, value) == value);

    nlohmann::json job = {
        {"program", "p.ngc"}, {"command", "schedule"}, {"tool", "ball"}, {"diameter", "6mm"}};
    job[o.name] = o.kind == OptionKind::Flag ? nlohmann::json(true) : nlohmann::json(value);
    const std::string manifest = dir.write("m.json", nlohmann::json{{"jobs", {job}}}.dump());
    if (o.commandLineOnly) {
      // The batch owns each job's folder and the progress display.
      CHECK_THROWS_WITH(readManifest(manifest), Catch::Matchers::Contains("not a job option"));
      continue;
    }
    const std::vector<ManifestJob> jobs = readManifest(manifest);
    REQUIRE(jobs.size() == 1);
    CHECK(jobs[0].values.at(o.name) == value);
  }
  // The options the manifest refused before the table (they drifted from the command line).
  for (const char* name : {"jerk", "rapid-feed", "material-side"})
    CHECK(findJobOption(name) != nullptr);
}

TEST_CASE("schedule options do not apply to simulate jobs in either front end", "[run]") {
  test::TempFolder dir("option_scope");
  CLI::App app;
  OptionValues values;
  CLI::App* cmd = app.add_subcommand("simulate");
  app::addJobOptions(*cmd, values, JobCommand::Simulate);
  std::vector<std::string> args = {"engage",     "simulate", "p.ngc",        "--tool", "flat",
                                   "--diameter", "6",        "--target-mrr", "5"};
  std::vector<char*> argv;
  for (std::string& a : args)
    argv.push_back(a.data());
  CHECK_THROWS_AS(app.parse(static_cast<int>(argv.size()), argv.data()), CLI::ParseError);

  const std::string own =
      dir.write("own.json", R"({"jobs": [{"program": "p.ngc", "tool": "flat", "diameter": "6",
                                "target-mrr": "5"}]})");
  CHECK_THROWS_WITH(readManifest(own),
                    Catch::Matchers::Contains("\"target-mrr\" applies to schedule jobs only"));
  // Inherited from the defaults, a schedule option does not concern a simulate job.
  const std::string inherited = dir.write("inherited.json", R"({"defaults": {"target-mrr": "5"},
                            "jobs": [{"program": "p.ngc", "tool": "flat", "diameter": "6"}]})");
  const auto jobs = readManifest(inherited);
  REQUIRE(jobs.size() == 1);
  CHECK(jobs[0].values.count("target-mrr") == 0);
}
