// The interpreter's run loop: one block at a time through its modal groups in LinuxCNC's order,
// parameters and assignments, the tool table, and the source files it reads.

#include "engine/gcode/Interpreter.h"

#include <limits>

namespace engage::gcode {

static std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
    if (end == text.size()) break;
    start = end + 1;
  }
  if (!lines.empty() && lines.back().empty()) lines.pop_back();
  return lines;
}

std::unique_ptr<SourceFile> makeSource(const std::string& name, const std::string& text) {
  auto f = std::make_unique<SourceFile>();
  f->name = name;
  f->folder = std::filesystem::path(name).parent_path().string();
  f->lines = splitLines(text);
  std::string label;
  std::string keyword;
  for (std::size_t i = 0; i < f->lines.size(); ++i) {
    if (gcode::peekOWord(f->lines[i], label, keyword))
      f->labels[label].emplace_back(static_cast<int>(i), keyword);
    else if (gcode::peekProgramNumber(f->lines[i], label))  // an M98 subprogram's start
      f->labels[label].emplace_back(static_cast<int>(i), "program");
  }
  return f;
}

const SourceFile::MacroIndex& SourceFile::macroIndex() const {
  if (macroIndex_) return *macroIndex_;
  auto ix = std::make_unique<MacroIndex>();
  ix->lineNumbers.assign(lines.size(), std::numeric_limits<double>::quiet_NaN());
  ix->loops.assign(lines.size(), {gcode::MacroStatement::None, 0});
  for (std::size_t i = 0; i < lines.size(); ++i) {
    gcode::peekLineNumber(lines[i], ix->lineNumbers[i]);
    ix->loops[i].first = gcode::peekMacroLoop(lines[i], ix->loops[i].second);
  }
  for (const auto& [label, entries] : labels)  // (makeSource found the programs' O lines)
    for (const auto& [line, keyword] : entries)
      if (keyword == "program") ix->programStarts.push_back(line);
  std::sort(ix->programStarts.begin(), ix->programStarts.end());
  macroIndex_ = std::move(ix);
  return *macroIndex_;
}

std::string readFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error("cannot read program '" + path + "': it is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read program '" + path + "': no such file or not readable");
  // Read in pieces up to a bound, so that a device such as /dev/zero cannot fill the memory.
  constexpr std::size_t kMaxBytes = std::size_t(1) << 30;
  std::string text;
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    text.append(buffer.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxBytes)
      throw Error("cannot read program '" + path + "': larger than 1 GiB (is it a program?)");
  }
  if (in.bad()) throw Error("cannot read program '" + path + "': a read failed");
  return text;
}

Interpreter::Interpreter(const ReaderOptions& options) : options_(options) {
  params_.assign(kParameterCount + 1, 0.0);
  params_[5220] = 1.0;  // G54
  if (!options.toolTable.empty()) readToolTable(options.toolTable);
  for (const auto& [tool, diameter] : options.toolDiameters)
    toolDiameters_.emplace(tool, diameter);  // (the tool table's, if any, first)
  pos_ = options.start;
  tool_ = preparedTool_ = options.startTool;
  startKnown_ = options.startKnown;
  if (options.machine) out_.kinematics = options.machine->kinematics;
  tipHeld_ = machineTcp();
  if (const auto& m = options.machine) {
    // The interpreter runs in the machine's coordinates (mm at the start); run() moves the
    // result into G54's frame.
    for (int a = 0; a < 3; ++a) {
      params_[5221 + static_cast<std::size_t>(a)] = m->workOffset[a];
      params_[5161 + static_cast<std::size_t>(a)] = m->g28[a];
      params_[5181 + static_cast<std::size_t>(a)] = m->g30[a];
    }
    pos_ = options.startKnown ? Vector3d(options.start + m->workOffset) : m->start;
    startKnown_ = true;
  }
  // The machine's start-up units: the stored lengths above are mm, held in program units.
  if (options.startInch) {
    convertStoredLengths(1.0 / kInch);
    inch_ = true;
  }
}

Toolpath Interpreter::run(std::unique_ptr<SourceFile> main) {
  files_.push_back(std::move(main));
  out_.files.push_back(files_[0]->name);
  execute();
  if (corner_) failCorner("the end of the program");
  comp_.flush();  // what compensation held back (the program ended with it on)
  out_.inch = inch_;
  if (options_.machine) toWorkFrame(*options_.machine);
  // Grown by doubling: up to twice the room the moves need, held through the whole run.
  out_.moves.shrink_to_fit();
  out_.blocks.shrink_to_fit();
  return std::move(out_);
}

namespace {

/// Haas NGC's #10000-#10999 on their legacy numbers (0: none, stored apart).
int haasLegacy(int n) {
  const int legacy = n - 10000;
  const bool mapped = (legacy >= 100 && legacy <= 199) || (legacy >= 500 && legacy <= 699) ||
                      (legacy >= 800 && legacy <= 999);
  return mapped ? legacy : 0;
}

/// Fanuc's and Haas's timers and date (#3001-#3002, #3011-#3012, #3020-#3028).
bool timerOrDate(int n) {
  return (n >= 3001 && n <= 3002) || (n >= 3011 && n <= 3012) || (n >= 3020 && n <= 3028);
}

[[noreturn]] void needsMachine(int n, const char* what) {
  throw std::out_of_range("expected a variable a simulation can give, found #" + std::to_string(n) +
                          " (" + what + ": only the machine knows it)");
}

}  // namespace

