#include "apps/JobOptions.h"

#include <map>

namespace engage::app {
namespace {

/// What the help shows as an option's value: its kind, its dimension or its choices.
std::string typeName(const OptionInfo& o) {
  switch (o.kind) {
    case OptionKind::Choice: {
      std::string s;
      for (const std::string& c : o.choices)
        s += (s.empty() ? "" : "|") + c;
      return s;
    }
    case OptionKind::Count:
      return "INT";
    case OptionKind::Fraction:
      return "NUMBER";
    case OptionKind::Flag:
      return "";
    case OptionKind::Text:
      return "TEXT";
    case OptionKind::Quantity:
      break;
  }
  switch (o.dimension) {
    case Dimension::Length:
      return "LENGTH";
    case Dimension::Angle:
      return "ANGLE";
    case Dimension::Feed:
      return "FEED";
    case Dimension::VolumeRate:
      return "RATE";
    case Dimension::Acceleration:
      return "ACCEL";
    case Dimension::Jerk:
      return "JERK";
    case Dimension::SpindleSpeed:
      return "SPEED";
    case Dimension::SpecificEnergy:
      return "ENERGY";
    case Dimension::Force:
      return "FORCE";
    case Dimension::Torque:
      return "TORQUE";
    case Dimension::Power:
      return "POWER";
    default:
      return "QUANTITY";
  }
}

/// The CLI11 side of one table entry bound to `target`. Values are checked by makeJob, the
/// one validation of all front ends, so that its messages are the same everywhere.
CLI::Option* addOption(CLI::App& cmd, const OptionInfo& o, std::string& target) {
  CLI::Option* opt = cmd.add_option("--" + o.name, target, o.help);
  opt->type_name(typeName(o));
  if (!o.defaultText.empty()) opt->capture_default_str();
  return opt;
}

/// A table entry on `cmd`, its text into values[o.name] (its default first; a flag "true"
/// when given). nullptr for a flag.
CLI::Option* addValue(CLI::App& cmd, const OptionInfo& o, OptionValues& values) {
  if (o.kind == OptionKind::Flag) {
    const std::string name = o.name;
    cmd.add_flag_callback(
        "--" + name, [&values, name] { values[name] = "true"; }, o.help);
    return nullptr;
  }
  std::string& target = values[o.name];
  target = o.defaultText;
  return addOption(cmd, o, target);
}

}  // namespace

void addJobOptions(CLI::App& cmd, OptionValues& values, JobCommand command) {
  cmd.add_option("program", values["program"], "G-code program")->required();
  for (const OptionInfo& o : jobOptions()) {
    if (!appliesTo(o, command)) continue;
    CLI::Option* opt = addValue(cmd, o, values);
    if (opt && o.required) opt->required();
  }
}

void addReaderOptions(CLI::App& cmd, OptionValues& values) {
  for (const char* name : {"tool-table", "tool-table-units", "startup-units", "dialect", "machine",
                           "start", "block-delete", "cutter-comp", "max-moves"}) {
    const OptionInfo& o = *findJobOption(name);
    CLI::Option* opt = addValue(cmd, o, values);
    // moves reads the program without makeJob: CLI11 checks the choices there.
    if (opt && o.kind == OptionKind::Choice) opt->check(CLI::IsMember(o.choices).description(""));
  }
}

void addToolOptions(CLI::App& cmd, ToolOptions& t, bool required) {
  const std::map<std::string, std::string*> fields = {{"tool", &t.tool},
                                                      {"diameter", &t.diameter},
                                                      {"corner-radius", &t.cornerRadius},
                                                      {"taper-angle", &t.taperAngle},
                                                      {"tip-angle", &t.tipAngle},
                                                      {"bottom-angle", &t.bottomAngle},
                                                      {"flute-length", &t.fluteLength}};
  for (const OptionInfo& o : jobOptions()) {
    // analyze studies one cutter: a tool library, shanks and holders belong to the job commands.
    if (o.group != OptionGroup::Tool || o.name == "tools" || o.name == "shank-diameter" ||
        o.name == "stickout" || o.name == "holder")
      continue;
    if (o.name == "flutes") {
      cmd.add_option("--flutes", t.flutes, o.help)->type_name(typeName(o))->capture_default_str();
      continue;
    }
    CLI::Option* opt = addOption(cmd, o, *fields.at(o.name));
    // analyze reads the cutter without makeJob: CLI11 checks the choices there.
    if (o.kind == OptionKind::Choice) opt->type_name("NAME")->check(CLI::IsMember(o.choices));
    if (required && o.required) opt->required();
  }
}

}  // namespace engage::app
