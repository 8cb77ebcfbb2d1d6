// Tests of apps/JobOptions.h: each command's help is generated from the option table
// (engine/run/OptionTable.h), so the help of simulate, schedule and analyze lists exactly the
// table's options that apply to them, with the table's text, and mentions no option that
// command lacks.

#include "apps/JobOptions.h"

#include "engine/run/OptionTable.h"

#include <catch2/catch.hpp>

#include <regex>
#include <set>
#include <string>

using namespace engage;

namespace {

/// The long names (without --) of a command's options.
std::set<std::string> optionNames(const CLI::App& cmd) {
  std::set<std::string> names;
  for (const CLI::Option* opt : cmd.get_options())
    for (const std::string& n : opt->get_lnames())
      names.insert(n);
  return names;
}

/// Every `--name` a help text mentions that `cmd` does not take, unless another command's
/// (`schedule's --force-limit`) is named before it.
std::vector<std::string> foreignMentions(const std::string& help, const std::set<std::string>& own,
                                         const std::string& command) {
  std::vector<std::string> foreign;
  static const std::regex mention(R"((\w+'s )?--([a-z][a-z0-9-]*))");
  for (auto it = std::sregex_iterator(help.begin(), help.end(), mention);
       it != std::sregex_iterator(); ++it) {
    const std::string owner = (*it)[1].str();
    if (!owner.empty() && owner != command + "'s ") continue;
    if (!own.count((*it)[2].str())) foreign.push_back((*it)[2].str());
  }
  return foreign;
}

}  // namespace

TEST_CASE("simulate's and schedule's help is the option table's, and names only their options",
          "[apps]") {
  for (const JobCommand command : {JobCommand::Simulate, JobCommand::Schedule}) {
    const std::string name = commandName(command);
    INFO(name);
    CLI::App app;
    OptionValues values;
    CLI::App* cmd = app.add_subcommand(name);
    app::addJobOptions(*cmd, values, command);
    const std::set<std::string> own = optionNames(*cmd);
    std::size_t fromTable = 0;
    for (const OptionInfo& o : jobOptions()) {
      INFO("--" << o.name);
      const CLI::Option* opt = cmd->get_option_no_throw("--" + o.name);
      if (!appliesTo(o, command)) {
        CHECK(opt == nullptr);  // schedule-only options are not simulate's
        continue;
      }
      REQUIRE(opt != nullptr);
      ++fromTable;
      CHECK(opt->get_description() == o.help);
      // A flag shows no value; every other option shows what it takes.
      CHECK(opt->get_type_name().empty() == (o.kind == OptionKind::Flag));
      if (!o.defaultText.empty()) CHECK(opt->get_default_str() == o.defaultText);
      CHECK(foreignMentions(o.help, own, name).empty());
    }
    // Nothing but the table's options, the program and --help.
    CHECK(own.size() == fromTable + 1);
    CHECK(own.count("help") == 1);
  }
}

TEST_CASE("analyze's cutter options are the table's and name only analyze's options", "[apps]") {
  CLI::App app;
  ToolOptions tool;
  CLI::App* cmd = app.add_subcommand("analyze");
  app::addToolOptions(*cmd, tool, false);
  const std::set<std::string> own = optionNames(*cmd);
  for (const std::string& name : own) {
    if (name == "help") continue;
    INFO("--" << name);
    const OptionInfo* o = findJobOption(name);
    REQUIRE(o != nullptr);
    CHECK(o->group == OptionGroup::Tool);
    CHECK(cmd->get_option("--" + name)->get_description() == o->help);
    CHECK(foreignMentions(o->help, own, "analyze").empty());
  }
  // --flutes is a whole number in every command (it was text in one and a number in another).
  CHECK(cmd->get_option("--flutes")->get_type_name() == "INT");
}