bool Interpreter::systemVariable(int n, double& value) const {
  if (n == 0) {
    value = gcode::vacantValue();
    return true;
  }
  if (n >= 1000 && n <= 1999) needsMachine(n, "an input, output or axis load");
  // Tool offsets as Haas numbers them: lengths, their wear, radii, their wear (program units).
  if (n >= 2001 && n <= 2800) {
    const int tool = (n - 2001) % 200 + 1;
    value = 0.0;  // (the wears)
    if (n <= 2200) {
      const auto it = toolLengths_.find(tool);
      value = it == toolLengths_.end() ? 0.0 : it->second / unit();
    } else if (n >= 2401 && n <= 2600) {
      const auto it = toolDiameters_.find(tool);
      value = it == toolDiameters_.end() ? 0.0 : it->second / 2.0 / unit();
    }
    return true;
  }
  if (timerOrDate(n)) needsMachine(n, "a timer or the date");
  if (n >= 4001 && n <= 4999) {
    // The modal state, as Fanuc numbers its groups (#4001 group 1, ...), and T, F, S.
    const double compensation = comp_.side() == CutterCompensation::Left    ? 41.0
                                : comp_.side() == CutterCompensation::Right ? 42.0
                                                                            : 40.0;
    switch (n) {
      case 4001:
        value = motion_ / 10.0;
        return true;
      case 4002:
        value = plane_ == Plane::XY ? 17.0 : plane_ == Plane::XZ ? 18.0 : 19.0;
        return true;
      case 4003:
        value = incremental_ ? 91.0 : 90.0;
        return true;
      case 4005:
        value = feedMode_ == FeedMode::InverseTime          ? 93.0
                : feedMode_ == FeedMode::UnitsPerRevolution ? 95.0
                                                            : 94.0;
        return true;
      case 4006:
        value = inch_ ? 20.0 : 21.0;
        return true;
      case 4007:
        value = compensation;
        return true;
      case 4010:
        value = retractToR_ ? 99.0 : 98.0;
        return true;
      case 4014:
        value = 53.0 + params_[5220];
        return true;
      case 4109:
        value = feed_ / (feedMode_ == FeedMode::InverseTime ? 1.0 : unit());
        return true;
      case 4119:
        value = spindleSpeed_;
        return true;
      case 4120:
        value = tool_;
        return true;
      default:
        needsMachine(n, "modal information engage does not keep");
    }
  }
  if (n >= 5001 && n <= 5199) {
    const int axis = (n - 1) % 20;      // 0 X, 1 Y, 2 Z
    const int block = (n - 5001) / 20;  // 0 end point, 1 machine, 2 work, 3 skip, 4 tool offset
    if (axis <= 2 && block <= 2) {
      value = block == 1 ? pos_[axis] / unit() : programPosition()[axis];
      return true;
    }
    if (axis <= 2 && block == 3) return false;  // #5061-#5063: the probe's (G38.2)
    if (axis <= 2 && block == 4) {
      value = axis == 2 ? toolLength_ / unit() : 0.0;
      return true;
    }
    if (n >= 5161) return false;  // G28, G30 (as LinuxCNC keeps them)
    needsMachine(n, "an axis state engage does not keep");
  }
  return false;
}

double Interpreter::numbered(int n) const {
  if (fanucLike()) {
    double value = 0.0;
    if (systemVariable(n, value)) return value;
    if (options_.dialect == Dialect::Haas && n >= 10000 && n <= 10999) {
      if (const int legacy = haasLegacy(n)) return params_[static_cast<std::size_t>(legacy)];
      const auto it = extendedVariables_.find(n);
      return it == extendedVariables_.end() ? 0.0 : it->second;
    }
  }
  if (n < 1 || n > kParameterCount)
    throw std::out_of_range("expected a parameter number in 1.." + std::to_string(kParameterCount) +
                            (options_.dialect == Dialect::Haas ? " or 10000..10999" : "") +
                            ", found #" + std::to_string(n));
  if (n >= 5420 && n <= 5422) return programPosition()[n - 5420];
  if (n == 5400) return tool_;
  return params_[static_cast<std::size_t>(n)];
}

bool Interpreter::named(const std::string& name, double& value) const {
  if (!name.empty() && name[0] == '_') {
    if (name == "_x" || name == "_y" || name == "_z") {
      value = programPosition()[name[1] - 'x'];
      return true;
    }
    if (name == "_metric") {
      value = inch_ ? 0.0 : 1.0;
      return true;
    }
    if (name == "_imperial") {
      value = inch_ ? 1.0 : 0.0;
      return true;
    }
    if (name == "_absolute") {
      value = incremental_ ? 0.0 : 1.0;
      return true;
    }
    if (name == "_incremental") {
      value = incremental_ ? 1.0 : 0.0;
      return true;
    }
    if (name == "_feed") {
      value = feed_ / unit();
      return true;
    }
    if (name == "_rpm") {
      value = spindleSpeed_;
      return true;
    }
    if (name == "_current_tool") {
      value = tool_;
      return true;
    }
    if (name == "_call_level") {
      value = static_cast<double>(frames_.size());
      return true;
    }
    if (name == "_task") {
      value = 0.0;
      return true;
    }  // not running under a machine's task
    const auto it = globals_.find(name);
    if (it == globals_.end()) return false;
    value = it->second;
    return true;
  }
  const auto& locals = frames_.empty() ? topLocals_ : frames_.back().locals;
  const auto it = locals.find(name);
  if (it == locals.end()) return false;
  value = it->second;
  return true;
}

void Interpreter::fail(int column, const std::string& message) const {
  throw GcodeError(files_[static_cast<std::size_t>(file_)]->name, line_ + 1, column, message);
}

std::string Interpreter::length(double programValue) const {
  return formatNumber(programValue) + (inch_ ? " in" : " mm");
}

Vector3d Interpreter::workOffset() const {
  const int cs = static_cast<int>(params_[5220]);
  const std::size_t base = static_cast<std::size_t>(5221 + 20 * (cs - 1));
  Vector3d o(params_[base], params_[base + 1], params_[base + 2]);
  if (params_[5210] != 0.0) o += Vector3d(params_[5211], params_[5212], params_[5213]);
  return o * unit();  // offsets are kept in program units, as LinuxCNC does
}

void Interpreter::convertStoredLengths(double factor) {
  auto scale = [&](std::size_t first, std::size_t count) {
    for (std::size_t i = first; i < first + count; ++i)
      params_[i] *= factor;
  };
  scale(5161, 3);
  scale(5181, 3);
  scale(5211, 3);
  for (int cs = 0; cs < 9; ++cs)
    scale(static_cast<std::size_t>(5221 + 20 * cs), 3);
}

void Interpreter::readToolTable(const std::string& path) {
  std::istringstream in(readFile(path));
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t semi = line.find(';');
    if (semi != std::string::npos) line.resize(semi);
    std::istringstream words(line);
    std::string w;
    int tool = -1;
    double length = 0.0, diameter = 0.0;
    while (words >> w) {
      const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
      const double v = std::strtod(w.c_str() + 1, nullptr);
      if (c == 'T' && v >= 0.0 && v <= 1e6) tool = static_cast<int>(v);
      if (c == 'Z') length = v;
      if (c == 'D') diameter = v;
    }
    const double scale = options_.toolTableInch ? kInch : 1.0;
    if (tool >= 0) {
      toolLengths_[tool] = length * scale;
      toolDiameters_[tool] = diameter * scale;
    }
  }
}

void Interpreter::execute(std::size_t returnDepth) {
  bool seenContent = false;
  bool percentMode = false;
  long long executed = 0;
  while (true) {
    const SourceFile& f = *files_[static_cast<std::size_t>(file_)];
    if (line_ >= static_cast<int>(f.lines.size())) {
      if (!frames_.empty()) {
        line_ = static_cast<int>(f.lines.size()) - 1;
        fail(1, frames_.back().m98
                    ? "expected M99 closing the subprogram, found the end of the file"
                    : "expected O-endsub closing the subroutine, found the end of the file");
      }
      return;
    }
    if (++executed > options_.maxExecutedLines)
      fail(1, "expected the program to end, found more than " +
                  std::to_string(options_.maxExecutedLines) + " executed lines (an endless loop?)");
    Block block;
    try {
      block = gcode::parseLine(f.lines[static_cast<std::size_t>(line_)], *this);
    } catch (const ParseFailure& e) {
      fail(e.column, e.message);
    }
    if (block.percent) {
      if (returnDepth > 0) return;  // a '%' inside a subroutine run here ends the program
      if (file_ == 0 && !seenContent) {
        percentMode = true;
        seenContent = true;
        ++line_;
        continue;
      }
      if (percentMode) return;  // the closing '%'
      ++line_;
      continue;
    }
    const bool empty = block.words.empty() && block.assignments.empty() && !block.hasOWord &&
                       block.macro.kind == gcode::MacroStatement::None;
    if (!empty) seenContent = true;
    if (block.blockDelete && options_.blockDelete) {
      ++line_;
      continue;
    }
    if (fanucLike())
      for (const gcode::Assignment& a : block.assignments)
        if (a.name.empty() && a.number == 3000)
          fail(a.column,
               "expected the program to go on, found alarm #3000 = " + formatNumber(a.value) +
                   (block.comments.empty() ? "" : " (" + block.comments[0] + ")") +
                   ": the control stops the program here");
    if (block.macro.kind != gcode::MacroStatement::None) {
      for (const gcode::Assignment& a : block.assignments)  // IF .. THEN's, when it holds
        assign(a);
      macroFlow(block);
      if (frames_.size() < returnDepth) return;
      continue;
    }
    if (std::any_of(block.words.begin(), block.words.end(), [](const gcode::Word& word) {
          return word.letter == 'G' && codeOf(word.value) == G_65;
        })) {
      macroCall(block);
      ++line_;
      continue;
    }
    if (block.hasOWord) {
      controlFlow(block);
      if (frames_.size() < returnDepth) return;
      continue;
    }
    if (profile_) {
      profileBlock(block);
      for (const gcode::Assignment& a : block.assignments)
        assign(a);
      ++line_;
      continue;
    }
    const bool end = executeBlock(block);
    for (const gcode::Assignment& a : block.assignments)
      assign(a);
    if (end) return;
    ++line_;
  }
}

void Interpreter::assign(const gcode::Assignment& a) {
  if (!a.name.empty()) {
    if (a.name[0] == '_')
      globals_[a.name] = a.value;
    else
      (frames_.empty() ? topLocals_ : frames_.back().locals)[a.name] = a.value;
    return;
  }
  if (fanucLike()) {
    const int n = a.number;
    auto readOnly = [&](const char* what) {
      fail(a.column, "expected a variable a program can set, found #" + std::to_string(n) + " (" +
                         what + ") on the left of '='");
    };
    if (n == 0) readOnly("vacant, always");
    if (n >= 1000 && n <= 1999 && !(n >= 1100 && n <= 1155)) readOnly("an input or axis load");
    if (n >= 1100 && n <= 1155) return;  // an output: it moves nothing
    if (n >= 2001 && n <= 2800) readOnly("a tool offset: give it in the tool table");
    if (timerOrDate(n)) readOnly("a timer or the date");
    if (n >= 4001 && n <= 4999) readOnly("the modal state");
    if (n >= 5001 && n <= 5160) readOnly("a position");
    if (n == 3003 || n == 3004 || n == 3006) return;  // single block, feed hold, stop: no motion
    if (options_.dialect == Dialect::Haas && n >= 10000 && n <= 10999) {
      if (const int legacy = haasLegacy(n))
        params_[static_cast<std::size_t>(legacy)] = a.value;
      else
        extendedVariables_[n] = a.value;
      return;
    }
  }
  if (a.number >= 5420 && a.number <= 5422)
    fail(a.column, "expected a writable parameter, found #" + std::to_string(a.number) +
                       " (the current position) on the left of '='");
  if (a.number == 5220 && !(a.value >= 1.0 && a.value <= 9.0 && a.value == std::round(a.value)))
    fail(a.column, "expected a coordinate system 1..9 in #5220, found " + formatNumber(a.value));
  params_[static_cast<std::size_t>(a.number)] = a.value;
}

Interpreter::Words Interpreter::collect(const Block& b) {
  Words w;
  w.corner = b.corner;
  std::map<int, std::pair<int, int>> gGroups;  // group -> (code, column)
  std::map<int, std::pair<int, int>> mGroups;
  for (const gcode::Word& word : b.words) {
    const char L = word.letter;
    if (L == 'G' || L == 'M') {
      const double scaled = word.value * 10.0;
      if (std::abs(scaled - std::round(scaled)) > 1e-6 || word.value < 0.0)
        fail(word.column, std::string("expected a ") + L + " code such as " +
                              (L == 'G' ? "G1 or G5.2" : "M3") + ", found " + L +
                              formatNumber(word.value));
      const int code = codeOf(word.value);
      const int group = L == 'G' ? gGroup(code) : (code % 10 ? -1 : mGroup(code));
      if (group < 0) {
        // An M code engage does not know moves no axis on the machines it reads for (Haas
        // M31/M33 chip conveyor, LinuxCNC's user M100-M199 scripts, ...): taken as inert, and
        // named in the run's warnings. Haas M96/M97 jump within the program: refused.
        if (L == 'M' && code % 10 == 0 && code != 960) {
          out_.inert.push_back({code / 10, file_, line_ + 1});
          continue;
        }
        if (L == 'M' && code == 960)
          fail(word.column,
               "expected an M code engage interprets, found M96 (Haas: a jump on an input, "
               "which only the machine knows)");
        fail(word.column,
             std::string("expected a known ") + L + " code, found " + codeName(L, code));
      }
      if (L == 'M' && code == M_97 && options_.dialect != Dialect::Haas)
        fail(word.column,
             "expected --dialect haas for M97 (a Haas local subprogram call), found the " +
                 dialectName() + " dialect");
      auto& groups = L == 'G' ? gGroups : mGroups;
      const bool coolantPair = L == 'M' && group == 8 && (code == G_7 || code == G_8);
      auto it = groups.find(group);
      // G80 beside a motion code (Fanuc and Haas headers: "G00 G17 G21 G40 G49 G80 G90"),
      // as LinuxCNC takes it: the canned cycle is cancelled and the motion code is the mode.
      if (L == 'G' && group == 1 && it != groups.end() &&
          (code == G_80) != (it->second.first == G_80)) {
        if (code == G_80) continue;
        w.g.erase(std::find(w.g.begin(), w.g.end(), std::pair<int, int>(800, it->second.second)));
        groups.erase(it);
        it = groups.end();
      }
      if (it != groups.end() &&
          !(coolantPair && (it->second.first == G_7 || it->second.first == G_8)) && group != 0 &&
          !(L == 'M' && group == 5))
        fail(word.column, "expected at most one " + std::string(1, L) + " code of modal group " +
                              std::to_string(group) + " per line, found " +
                              codeName(L, it->second.first) + " and " + codeName(L, code));
      if (L == 'G' && group == 0 && it != groups.end() && code != G_53 && it->second.first != G_53)
        fail(word.column, "expected at most one non-modal G code per line, found " +
                              codeName('G', it->second.first) + " and " + codeName('G', code));
      groups[group] = {code, word.column};
      (L == 'G' ? w.g : w.m).emplace_back(code, word.column);
      continue;
    }
    const std::size_t i = slot(L);
    if (w.v[i])
      fail(word.column, std::string("expected one ") + L + " word per line, found a second " + L);
    w.v[i] = word.value;
    w.col[i] = word.column;
  }
  // Rotary and UVW words are read and kept out of the XYZ path; the move is marked so that a
  // simulation without the machine's kinematics can refuse it with the line named.
  for (const char axis : {'A', 'B', 'C', 'U', 'V', 'W'})
    if (w.has(axis)) w.otherAxes = true;
  return w;
}

void Interpreter::refuseUnsupported(const Words& w) const {
  for (const auto& [code, column] : w.g) {
    switch (code) {
      case G_76:
        fail(column,
             "expected a milling motion, found G76 (the lathe threading cycle is not "
             "interpreted)");
      case G_86:
      case G_87:
      case G_88:
        fail(column, "expected one of the canned cycles G73 G81 G82 G83 G85 G89, found " +
                         codeName('G', code));
      case G_43_2:
      case G_52:
      case G_17_1:
      case G_18_1:
      case G_19_1:
        fail(column, "expected a supported G code, found " + codeName('G', code));
      default:
        break;
    }
  }
}

void Interpreter::feedSpindleAndTool(const Words& w) {
  if (const auto g = w.gIn(5))
    feedMode_ = *g == G_93   ? FeedMode::InverseTime
                : *g == G_95 ? FeedMode::UnitsPerRevolution
                             : FeedMode::UnitsPerMinute;
  if (w.has('F')) {
    if (w.get('F') < 0.0)
      fail(w.column('F'), "expected a non-negative F word, found F" + formatNumber(w.get('F')));
    feed_ = feedMode_ == FeedMode::InverseTime ? w.get('F') : w.get('F') * unit();
  }
  if (w.has('S')) {
    if (w.get('S') < 0.0)
      fail(w.column('S'), "expected a non-negative S word, found S" + formatNumber(w.get('S')));
    spindleSpeed_ = w.get('S');
  }
  if (w.has('T')) {
    if (w.get('T') < 0.0)
      fail(w.column('T'), "expected a tool number, found T" + formatNumber(w.get('T')));
    preparedTool_ = static_cast<int>(std::lround(w.get('T')));
  }
  if (w.hasM(M_6) && comp_.on())
    fail(w.mColumn(M_6),
         "expected G40 before a tool change (M6), found cutter radius "
         "compensation on");
  if (w.hasM(M_6)) {
    tool_ = preparedTool_;
    out_.toolLoads.push_back({tool_, fileIndexInOutput(), line_ + 1, out_.moves.size()});
  }
  // A tool change makes LinuxCNC read the position back from the machine: after G40 that is
  // the offset point the tool is at, not the programmed one.
  if ((w.hasM(M_6) || w.hasM(M_61)) && physicalStart_) {
    pos_ = *physicalStart_;
    physicalStart_.reset();
  }
  if (w.hasM(M_61)) {
    if (!w.has('Q')) fail(1, "expected a Q word (tool number) with M61, found none");
    tool_ = static_cast<int>(std::lround(w.get('Q')));
    out_.toolLoads.push_back({tool_, fileIndexInOutput(), line_ + 1, out_.moves.size()});
  }
  if (w.hasM(M_3)) spindleDirection_ = 1;
  if (w.hasM(M_4)) spindleDirection_ = -1;
  if (w.hasM(M_5)) spindleDirection_ = 0;
  if (w.hasM(M_70)) saveModal();
  if (w.hasM(M_72)) restoreModal();
}

void Interpreter::modes(Words& w) {
  if (w.hasG(G_4) && !w.has('P'))
    fail(w.gColumn(G_4), "expected a P word (seconds) with G4, found none");
  if (const auto g = w.gIn(2)) plane_ = *g == G_17 ? Plane::XY : *g == G_18 ? Plane::XZ : Plane::YZ;
  if (const auto g = w.gIn(6)) {
    out_.unitsSet = true;
    const bool inch = *g == G_20;
    if (inch != inch_) {
      convertStoredLengths(inch ? 1.0 / kInch : kInch);
      inch_ = inch;
    }
  }
  // LinuxCNC sets the plane before compensation ("G17 G41 D1" is fine), the rest after.
  const bool compensatingBefore = comp_.on();
  if (const auto g = w.gIn(7)) compensation(*g, w);
  if (comp_.on()) refuseWithCompensation(w, compensatingBefore);
  if (const auto g = w.gIn(8)) {
    // The spindle stays where it is: a longer tool puts the tip lower.
    const double previousLength = toolLength_;
    if (*g == G_43 || *g == G_43_4 || *g == G_43_5 || *g == G_234) {
      const int h = w.has('H') ? static_cast<int>(std::lround(w.get('H'))) : tool_;
      const auto it = toolLengths_.find(h);
      toolLength_ = it == toolLengths_.end() ? 0.0 : it->second;  // mm
    } else if (*g == G_43_1) {
      toolLength_ = w.has('Z') ? w.get('Z') * unit() : 0.0;
    } else {
      toolLength_ = 0.0;
    }
    params_[5403] = toolLength_ / unit();
    // LinuxCNC re-reads the position after a tool change (M6) on the same line, so the
    // shift applies only without one. Before the first move the position is an assumption
    // (the program origin), not where a homed spindle is: shifting it by a 40 mm tool
    // length would start the program 40 mm inside the stock and sweep a phantom plunge.
    if (!w.hasM(M_6) && (startKnown_ || !out_.moves.empty()))
      pos_.z() -= toolLength_ - previousLength;
  }
  if (const auto g = w.gIn(12)) {
    static const std::map<int, int> systems{{G_54, 1},   {G_55, 2},   {G_56, 3},
                                            {G_57, 4},   {G_58, 5},   {G_59, 6},
                                            {G_59_1, 7}, {G_59_2, 8}, {G_59_3, 9}};
    params_[5220] = systems.at(*g);
  }
  // Lathe diameter mode (G7, from this line on): every X word is a diameter, halved here
  // (motions, G92, G10 alike, as LinuxCNC does); arc centre words stay radii.
  if (const auto g = w.gIn(15)) {
    diameterMode_ = *g == G_7;
    if (diameterMode_) markLathe("G7, lathe diameter mode");
  }
  if (diameterMode_ && w.has('X')) w.v[slot('X')] = w.get('X') / 2.0;
  if (const auto g = w.gIn(3)) incremental_ = *g == G_91;
  if (const auto g = w.gIn(4)) arcIncremental_ = *g == G_91_1;
  if (const auto g = w.gIn(10)) retractToR_ = *g == G_99;
  tipModes(w);
}

bool Interpreter::executeBlock(const Block& b) {
  if (b.words.empty()) return false;
  currentBlock_ = &b;
  blockRecorded_ = false;
  Words w = collect(b);

  refuseUnsupported(w);  // first, with a clear word
  feedSpindleAndTool(w);
  modes(w);

  // Non-modal group 0 (other than G4 and G53) consumes the axis words.
  const std::optional<int> g0 = [&]() -> std::optional<int> {
    for (const auto& [code, c] : w.g)
      if (gGroup(code) == 0 && code != G_4 && code != G_53) return code;
    return std::nullopt;
  }();
  const std::optional<int> motionWord = w.gIn(1);
  const bool latheCycleLine = motionWord && isLatheCycle(*motionWord);
  if (latheCycleLine) markLathe(codeName('G', *motionWord) + ", a lathe turning cycle");
  // E is G70's end offset and nothing else: "X1e308" reads as X1 E308, which LinuxCNC refuses.
  if (w.has('E') && !(motionWord && *motionWord == G_70))
    fail(w.column('E'),
         "expected an E word only with G70 (no exponents in G-code numbers: "
         "write 1e5 as 100000), found E" +
             formatNumber(w.get('E')));
  // U and W of a lathe cycle shift its profile; they are not axes there.
  if (latheCycleLine) w.otherAxes = w.has('A') || w.has('B') || w.has('C') || w.has('V');
  // Under G43.5 the tool's axis I, J, K moves the rotary axes as their words would (G68.2's I,
  // J, K are its angles).
  const bool vectorLine = tcpVector_ && !g0 && !w.hasG(G_68_2);
  const bool axisWords = vectorLine && (w.has('I') || w.has('J') || w.has('K'));
  const bool axes = w.has('X') || w.has('Y') || w.has('Z') || w.has('@') || w.has('^') ||
                    w.otherAxes || axisWords;
  // A rotary or UVW word moves its axis only where its target differs from the axis's
  // position (posts write "A0" on every line of 3-axis programs): only then is the move
  // marked. Axis words of G92, G10, G28 and the like set no position here.
  otherAxes_ = false;
  for (const char axis : {'A', 'B', 'C', 'U', 'V', 'W'}) {
    if (!w.has(axis) || (latheCycleLine && (axis == 'U' || axis == 'W')) || g0) continue;
    double& at = otherAxisPosition_[std::string_view("ABCUVW").find(axis)];
    const double to = incremental_ ? at + w.get(axis) : w.get(axis);
    if (to != at) otherAxes_ = true;
    if (to != at && axis <= 'C' && dwo_)
      fail(w.column(axis), std::string("expected G255 (the dynamic work offset off) before ") +
                               "rotary motion, found " + axis + formatNumber(to) +
                               " with G254 in force");
    if (to != at && axis <= 'C' && options_.machine && options_.machine->kinematics.rotary() &&
        options_.machine->kinematics.rotaryAxes().find(axis) == std::string::npos) {
      std::string letters;
      for (const char a : options_.machine->kinematics.rotaryAxes())
        letters += std::string(letters.empty() ? "" : " and ") + a;
      fail(w.column(axis), "expected the rotary axes of this machine only, " + letters + " (" +
                               kinematicsTypeName(options_.machine->kinematics.type) + " in " +
                               options_.machine->name + "), found " + axis);
    }
    at = to;
  }
  if (vectorLine) toolVector(w, motionWord ? *motionWord : motion_);
  if (g0 && motionWord && axes && (*g0 == G_10 || *g0 == G_28 || *g0 == G_30 || *g0 == G_92))
    fail(w.gColumn(*g0), "expected either " + codeName('G', *g0) +
                             " or a motion on this line, found both using the axis words");
  // Machine coordinates are the joints' (Haas: G53, G28 and G30 ignore G254): TCP lets go of
  // the tip for them.
  const bool machineCoords = w.hasG(G_53);
  const bool jointMove =
      tipHeld_ && !machineTcp() && (machineCoords || (g0 && (*g0 == G_28 || *g0 == G_30)));
  if (jointMove) holdTip(false);
  if (g0) nonModal(*g0, w);

  // Motion.
  motionBefore_ = motion_;
  if (motionWord) motion_ = *motionWord;
  if (machineCoords && !(motion_ == G_0 || motion_ == G_1))
    fail(w.gColumn(G_53),
         "expected G0 or G1 with G53, found " + codeName('G', motion_) + " active");
  const bool axesForMotion = axes && !w.hasG(G_43_1) && !w.hasG(G_68_2) &&
                             !(g0 && (*g0 == G_10 || *g0 == G_28 || *g0 == G_30 || *g0 == G_92));
  const bool cycleMode = motion_ == G_73 || (motion_ >= G_81 && motion_ <= G_89);
  if (!cycleMode) cycleInitialValid_ = false;
  if (motionWord && *motionWord == G_80) {
    if (axesForMotion) fail(w.gColumn(G_80), "expected no axis words with G80, found some");
    cycleActive_ = false;
  } else if (axesForMotion || latheCycleLine ||
             (motionWord && (*motionWord == G_2 || *motionWord == G_3 || *motionWord == G_5_3))) {
    if (motion_ < 0 || motion_ == G_80)
      fail(w.column(w.has('X')   ? 'X'
                    : w.has('Y') ? 'Y'
                                 : 'Z'),
           "expected a motion mode (G0, G1, G2, G3, ...) for these axis words, found G80 (none) "
           "active");
    motion(w, motionWord.has_value(), machineCoords);
  } else if (motionWord && *motionWord == G_5_2 && (w.has('P') || w.has('L'))) {
    motion(w, true, false);  // G5.2 opening a NURBS block without axis words
  }
  if (jointMove) holdTip(true);

  // Stop codes, and M98/M99 subprograms (LinuxCNC 2.9, Fanuc and Haas posts), last.
  for (const auto& [code, c] : w.m)
    if (code == M_2 || code == M_30) return true;
  if (w.hasM(M_98)) subprogramCall(w);
  if (w.hasM(M_97)) localSubprogramCall(w);
  if (w.hasM(M_99)) {
    if (frames_.empty()) return true;  // M99 in the main program ends it (as LinuxCNC)
    subprogramReturn(w.mColumn(M_99));
  }
  return false;
}

void Interpreter::saveModal() {
  saved_ = Modal{plane_,      inch_, incremental_,  arcIncremental_, feedMode_,
                 retractToR_, feed_, spindleSpeed_, motion_};
}

void Interpreter::restoreModal() {
  if (!saved_) return;
  const Modal& s = *saved_;
  if (s.inch != inch_) {
    convertStoredLengths(s.inch ? 1.0 / kInch : kInch);
  }
  plane_ = s.plane;
  inch_ = s.inch;
  incremental_ = s.incremental;
  arcIncremental_ = s.arcIncremental;
  feedMode_ = s.feedMode;
  retractToR_ = s.retractToR;
  feed_ = s.feed;
  spindleSpeed_ = s.spindle;
  motion_ = s.motion;
}

void Interpreter::nonModal(int code, const Words& w) {
  const int column = w.gColumn(code);
  switch (code) {
    case G_10: {  // G10
      if (!w.has('L')) fail(column, "expected an L word with G10, found none");
      const int L = static_cast<int>(std::lround(w.get('L')));
      if (L == 1 || L == 10 || L == 11) return;  // tool table edits: no effect on the path
      if (L != 2 && L != 20)
        fail(w.column('L'), "expected G10 L1, L2, L10, L11 or L20, found L" + std::to_string(L));
      if (w.has('R') && w.get('R') != 0.0)
        fail(w.column('R'),
             "expected no XY rotation (R) in G10 L2, found R" + formatNumber(w.get('R')));
      int p = w.has('P') ? static_cast<int>(std::lround(w.get('P'))) : 0;
      if (p == 0) p = static_cast<int>(params_[5220]);
      if (p < 1 || p > 9)
        fail(w.column('P'),
             "expected a coordinate system P1..P9 (or P0 for the active one), found P" +
                 std::to_string(p));
      const std::size_t base = static_cast<std::size_t>(5221 + 20 * (p - 1));
      for (int a = 0; a < 3; ++a) {
        const char letter = static_cast<char>('X' + a);
        if (!w.has(letter)) continue;
        if (L == 2) {
          params_[base + static_cast<std::size_t>(a)] = w.get(letter);
        } else {
          // L20: the current position becomes the given value in system p.
          double g92 = params_[5210] != 0.0 ? params_[5211 + static_cast<std::size_t>(a)] : 0.0;
          params_[base + static_cast<std::size_t>(a)] = pos_[a] / unit() - g92 - w.get(letter);
        }
      }
      return;
    }
    case G_28:
    case G_30: {  // G28 / G30: through the optional intermediate point to home
      const std::size_t home = code == G_28 ? 5161 : 5181;
      const bool any = w.has('X') || w.has('Y') || w.has('Z');
      if (any) {
        const Vector3d intermediate = target(w, false);
        emitLinear(MoveKind::Rapid, intermediate);
      }
      Vector3d end = pos_;
      for (int a = 0; a < 3; ++a)
        if (!any || w.has(static_cast<char>('X' + a)))
          end[a] =
              params_[home + static_cast<std::size_t>(a)] * unit() - (a == 2 ? toolLength_ : 0.0);
      emitLinear(MoveKind::Rapid, end);
      return;
    }
    case G_28_1:
    case G_30_1: {  // store the current machine position as home
      const std::size_t home = code == G_28_1 ? 5161 : 5181;
      for (int a = 0; a < 3; ++a)
        params_[home + static_cast<std::size_t>(a)] =
            (pos_[a] + (a == 2 ? toolLength_ : 0.0)) / unit();
      return;
    }
    case G_92: {  // G92: offsets so that the current point takes the given values
      // (A rotary or UVW word alone, "G92 A0", offsets an axis engage does not move: nothing.)
      if (!(w.has('X') || w.has('Y') || w.has('Z') || w.otherAxes))
        fail(column, "expected axis words with G92, found none");
      const int cs = static_cast<int>(params_[5220]);
      const std::size_t base = static_cast<std::size_t>(5221 + 20 * (cs - 1));
      for (int a = 0; a < 3; ++a) {
        const char letter = static_cast<char>('X' + a);
        if (params_[5210] == 0.0) params_[5211 + static_cast<std::size_t>(a)] = 0.0;
        if (w.has(letter))
          params_[5211 + static_cast<std::size_t>(a)] =
              pos_[a] / unit() - params_[base + static_cast<std::size_t>(a)] - w.get(letter);
      }
      params_[5210] = 1.0;
      return;
    }
    case G_92_1:  // G92.1: cancel and zero
      params_[5210] = 0.0;
      params_[5211] = params_[5212] = params_[5213] = 0.0;
      return;
    case G_92_2:
      params_[5210] = 0.0;
      return;  // G92.2: suspend, keep values
    case G_92_3:
      params_[5210] = 1.0;
      return;  // G92.3: restore
    default:
      return;
  }
}

int Interpreter::recordBlock() const {
  if (!blockRecorded_) {
    SourceBlock sb;
    sb.file = fileIndexInOutput();
    sb.line = line_ + 1;
    if (currentBlock_)
      for (const gcode::Word& w : currentBlock_->words)
        sb.words.push_back(WordSpan{w.letter, w.column - 1, w.endColumn - 1});
    out_.blocks.push_back(std::move(sb));
    blockRecorded_ = true;
  }
  return static_cast<int>(out_.blocks.size()) - 1;
}

int Interpreter::fileIndexInOutput() const {
  const std::string& name = files_[static_cast<std::size_t>(file_)]->name;
  for (std::size_t i = 0; i < out_.files.size(); ++i)
    if (out_.files[i] == name) return static_cast<int>(i);
  return 0;
}

Move Interpreter::base(MoveKind kind) const {
  if (out_.moves.size() >= options_.maxMoves)
    fail(1, "expected at most " + std::to_string(options_.maxMoves) + " moves in a program" +
                options_.maxMovesWhy + ", found more");
  Move m;
  m.kind = kind;
  m.start = physicalStart_ ? *physicalStart_ : pos_;
  physicalStart_.reset();
  m.plane = plane_;
  m.spindleRpm = spindleDirection_ * spindleSpeed_;
  m.tool = tool_;
  m.file = fileIndexInOutput();
  m.line = line_ + 1;
  m.inch = inch_;
  m.incremental = incremental_;
  m.absoluteArcCenters = !arcIncremental_;
  m.feedMode = feedMode_;
  if (feedMode_ == FeedMode::InverseTime && kind != MoveKind::Rapid && feed_ > 0.0)
    m.minutes = 1.0 / feed_;
  m.workOffset = workOffset();
  m.block = recordBlock();
  m.otherAxes = otherAxes_;
  m.rotaryStart = out_.moves.empty() ? Eigen::Vector3d::Zero() : out_.moves.back().rotaryEnd;
  m.rotaryEnd = rotaryNow();
  m.tipHeld = tipHeld_;
  m.axisVector = tcpVector_;
  m.frame = frame_;
  return m;
}

std::size_t Interpreter::slot(char c) {
  return c == '@' ? 26 : c == '^' ? 27 : static_cast<std::size_t>(c - 'A');
}

}  // namespace engage::gcode
