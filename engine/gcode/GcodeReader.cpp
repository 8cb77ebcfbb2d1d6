#include "engine/gcode/GcodeReader.h"

#include "engine/gcode/CutterComp.h"

#include "engine/gcode/GcodeError.h"
#include "engine/gcode/LatheCycle.h"
#include "engine/gcode/LineParser.h"
#include "engine/gcode/Spline.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace engage {
namespace {

using Eigen::Vector3d;
using gcode::Block;
using gcode::ParseFailure;

constexpr double kInch = 25.4;
constexpr double kHalfPi = 1.57079632679489661923;
constexpr int kParameterCount = 5602;  // #1 .. #5602, as LinuxCNC
/// Spline flattening tolerance, mm (Toolpath.h promises 0.001 mm).
constexpr double kSplineTolerance = 0.001;
/// LinuxCNC's arc radius-mismatch tolerances (TOLERANCE_MM, TOLERANCE_INCH).
constexpr double kArcToleranceMm = 0.005;
constexpr double kArcToleranceInch = 0.0005;
/// Work limits of one canned-cycle block (pecks, L repeats): beyond them a typo, not a program.
constexpr int kMaxPecks = 100000;
/// LinuxCNC's G83/G73 rapid clearance above the last peck: 0.010 in.
constexpr double kPeckClearanceInch = 0.010;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// G or M number times ten, e.g. G5.2 -> 52, G90.1 -> 901.
int codeOf(double value) {
  return static_cast<int>(std::lround(value * 10.0));
}
std::string codeName(char letter, int code) {
  std::string s(1, letter);
  s += std::to_string(code / 10);
  if (code % 10) s += "." + std::to_string(code % 10);
  return s;
}

/// Modal group of a G code (x10), -1 if unknown.
int gGroup(int g) {
  switch (g) {
    case 0:
    case 10:
    case 20:
    case 30:
    case 50:
    case 51:
    case 52:
    case 53:
    case 330:
    case 331:
    case 382:
    case 383:
    case 384:
    case 385:
    case 700:
    case 710:
    case 711:
    case 712:
    case 720:
    case 721:
    case 722:
    case 730:
    case 760:
    case 800:
    case 810:
    case 820:
    case 830:
    case 840:
    case 850:
    case 860:
    case 870:
    case 880:
    case 890:
      return 1;
    case 170:
    case 171:
    case 180:
    case 181:
    case 190:
    case 191:
      return 2;
    case 900:
    case 910:
      return 3;
    case 901:
    case 911:
      return 4;
    case 930:
    case 940:
    case 950:
      return 5;
    case 200:
    case 210:
      return 6;
    case 400:
    case 410:
    case 411:
    case 420:
    case 421:
      return 7;
    case 430:
    case 431:
    case 432:
    case 490:
      return 8;
    case 980:
    case 990:
      return 10;
    case 540:
    case 550:
    case 560:
    case 570:
    case 580:
    case 590:
    case 591:
    case 592:
    case 593:
      return 12;
    case 610:
    case 611:
    case 640:
      return 13;
    case 960:
    case 970:
      return 14;
    case 70:
    case 80:
      return 15;
    case 40:
    case 100:
    case 280:
    case 281:
    case 300:
    case 301:
    case 530:
    case 920:
    case 921:
    case 922:
    case 923:
    case 520:
      return 0;
    default:
      return -1;
  }
}

/// G70, G71, G71.1, G71.2, G72, G72.1, G72.2 (x10).
bool isLatheCycle(int g) {
  return g == 700 || (g >= 710 && g <= 712) || (g >= 720 && g <= 722);
}

int mGroup(int m) {
  switch (m / 10) {
    case 0:
    case 1:
    case 2:
    case 30:
    case 60:
    case 98:
    case 99:
      return 4;
    case 6:
    case 61:
      return 6;
    case 3:
    case 4:
    case 5:
      return 7;
    case 7:
    case 8:
    case 9:
      return 8;
    case 48:
    case 49:
    case 50:
    case 51:
    case 52:
    case 53:
      return 9;
    case 62:
    case 63:
    case 64:
    case 65:
    case 66:
    case 67:
    case 68:
      return 5;
    case 70:
    case 71:
    case 72:
    case 73:
      return 10;
    default:
      return -1;
  }
}

/// One loaded source file with its O-word index.
struct SourceFile {
  std::string name;
  std::string folder;
  std::vector<std::string> lines;
  /// label -> (line index, keyword), in line order.
  std::unordered_map<std::string, std::vector<std::pair<int, std::string>>> labels;
};

std::vector<std::string> splitLines(const std::string& text) {
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

/// The interpreter: modal state, parameters, call stack, and the moves it emits.
class Interpreter final : public gcode::ParameterSource {
 public:
  Interpreter(const ReaderOptions& options) : options_(options) {
    params_.assign(kParameterCount + 1, 0.0);
    params_[5220] = 1.0;  // G54
    if (!options.toolTable.empty()) readToolTable(options.toolTable);
    for (const auto& [tool, diameter] : options.toolDiameters)
      toolDiameters_.emplace(tool, diameter);  // (the tool table's, if any, first)
    pos_ = options.start;
    tool_ = preparedTool_ = options.startTool;
    startKnown_ = options.startKnown;
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
  }

  Toolpath run(std::unique_ptr<SourceFile> main) {
    files_.push_back(std::move(main));
    out_.files.push_back(files_[0]->name);
    execute();
    comp_.flush();  // what compensation held back (the program ended with it on)
    out_.inch = inch_;
    if (options_.machine) toWorkFrame(*options_.machine);
    // Grown by doubling: CAMotics' tiger's 67,424 moves held room for 131,072 (12 MB more
    // through the whole run).
    out_.moves.shrink_to_fit();
    out_.blocks.shrink_to_fit();
    return std::move(out_);
  }

  /// With a machine: every move within its travel, then moved from the machine's coordinates
  /// into G54's frame.
  void toWorkFrame(const MachineSetup& m) {
    for (const Move& move : out_.moves) {
      if (!m.limited) break;
      for (int a = 0; a < 3; ++a) {
        const double v = move.end[a];
        if (v >= m.travelMin[a] - 1e-6 && v <= m.travelMax[a] + 1e-6) continue;
        auto mm = [](double x) { return num(x) + " mm"; };
        throw GcodeError(out_.files[static_cast<std::size_t>(move.file)], move.line, 1,
                         "expected moves within the travel of the machine (" + m.name + ": " +
                             std::string(1, static_cast<char>('X' + a)) + " " + mm(m.travelMin[a]) +
                             " to " + mm(m.travelMax[a]) + ", machine coordinates), found one to " +
                             std::string(1, static_cast<char>('X' + a)) + " " + mm(v));
      }
    }
    for (Move& move : out_.moves) {
      move.start -= m.workOffset;
      move.end -= m.workOffset;
      move.workOffset -= m.workOffset;
      if (move.kind == MoveKind::Arc) move.center -= m.workOffset;
      for (Vector3d& p : move.points)
        p -= m.workOffset;
    }
  }

  // ParameterSource
  double numbered(int n) const override {
    if (n < 1 || n > kParameterCount)
      throw std::out_of_range("expected a parameter number in 1.." +
                              std::to_string(kParameterCount) + ", found #" + std::to_string(n));
    if (n >= 5420 && n <= 5422) return programPosition()[n - 5420];
    if (n == 5400) return tool_;
    return params_[static_cast<std::size_t>(n)];
  }
  bool named(const std::string& name, double& value) const override {
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

 private:
  /// A lathe cycle's profile being read: its last point (program units) and segments.
  struct LatheProfile {
    double x, z;
    std::vector<gcode::LatheSegment> segments;
  };
  struct Frame {
    int file;
    int returnLine;
    std::array<double, 30> saved{};
    std::unordered_map<std::string, double> locals;
    /// An M98 call (ends with M99, shares the caller's parameters): where its subprogram
    /// starts and how many more times it runs (M98 L).
    bool m98 = false;
    int startFile = 0, startLine = 0;
    long repeats = 0;
  };

  // ---------------------------------------------------------------- errors
  [[noreturn]] void fail(int column, const std::string& message) const {
    throw GcodeError(files_[static_cast<std::size_t>(file_)]->name, line_ + 1, column, message);
  }

  // ---------------------------------------------------------------- units and frames
  double unit() const { return inch_ ? kInch : 1.0; }
  /// A length in program units with its unit, for messages.
  std::string length(double programValue) const {
    return num(programValue) + (inch_ ? " in" : " mm");
  }
  Vector3d workOffset() const {
    const int cs = static_cast<int>(params_[5220]);
    const std::size_t base = static_cast<std::size_t>(5221 + 20 * (cs - 1));
    Vector3d o(params_[base], params_[base + 1], params_[base + 2]);
    if (params_[5210] != 0.0) o += Vector3d(params_[5211], params_[5212], params_[5213]);
    return o * unit();  // offsets are kept in program units, as LinuxCNC does
  }
  Vector3d programPosition() const { return (pos_ - workOffset()) / unit(); }
  Vector3d toMachine(const Vector3d& program) const { return program * unit() + workOffset(); }

  /// Converts every stored length parameter when G20/G21 changes the program units.
  void convertStoredLengths(double factor) {
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

  // ---------------------------------------------------------------- tool table
  void readToolTable(const std::string& path) {
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

  // ---------------------------------------------------------------- the run loop
  /// Runs lines from line_ on. With `returnDepth` > 0 it runs a call whose frame is at that
  /// depth and returns when the call does.
  void execute(std::size_t returnDepth = 0) {
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
                    std::to_string(options_.maxExecutedLines) +
                    " executed lines (an endless loop?)");
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
      const bool empty = block.words.empty() && block.assignments.empty() && !block.hasOWord;
      if (!empty) seenContent = true;
      if (block.blockDelete && options_.blockDelete) {
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

  void assign(const gcode::Assignment& a) {
    if (!a.name.empty()) {
      if (a.name[0] == '_')
        globals_[a.name] = a.value;
      else
        (frames_.empty() ? topLocals_ : frames_.back().locals)[a.name] = a.value;
      return;
    }
    if (a.number >= 5420 && a.number <= 5422)
      fail(a.column, "expected a writable parameter, found #" + std::to_string(a.number) +
                         " (the current position) on the left of '='");
    if (a.number == 5220 && !(a.value >= 1.0 && a.value <= 9.0 && a.value == std::round(a.value)))
      fail(a.column, "expected a coordinate system 1..9 in #5220, found " + num(a.value));
    params_[static_cast<std::size_t>(a.number)] = a.value;
  }

  // ---------------------------------------------------------------- O-words
  const std::vector<std::pair<int, std::string>>& labelEntries(const std::string& label,
                                                               int column) const {
    const SourceFile& f = *files_[static_cast<std::size_t>(file_)];
    const auto it = f.labels.find(label);
    if (it == f.labels.end()) fail(column, "expected a known O-word label, found o" + label);
    return it->second;
  }
  /// First entry of `label` after line `from` whose keyword is one of `keywords`.
  int findForward(const std::string& label, int from, std::initializer_list<const char*> keywords,
                  int column, const char* expected) const {
    for (const auto& [line, kw] : labelEntries(label, column))
      if (line > from)
        for (const char* k : keywords)
          if (kw == k) return line;
    fail(column, std::string("expected ") + expected + " for o" + label + ", found none");
  }
  int findBackward(const std::string& label, int from, const char* keyword, int column) const {
    const auto& entries = labelEntries(label, column);
    for (auto it = entries.rbegin(); it != entries.rend(); ++it)
      if (it->first < from && it->second == keyword) return it->first;
    fail(column, std::string("expected O-") + keyword + " opening o" + label + ", found none");
  }
  bool hasKeywordBefore(const std::string& label, int from, const char* keyword) const {
    const SourceFile& f = *files_[static_cast<std::size_t>(file_)];
    const auto it = f.labels.find(label);
    if (it == f.labels.end()) return false;
    for (const auto& [line, kw] : it->second)
      if (line < from && kw == keyword) return true;
    return false;
  }

  void controlFlow(const Block& b) {
    const gcode::OWord& o = b.oword;
    const std::string& k = o.keyword;
    const int c = o.column;
    if (k == "sub") {
      line_ = findForward(o.label, line_, {"endsub"}, c, "O-endsub") + 1;
    } else if (k == "endsub" || k == "return") {
      if (frames_.empty() || frames_.back().m98)
        fail(c, "expected to be inside a called subroutine, found O-" + k);
      if (!o.arguments.empty()) globals_["_value"] = o.arguments[0];
      Frame f = std::move(frames_.back());
      frames_.pop_back();
      for (std::size_t i = 0; i < 30; ++i)
        params_[i + 1] = f.saved[i];
      file_ = f.file;
      line_ = f.returnLine;
    } else if (k == "call") {
      call(o);
    } else if (k == "do") {
      ++line_;
    } else if (k == "while") {
      const bool cond = o.arguments[0] != 0.0;
      if (hasKeywordBefore(o.label, line_, "do")) {
        // The tail of a do-while loop.
        line_ = cond ? findBackward(o.label, line_, "do", c) + 1 : line_ + 1;
      } else {
        line_ = cond ? line_ + 1 : findForward(o.label, line_, {"endwhile"}, c, "O-endwhile") + 1;
      }
    } else if (k == "endwhile") {
      line_ = findBackward(o.label, line_, "while", c);
    } else if (k == "if") {
      if (o.arguments[0] != 0.0) {
        ++line_;
      } else {
        nextBranch(o.label, c);
      }
    } else if (k == "elseif") {
      // Reached from inside a taken branch, or from nextBranch evaluating it.
      line_ = findForward(o.label, line_, {"endif"}, c, "O-endif") + 1;
    } else if (k == "else") {
      line_ = findForward(o.label, line_, {"endif"}, c, "O-endif") + 1;
    } else if (k == "endif") {
      ++line_;
    } else if (k == "repeat") {
      const long count = std::lround(o.arguments[0]);
      const auto key = std::make_pair(file_, line_);
      if (count <= 0) {
        repeats_.erase(key);
        line_ = findForward(o.label, line_, {"endrepeat"}, c, "O-endrepeat") + 1;
      } else {
        repeats_[key] = count;
        ++line_;
      }
    } else if (k == "endrepeat") {
      const int start = findBackward(o.label, line_, "repeat", c);
      const auto key = std::make_pair(file_, start);
      auto it = repeats_.find(key);
      if (it != repeats_.end() && --it->second > 0) {
        line_ = start + 1;
      } else {
        if (it != repeats_.end()) repeats_.erase(it);
        ++line_;
      }
    } else if (k == "break" || k == "continue") {
      loopJump(o.label, k == "break", c);
    }
  }

  /// From a false if/elseif at line_, move to the next branch that runs.
  void nextBranch(const std::string& label, int column) {
    int at = line_;
    for (;;) {
      const int next = findForward(label, at, {"elseif", "else", "endif"}, column, "O-endif");
      const std::string& text =
          files_[static_cast<std::size_t>(file_)]->lines[static_cast<std::size_t>(next)];
      std::string l;
      std::string kw;
      gcode::peekOWord(text, l, kw);
      if (kw == "elseif") {
        const int saved = line_;
        line_ = next;
        Block b;
        try {
          b = gcode::parseLine(text, *this);
        } catch (const ParseFailure& e) {
          fail(e.column, e.message);
        }
        line_ = saved;
        if (b.oword.arguments[0] != 0.0) {
          line_ = next + 1;
          return;
        }
        at = next;
        continue;
      }
      line_ = next + 1;  // into the else branch, or past endif
      return;
    }
  }

  void loopJump(const std::string& label, bool isBreak, int column) {
    // The loop this label belongs to: while/endwhile, do/while, repeat/endrepeat.
    const auto& entries = labelEntries(label, column);
    int open = -1;
    std::string openKw;
    for (const auto& [line, kw] : entries)
      if (line < line_ && (kw == "while" || kw == "do" || kw == "repeat")) {
        open = line;
        openKw = kw;
      }
    if (open < 0)
      fail(column, "expected to be inside an o" + label + " loop, found O-" +
                       std::string(isBreak ? "break" : "continue"));
    if (openKw == "repeat") {
      const int close = findForward(label, line_, {"endrepeat"}, column, "O-endrepeat");
      if (isBreak) {
        repeats_.erase(std::make_pair(file_, open));
        line_ = close + 1;
      } else {
        line_ = close;
      }
    } else if (openKw == "do") {
      const int close = findForward(label, line_, {"while"}, column, "O-while");
      line_ = isBreak ? close + 1 : close;
    } else {
      const int close = findForward(label, line_, {"endwhile"}, column, "O-endwhile");
      line_ = isBreak ? close + 1 : open;
    }
  }

  /// The file and line where `label` opens as `keyword` ("sub": an O-sub; "program": an M98
  /// subprogram's O line): in this file, the main file, files already read, then `fileName`
  /// (if not empty) beside the main file or on the search path, read in. Such a file without
  /// the label starts at its first line (line -1) when `wholeFile`. {-1, -1}: found nowhere.
  std::pair<int, int> findLabel(const std::string& label, const char* keyword,
                                const std::string& fileName, bool wholeFile) {
    int targetFile = -1;
    int targetLine = -1;
    auto findIn = [&](int fi) {
      const SourceFile& f = *files_[static_cast<std::size_t>(fi)];
      const auto it = f.labels.find(label);
      if (it == f.labels.end()) return false;
      for (const auto& [line, kw] : it->second)
        if (kw == keyword) {
          targetFile = fi;
          targetLine = line;
          return true;
        }
      return false;
    };
    if (findIn(file_) || findIn(0)) return {targetFile, targetLine};
    for (int fi = 1; fi < static_cast<int>(files_.size()); ++fi)
      if (findIn(fi)) return {targetFile, targetLine};
    if (fileName.empty()) return {-1, -1};
    std::vector<std::string> folders{files_[0]->folder};
    folders.insert(folders.end(), options_.subroutinePath.begin(), options_.subroutinePath.end());
    for (const std::string& folder : folders) {
      const std::filesystem::path p = folder.empty() ? std::filesystem::path(fileName)
                                                     : std::filesystem::path(folder) / fileName;
      std::error_code ec;
      if (!std::filesystem::is_regular_file(p, ec)) continue;
      files_.push_back(makeSource(p.string(), readFile(p.string())));
      out_.files.push_back(p.string());
      const int fi = static_cast<int>(files_.size()) - 1;
      if (findIn(fi)) return {targetFile, targetLine};
      return wholeFile ? std::pair<int, int>{fi, -1} : std::pair<int, int>{-1, -1};
    }
    return {-1, -1};
  }

  /// The file and line of subroutine `label`'s O-sub (findLabel; a <name> label may be in
  /// name.ngc).
  std::pair<int, int> findSubroutine(const std::string& label, int column) {
    const bool named = label.size() > 2 && label.front() == '<';
    const auto found =
        findLabel(label, "sub", named ? label.substr(1, label.size() - 2) + ".ngc" : "", false);
    if (found.first < 0)
      fail(column, "expected a subroutine o" + label + " (in this program or as " +
                       (label.front() == '<' ? label.substr(1, label.size() - 2) : label) +
                       ".ngc beside it), found none");
    return found;
  }

  void call(const gcode::OWord& o) {
    const auto [targetFile, targetLine] = findSubroutine(o.label, o.column);
    if (frames_.size() >= 64)
      fail(o.column, "expected subroutine calls nested at most 64 deep, found deeper recursion");
    Frame f;
    f.file = file_;
    f.returnLine = line_ + 1;
    for (std::size_t i = 0; i < 30; ++i) {
      f.saved[i] = params_[i + 1];
      params_[i + 1] = i < o.arguments.size() ? o.arguments[i] : 0.0;
    }
    frames_.push_back(std::move(f));
    file_ = targetFile;
    line_ = targetLine + 1;
  }

  // ---------------------------------------------------------------- one block
  /// Slot of a word letter: A-Z, then '@' (polar radius) and '^' (polar angle).
  static std::size_t slot(char c) {
    return c == '@' ? 26 : c == '^' ? 27 : static_cast<std::size_t>(c - 'A');
  }
  struct Words {
    std::array<std::optional<double>, 28> v;
    std::array<int, 28> col{};
    std::vector<std::pair<int, int>> g;  ///< (code x10, column)
    bool otherAxes = false;              ///< A, B, C, U, V or W words on the line
    std::vector<std::pair<int, int>> m;
    bool has(char c) const { return v[slot(c)].has_value(); }
    double get(char c) const { return *v[slot(c)]; }
    int column(char c) const { return col[slot(c)]; }
    std::optional<int> gIn(int group) const {
      for (const auto& [code, c] : g)
        if (gGroup(code) == group) return code;
      return std::nullopt;
    }
    bool hasG(int code) const {
      for (const auto& [x, c] : g)
        if (x == code) return true;
      return false;
    }
    bool hasM(int code) const {
      for (const auto& [x, c] : m)
        if (x == code) return true;
      return false;
    }
    int gColumn(int code) const {
      for (const auto& [x, c] : g)
        if (x == code) return c;
      return 1;
    }
    int mColumn(int code) const {
      for (const auto& [x, c] : m)
        if (x == code) return c;
      return 1;
    }
  };

  Words collect(const Block& b) {
    Words w;
    std::map<int, std::pair<int, int>> gGroups;  // group -> (code, column)
    std::map<int, std::pair<int, int>> mGroups;
    for (const gcode::Word& word : b.words) {
      const char L = word.letter;
      if (L == 'G' || L == 'M') {
        const double scaled = word.value * 10.0;
        if (std::abs(scaled - std::round(scaled)) > 1e-6 || word.value < 0.0)
          fail(word.column, std::string("expected a ") + L + " code such as " +
                                (L == 'G' ? "G1 or G5.2" : "M3") + ", found " + L +
                                num(word.value));
        const int code = codeOf(word.value);
        const int group = L == 'G' ? gGroup(code) : (code % 10 ? -1 : mGroup(code));
        if (group < 0) {
          if (L == 'M' && code >= 1000 && code <= 1990)
            fail(word.column, "expected a built-in M code, found " + codeName('M', code) +
                                  " (user M codes M100-M199 are not interpreted)");
          fail(word.column,
               std::string("expected a known ") + L + " code, found " + codeName(L, code));
        }
        auto& groups = L == 'G' ? gGroups : mGroups;
        const bool coolantPair = L == 'M' && group == 8 && (code == 70 || code == 80);
        auto it = groups.find(group);
        // G80 beside a motion code (Fanuc and Haas headers: "G00 G17 G21 G40 G49 G80 G90"),
        // as LinuxCNC takes it: the canned cycle is cancelled and the motion code is the mode.
        if (L == 'G' && group == 1 && it != groups.end() &&
            (code == 800) != (it->second.first == 800)) {
          if (code == 800) continue;
          w.g.erase(std::find(w.g.begin(), w.g.end(), std::pair<int, int>(800, it->second.second)));
          groups.erase(it);
          it = groups.end();
        }
        if (it != groups.end() &&
            !(coolantPair && (it->second.first == 70 || it->second.first == 80)) && group != 0 &&
            !(L == 'M' && group == 5))
          fail(word.column, "expected at most one " + std::string(1, L) + " code of modal group " +
                                std::to_string(group) + " per line, found " +
                                codeName(L, it->second.first) + " and " + codeName(L, code));
        if (L == 'G' && group == 0 && it != groups.end() && code != 530 && it->second.first != 530)
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
    // Rotary and UVW words are read and kept out of the XYZ path; the move is marked so that
    // a 3-axis simulation can refuse it with the line named.
    for (const char axis : {'A', 'B', 'C', 'U', 'V', 'W'})
      if (w.has(axis)) w.otherAxes = true;
    return w;
  }

  /// Executes a block in LinuxCNC's order; true when the program ends.
  bool executeBlock(const Block& b) {
    if (b.words.empty()) return false;
    currentBlock_ = &b;
    blockRecorded_ = false;
    Words w = collect(b);

    // Unsupported codes first, with a clear word.
    for (const auto& [code, column] : w.g) {
      switch (code) {
        case 760:
          fail(column,
               "expected a milling motion, found G76 (the lathe threading cycle is not "
               "interpreted)");
        case 860:
        case 870:
        case 880:
          fail(column, "expected one of the canned cycles G73 G81 G82 G83 G85 G89, found " +
                           codeName('G', code));
        case 432:
        case 520:
        case 171:
        case 181:
        case 191:
          fail(column, "expected a supported G code, found " + codeName('G', code));
        default:
          break;
      }
    }

    // Feed mode, F, S, T, M6/M61, spindle.
    if (const auto g = w.gIn(5))
      feedMode_ = *g == 930   ? FeedMode::InverseTime
                  : *g == 950 ? FeedMode::UnitsPerRevolution
                              : FeedMode::UnitsPerMinute;
    if (w.has('F')) {
      if (w.get('F') < 0.0)
        fail(w.column('F'), "expected a non-negative F word, found F" + num(w.get('F')));
      feed_ = feedMode_ == FeedMode::InverseTime ? w.get('F') : w.get('F') * unit();
    }
    if (w.has('S')) {
      if (w.get('S') < 0.0)
        fail(w.column('S'), "expected a non-negative S word, found S" + num(w.get('S')));
      spindleSpeed_ = w.get('S');
    }
    if (w.has('T')) {
      if (w.get('T') < 0.0)
        fail(w.column('T'), "expected a tool number, found T" + num(w.get('T')));
      preparedTool_ = static_cast<int>(std::lround(w.get('T')));
    }
    if (w.hasM(60) && comp_.on())
      fail(w.mColumn(60),
           "expected G40 before a tool change (M6), found cutter radius "
           "compensation on");
    if (w.hasM(60)) tool_ = preparedTool_;
    // A tool change makes LinuxCNC read the position back from the machine: after G40 that is
    // the offset point the tool is at, not the programmed one.
    if ((w.hasM(60) || w.hasM(610)) && physicalStart_) {
      pos_ = *physicalStart_;
      physicalStart_.reset();
    }
    if (w.hasM(610)) {
      if (!w.has('Q')) fail(1, "expected a Q word (tool number) with M61, found none");
      tool_ = static_cast<int>(std::lround(w.get('Q')));
    }
    if (w.hasM(30)) spindleDirection_ = 1;
    if (w.hasM(40)) spindleDirection_ = -1;
    if (w.hasM(50)) spindleDirection_ = 0;
    if (w.hasM(700)) saveModal();
    if (w.hasM(720)) restoreModal();

    // Dwell, plane, units, compensation, tool length, coordinate system, modes.
    if (w.hasG(40) && !w.has('P'))
      fail(w.gColumn(40), "expected a P word (seconds) with G4, found none");
    if (const auto g = w.gIn(2)) plane_ = *g == 170 ? Plane::XY : *g == 180 ? Plane::XZ : Plane::YZ;
    if (const auto g = w.gIn(6)) {
      const bool inch = *g == 200;
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
      if (*g == 430) {
        const int h = w.has('H') ? static_cast<int>(std::lround(w.get('H'))) : tool_;
        const auto it = toolLengths_.find(h);
        toolLength_ = it == toolLengths_.end() ? 0.0 : it->second;  // mm
      } else if (*g == 431) {
        toolLength_ = w.has('Z') ? w.get('Z') * unit() : 0.0;
      } else {
        toolLength_ = 0.0;
      }
      params_[5403] = toolLength_ / unit();
      // LinuxCNC re-reads the position after a tool change (M6) on the same line, so the
      // shift applies only without one. Before the first move the position is an assumption
      // (the program origin), not where a homed spindle is: shifting it by a 40 mm tool
      // length would start the program 40 mm inside the stock and sweep a phantom plunge.
      if (!w.hasM(60) && (startKnown_ || !out_.moves.empty()))
        pos_.z() -= toolLength_ - previousLength;
    }
    if (const auto g = w.gIn(12)) {
      static const std::map<int, int> systems{{540, 1}, {550, 2}, {560, 3}, {570, 4}, {580, 5},
                                              {590, 6}, {591, 7}, {592, 8}, {593, 9}};
      params_[5220] = systems.at(*g);
    }
    // Lathe diameter mode (G7, from this line on): every X word is a diameter, halved here
    // (motions, G92, G10 alike, as LinuxCNC does); arc centre words stay radii.
    if (const auto g = w.gIn(15)) {
      diameterMode_ = *g == 70;
      if (diameterMode_) markLathe("G7, lathe diameter mode");
    }
    if (diameterMode_ && w.has('X')) w.v[slot('X')] = w.get('X') / 2.0;
    if (const auto g = w.gIn(3)) incremental_ = *g == 910;
    if (const auto g = w.gIn(4)) arcIncremental_ = *g == 911;
    if (const auto g = w.gIn(10)) retractToR_ = *g == 990;

    // Non-modal group 0 (other than G4 and G53) consumes the axis words.
    const std::optional<int> g0 = [&]() -> std::optional<int> {
      for (const auto& [code, c] : w.g)
        if (gGroup(code) == 0 && code != 40 && code != 530) return code;
      return std::nullopt;
    }();
    const std::optional<int> motionWord = w.gIn(1);
    const bool latheCycleLine = motionWord && isLatheCycle(*motionWord);
    if (latheCycleLine) markLathe(codeName('G', *motionWord) + ", a lathe turning cycle");
    // E is G70's end offset and nothing else: "X1e308" reads as X1 E308, which LinuxCNC refuses.
    if (w.has('E') && !(motionWord && *motionWord == 700))
      fail(w.column('E'),
           "expected an E word only with G70 (no exponents in G-code numbers: "
           "write 1e5 as 100000), found E" +
               num(w.get('E')));
    // U and W of a lathe cycle shift its profile; they are not axes there.
    if (latheCycleLine) w.otherAxes = w.has('A') || w.has('B') || w.has('C') || w.has('V');
    const bool axes =
        w.has('X') || w.has('Y') || w.has('Z') || w.has('@') || w.has('^') || w.otherAxes;
    // A rotary or UVW word moves its axis only where its target differs from the axis's
    // position (posts write "A0" on every line of 3-axis programs): only then is the move
    // marked. Axis words of G92, G10, G28 and the like set no position here.
    otherAxes_ = false;
    for (const char axis : {'A', 'B', 'C', 'U', 'V', 'W'}) {
      if (!w.has(axis) || (latheCycleLine && (axis == 'U' || axis == 'W')) || g0) continue;
      double& at = otherAxisPosition_[std::string_view("ABCUVW").find(axis)];
      const double to = incremental_ ? at + w.get(axis) : w.get(axis);
      if (to != at) otherAxes_ = true;
      at = to;
    }
    if (g0 && motionWord && axes && (*g0 == 100 || *g0 == 280 || *g0 == 300 || *g0 == 920))
      fail(w.gColumn(*g0), "expected either " + codeName('G', *g0) +
                               " or a motion on this line, found both using the axis words");
    if (g0) nonModal(*g0, w);

    // Motion.
    motionBefore_ = motion_;
    if (motionWord) motion_ = *motionWord;
    const bool machineCoords = w.hasG(530);
    if (machineCoords && !(motion_ == 0 || motion_ == 10))
      fail(w.gColumn(530),
           "expected G0 or G1 with G53, found " + codeName('G', motion_) + " active");
    const bool axesForMotion =
        axes && !w.hasG(431) && !(g0 && (*g0 == 100 || *g0 == 280 || *g0 == 300 || *g0 == 920));
    const bool cycleMode = motion_ == 730 || (motion_ >= 810 && motion_ <= 890);
    if (!cycleMode) cycleInitialValid_ = false;
    if (motionWord && *motionWord == 800) {
      if (axesForMotion) fail(w.gColumn(800), "expected no axis words with G80, found some");
      cycleActive_ = false;
    } else if (axesForMotion || latheCycleLine ||
               (motionWord && (*motionWord == 20 || *motionWord == 30 || *motionWord == 53))) {
      if (motion_ < 0 || motion_ == 800)
        fail(w.column(w.has('X')   ? 'X'
                      : w.has('Y') ? 'Y'
                                   : 'Z'),
             "expected a motion mode (G0, G1, G2, G3, ...) for these axis words, found G80 (none) "
             "active");
      motion(w, motionWord.has_value(), machineCoords);
    } else if (motionWord && *motionWord == 52 && (w.has('P') || w.has('L'))) {
      motion(w, true, false);  // G5.2 opening a NURBS block without axis words
    }

    // Stop codes, and M98/M99 subprograms (LinuxCNC 2.9, Fanuc and Haas posts), last.
    for (const auto& [code, c] : w.m)
      if (code == 20 || code == 300) return true;
    if (w.hasM(980)) subprogramCall(w);
    if (w.hasM(990)) {
      if (frames_.empty()) return true;  // M99 in the main program ends it (as LinuxCNC)
      subprogramReturn(w.mColumn(990));
    }
    return false;
  }

  /// M98 P<program> [L<times>]: runs O<program> (in this program, or <program>.ngc beside
  /// it) until its M99, L times. With --dialect fanuc and no L, a P of more than four digits
  /// carries the count in its leading digits (P30001234: O1234 three times).
  void subprogramCall(const Words& w) {
    const int column = w.mColumn(980);
    if (!w.has('P')) fail(column, "expected a P word (the program number) with M98, found none");
    const double pv = w.get('P');
    if (!(pv >= 0.0) || std::abs(pv - std::round(pv)) > 1e-9 || pv > 1e9)
      fail(w.column('P'), "expected a program number P with M98, found P" + num(pv));
    long program = std::lround(pv);
    long times = 1;
    if (w.has('L')) {
      const double l = w.get('L');
      if (!(l >= 0.0) || std::abs(l - std::round(l)) > 1e-9 || l > 1e9)
        fail(w.column('L'), "expected a repeat count L with M98, found L" + num(l));
      times = std::lround(l);
    } else if (options_.dialect == Dialect::Fanuc && program > 9999) {
      times = program / 10000;
      program %= 10000;
    }
    if (times == 0) return;
    const std::string label = std::to_string(program);
    const auto [targetFile, targetLine] = findLabel(label, "program", label + ".ngc", true);
    if (targetFile < 0)
      fail(w.column('P'), "expected a subprogram O" + label + " (in this program or as " + label +
                              ".ngc beside it), found none");
    if (frames_.size() >= 64)
      fail(column, "expected subprogram calls nested at most 64 deep, found deeper recursion");
    Frame f;
    f.file = file_;
    f.returnLine = line_ + 1;
    f.m98 = true;
    f.startFile = targetFile;
    f.startLine = targetLine;
    f.repeats = times - 1;
    frames_.push_back(std::move(f));
    file_ = targetFile;
    line_ = targetLine;  // (the run loop goes on with the next line)
  }

  /// M99: back after the M98 that called, or once more from the subprogram's start.
  void subprogramReturn(int column) {
    Frame& f = frames_.back();
    if (!f.m98)
      fail(column,
           "expected M99 only in a subprogram an M98 called, found it in an O-word "
           "subroutine (end that with O-endsub)");
    if (f.repeats > 0) {
      --f.repeats;
      file_ = f.startFile;
      line_ = f.startLine;
      return;
    }
    file_ = f.file;
    line_ = f.returnLine - 1;
    frames_.pop_back();
  }

  void saveModal() {
    saved_ = Modal{plane_,      inch_, incremental_,  arcIncremental_, feedMode_,
                   retractToR_, feed_, spindleSpeed_, motion_};
  }
  void restoreModal() {
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

  void nonModal(int code, const Words& w) {
    const int column = w.gColumn(code);
    switch (code) {
      case 100: {  // G10
        if (!w.has('L')) fail(column, "expected an L word with G10, found none");
        const int L = static_cast<int>(std::lround(w.get('L')));
        if (L == 1 || L == 10 || L == 11) return;  // tool table edits: no effect on the path
        if (L != 2 && L != 20)
          fail(w.column('L'), "expected G10 L1, L2, L10, L11 or L20, found L" + std::to_string(L));
        if (w.has('R') && w.get('R') != 0.0)
          fail(w.column('R'), "expected no XY rotation (R) in G10 L2, found R" + num(w.get('R')));
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
      case 280:
      case 300: {  // G28 / G30: through the optional intermediate point to home
        const std::size_t home = code == 280 ? 5161 : 5181;
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
      case 281:
      case 301: {  // store the current machine position as home
        const std::size_t home = code == 281 ? 5161 : 5181;
        for (int a = 0; a < 3; ++a)
          params_[home + static_cast<std::size_t>(a)] =
              (pos_[a] + (a == 2 ? toolLength_ : 0.0)) / unit();
        return;
      }
      case 920: {  // G92: offsets so that the current point takes the given values
        if (!(w.has('X') || w.has('Y') || w.has('Z')))
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
      case 921:  // G92.1: cancel and zero
        params_[5210] = 0.0;
        params_[5211] = params_[5212] = params_[5213] = 0.0;
        return;
      case 922:
        params_[5210] = 0.0;
        return;  // G92.2: suspend, keep values
      case 923:
        params_[5210] = 1.0;
        return;  // G92.3: restore
      default:
        return;
    }
  }

  // ---------------------------------------------------------------- motion
  /// Target of the axis words in machine coordinates (mm).
  Vector3d target(const Words& w, bool machineCoords) const {
    Vector3d end = pos_;
    const Vector3d program = programPosition();
    const Vector3d offset = workOffset();
    for (int a = 0; a < 3; ++a) {
      const char letter = static_cast<char>('X' + a);
      if (!w.has(letter)) continue;
      const double v = w.get(letter);
      if (machineCoords)
        // G53 positions the spindle's gauge line; the tip is one tool length below it.
        end[a] = v * unit() - (a == 2 ? toolLength_ : 0.0);
      else if (incremental_)
        end[a] = (program[a] + v) * unit() + offset[a];
      else
        end[a] = v * unit() + offset[a];
    }
    if (w.has('@') || w.has('^')) {
      const Eigen::Vector2d xy = polarTarget(w, Eigen::Vector2d(program.x(), program.y()));
      end.x() = xy.x() * unit() + offset.x();
      end.y() = xy.y() * unit() + offset.y();
    }
    return end;
  }

  /// LinuxCNC polar words in the XY plane, program units: @ radius and ^ angle (degrees)
  /// about the program origin; absolute in G90, added to the current radius and angle in G91.
  Eigen::Vector2d polarTarget(const Words& w, const Eigen::Vector2d& current) const {
    const char* clash = w.has('X') ? "X" : w.has('Y') ? "Y" : nullptr;
    if (clash)
      fail(w.column(clash[0]),
           std::string("expected either polar (@, ^) or cartesian words, found both @/^ and ") +
               clash);
    if (plane_ != Plane::XY)
      fail(w.column(w.has('@') ? '@' : '^'),
           "expected the XY plane (G17) for polar words, found " + std::string(planeName(plane_)));
    const double r0 = current.norm();
    const double a0 = std::atan2(current.y(), current.x());
    const double at = w.has('@') ? w.get('@') : 0.0;
    const double angle = w.has('^') ? w.get('^') * kHalfPi / 90.0 : 0.0;
    const double r = incremental_ ? r0 + at : (w.has('@') ? at : r0);
    const double a = incremental_ ? a0 + angle : (w.has('^') ? angle : a0);
    return Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
  }

  Move base(MoveKind kind) const {
    if (out_.moves.size() >= options_.maxMoves)
      fail(1, "expected at most " + std::to_string(options_.maxMoves) +
                  " moves in a program, found more");
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
    m.workOffset = workOffset();
    m.block = recordBlock();
    m.otherAxes = otherAxes_;
    return m;
  }

  /// Index of the current executed line in Toolpath::blocks, recording it on first use.
  int recordBlock() const {
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
  int fileIndexInOutput() const {
    const std::string& name = files_[static_cast<std::size_t>(file_)]->name;
    for (std::size_t i = 0; i < out_.files.size(); ++i)
      if (out_.files[i] == name) return static_cast<int>(i);
    return 0;
  }

  /// Feed of a move of `length` mm under the active feed mode, mm/min.
  double feedFor(double length, const Words& w, int column) {
    switch (feedMode_) {
      case FeedMode::InverseTime:
        if (!w.has('F'))
          fail(column,
               "expected an F word on every feed move in inverse-time mode (G93), found none");
        if (feed_ <= 0.0) fail(w.column('F'), "expected a positive inverse-time F word, found F0");
        return length * feed_;
      case FeedMode::UnitsPerRevolution:
        if (spindleSpeed_ <= 0.0)
          fail(column, "expected a spindle speed S for feed per revolution (G95), found S0");
        if (feed_ <= 0.0)
          fail(column, "expected a positive F word before the first feed move, found F0");
        return feed_ * spindleSpeed_;
      case FeedMode::UnitsPerMinute:
        break;
    }
    if (feed_ <= 0.0)
      fail(column, "expected a positive F word before the first feed move, found feed 0");
    return feed_;
  }

  void emitLinear(MoveKind kind, const Vector3d& end, double feed = 0.0) {
    Move m = base(kind);
    m.end = end;
    m.feed = kind == MoveKind::Rapid ? 0.0 : feed;
    pos_ = end;
    out_.moves.push_back(std::move(m));
  }

  void motion(const Words& w, bool explicitMotion, bool machineCoords) {
    const int column = explicitMotion ? w.gColumn(motion_) : 1;
    if (comp_.on() && motion_ != 0 && motion_ != 10 && motion_ != 20 && motion_ != 30)
      fail(column, "expected G0, G1, G2 or G3 with cutter radius compensation on, found " +
                       codeName('G', motion_));
    switch (motion_) {
      case 0:
        arcNotAllowed_ = false;
        if (comp_.offsetting()) {
          compensated(MoveKind::Rapid, target(w, false), 0.0, column);
          return;
        }
        emitLinear(MoveKind::Rapid, target(w, machineCoords));
        return;
      case 10: {
        arcNotAllowed_ = false;
        const Vector3d end = target(w, machineCoords);
        const double feed = feedFor((end - pos_).norm(), w, column);
        if (comp_.offsetting()) {
          compensated(MoveKind::Line, end, feed, column);
          return;
        }
        emitLinear(MoveKind::Line, end, feed);
        return;
      }
      case 20:
      case 30:
        if (arcNotAllowed_)
          fail(column,
               "expected a straight move just after G40 (LinuxCNC ends compensation "
               "with one), found " +
                   codeName('G', motion_));
        arc(w, column);
        return;
      case 50:
      case 51:
        spline(w, column);
        return;
      case 52:
        nurbsPoint(w, column);
        return;
      case 53:
        nurbsEnd(w, column);
        return;
      case 730:
      case 810:
      case 820:
      case 830:
      case 850:
      case 890:
        cycle(w, column, explicitMotion);
        return;
      case 330:
      case 331:
        synchronised(w, column);
        return;
      case 382:
      case 383:
      case 384:
      case 385:
        probe(w, column);
        return;
      default:
        if (isLatheCycle(motion_)) {
          latheCycle(w, column);
          return;
        }
        fail(column, "expected a supported motion, found " + codeName('G', motion_));
    }
  }

  /// G33 (spindle-synchronised line) and G33.1 (rigid tapping: in to the target and back
  /// out to the start). The feed is the pitch K times the spindle speed.
  void synchronised(const Words& w, int column) {
    const std::string name = codeName('G', motion_);
    if (!w.has('K'))
      fail(column,
           "expected a K word (distance per spindle revolution) with " + name + ", found none");
    if (!(w.get('K') > 0.0))
      fail(w.column('K'),
           "expected a positive K word with " + name + ", found K" + num(w.get('K')));
    if (!(spindleSpeed_ > 0.0))
      fail(column, "expected a spindle speed S > 0 for " + name + " (feed = K x S), found S0");
    const double feed = w.get('K') * unit() * spindleSpeed_;
    const Vector3d start = pos_;
    emitLinear(MoveKind::Line, target(w, false), feed);
    out_.moves.back().feedSource = FeedSource::Spindle;
    if (motion_ == 331) {
      emitLinear(MoveKind::Line, start, feed);
      out_.moves.back().feedSource = FeedSource::Spindle;
    }
  }

  /// Note the first sign that the program is for a lathe.
  void markLathe(const std::string& what) {
    if (out_.latheLine != 0) return;
    out_.latheLine = line_ + 1;
    out_.lathe = what;
  }

  /// G70-G72, LinuxCNC's lathe cycles: a rapid to the cycle's start point, the profile read
  /// from subroutine Q (readLatheProfile), and the cycle's moves (LatheCycle.h) run as
  /// G0/G1/G2/G3 blocks of the cycle's line, with absolute arc centres.
  void latheCycle(const Words& w, int column) {
    const std::string name = codeName('G', motion_);
    if (!w.has('Q'))
      fail(column,
           "expected a Q word (the profile's subroutine number) with " + name + ", found none");
    if (incremental_)
      fail(column, "expected absolute distance mode (G90) for " + name + ", found G91");
    if (plane_ != Plane::XZ)
      fail(column, "expected the XZ plane (G18) for " + name + ", found the " + planeName(plane_) +
                       " plane");
    gcode::LatheCycle cycle;
    cycle.code = motion_ / 10;
    cycle.variant = motion_ % 10;
    const Vector3d here = programPosition();
    cycle.start = {w.has('Z') ? w.get('Z') : here.z(), w.has('X') ? w.get('X') : here.x()};
    const auto word = [&](char c, double& v) {
      if (w.has(c)) v = w.get(c);
    };
    word('D', cycle.d);
    word('E', cycle.e);
    word('P', cycle.passes);
    word('I', cycle.depth);
    word('R', cycle.retract);
    word('U', cycle.u);
    word('W', cycle.w);
    // The rapid to the start point comes first, then the profile is read.
    const Vector3d startPoint = target(w, false);
    if ((startPoint - pos_).cwiseAbs().maxCoeff() > 1e-9) emitLinear(MoveKind::Rapid, startPoint);
    const std::vector<gcode::LatheSegment> profile =
        readLatheProfile(std::to_string(std::lround(w.get('Q'))), w.column('Q'), cycle.start);

    std::vector<gcode::LatheMove> moves;
    try {
      moves = gcode::latheCycleMoves(profile, cycle);
    } catch (const gcode::LatheCycleError& e) {
      fail(column, std::string(e.what()) + " in " + name);
    }
    const bool arcIncremental = arcIncremental_;
    arcIncremental_ = false;
    for (const gcode::LatheMove& m : moves) {
      Words step;
      step.v[slot('X')] = m.end.imag();
      step.v[slot('Z')] = m.end.real();
      if (m.kind == gcode::LatheMoveKind::Arc) {
        step.v[slot('I')] = m.centre.imag();
        step.v[slot('K')] = m.centre.real();
        motion_ = m.ccw ? 30 : 20;
        try {
          arc(step, column);
        } catch (const GcodeError& e) {
          // Name the arc's maker: the program has no such arc line.
          throw GcodeError(e.file(), e.line(), e.column(),
                           e.message() + " (an arc that " + name + " made from its profile)");
        }
      } else {
        motion_ = m.kind == gcode::LatheMoveKind::Rapid ? 0 : 10;
        const Vector3d end = target(step, false);
        if ((end - pos_).cwiseAbs().maxCoeff() <= 1e-9) continue;  // LinuxCNC's zero moves
        if (motion_ == 0)
          emitLinear(MoveKind::Rapid, end);
        else
          emitLinear(MoveKind::Line, end, feedFor((end - pos_).norm(), step, column));
      }
    }
    arcIncremental_ = arcIncremental;
  }

  /// The profile of a lathe cycle from `start` (program units): subroutine `label` called
  /// and run as LinuxCNC does, its control lines and parameter assignments executed, its
  /// motion lines read into segments instead of moving (the position that #<_x>, #<_z> and
  /// #5420-#5422 report follows the profile's points meanwhile).
  std::vector<gcode::LatheSegment> readLatheProfile(const std::string& label, int column,
                                                    gcode::LathePoint start) {
    const int callerLine = line_;
    const Vector3d machinePosition = pos_;
    profile_ = LatheProfile{start.imag(), start.real(), {}};
    gcode::OWord o;
    o.label = label;
    o.keyword = "call";
    o.column = column;
    call(o);
    const std::size_t depth = frames_.size();
    execute(depth);
    if (frames_.size() >= depth)  // it stopped inside the subroutine (a closing '%')
      fail(1, "expected O-endsub closing the profile subroutine o" + label +
                  ", found the end of the program");
    std::vector<gcode::LatheSegment> segments = std::move(profile_->segments);
    profile_.reset();
    pos_ = machinePosition;
    line_ = callerLine;
    return segments;
  }

  /// One motion line of a lathe profile: a segment from the last point to its X and Z (or
  /// the last point moved by U and W), with a corner finish after it for an A (fillet) or
  /// C (chamfer) word.
  void profileBlock(const Block& b) {
    if (b.words.empty()) return;
    Words pw = collect(b);
    LatheProfile& p = *profile_;
    const gcode::LathePoint start{p.z, p.x};
    gcode::LathePoint end = start;
    for (const auto& [absolute, relative] : {std::pair{'X', 'U'}, std::pair{'Z', 'W'}}) {
      if (pw.has(relative) && pw.has(absolute))
        fail(pw.column(relative), std::string("expected either ") + absolute + " or " + relative +
                                      " on a line of a lathe profile, found both");
    }
    if (pw.has('U')) end.imag(end.imag() + pw.get('U') / (diameterMode_ ? 2.0 : 1.0));
    if (pw.has('X')) end.imag(pw.get('X') / (diameterMode_ ? 2.0 : 1.0));
    if (pw.has('W')) end.real(end.real() + pw.get('W'));
    if (pw.has('Z')) end.real(pw.get('Z'));
    gcode::LathePoint centre{pw.has('K') ? pw.get('K') : 0.0, pw.has('I') ? pw.get('I') : 0.0};
    if (const std::optional<int> g = pw.gIn(1)) motion_ = *g;  // they stay in effect
    if (end == start) return;
    gcode::LatheSegment s;
    s.start = start;
    s.end = end;
    if (motion_ == 20 || motion_ == 30) {
      if (pw.has('R')) {
        if (pw.has('I') || pw.has('K'))
          fail(pw.column('R'), "expected either R or I/K for an arc, found both");
        // The centre on the side G2/G3 and the sign of R put it.
        const double r = pw.get('R');
        const gcode::LathePoint chord = end - start;
        const double h2 = (r * r - std::norm(chord) / 4) / std::norm(chord);
        if (h2 < -1e-9)
          fail(pw.column('R'), "expected an arc radius that reaches the end point (at least " +
                                   length(std::abs(chord) / 2.0) + "), found R" + num(r));
        const gcode::LathePoint d =
            gcode::LathePoint(0.0, 1.0) * std::sqrt(std::max(h2, 0.0)) * chord;
        centre = (start + end) / 2.0 + (motion_ == 30 ? d : -d);
      } else {
        if (!pw.has('I') && !pw.has('K'))
          fail(1, "expected I or K (or R) for an arc of the lathe profile, found neither");
        if (arcIncremental_) centre += start;
      }
      s.arc = true;
      s.ccw = motion_ == 30;
      s.centre = centre;
    }
    // (as LinuxCNC) other motions add nothing; the next segment starts at their end
    if (motion_ == 0 || motion_ == 10 || motion_ == 20 || motion_ == 30) {
      p.segments.push_back(s);
      if (pw.has('A') && pw.has('C'))
        fail(pw.column('C'),
             "expected either A (fillet) or C (chamfer) at a profile corner, "
             "found both");
      if (pw.has('A') || pw.has('C')) {
        gcode::LatheSegment corner;
        corner.arc = pw.has('A');
        corner.start = corner.end = corner.centre = end;
        corner.corner = pw.get(corner.arc ? 'A' : 'C');
        p.segments.push_back(corner);
      }
    }
    p.x = end.imag();
    p.z = end.real();
    const Vector3d program = programPosition();
    pos_ = toMachine(Vector3d(p.x, program.y(), p.z));
  }

  /// G38.2-G38.5. Without a part to touch, the probe runs to its target and, as LinuxCNC's
  /// stand-alone interpreter has it, stops 0.254 mm (0.010 in) back towards the start:
  /// engage makes that back-off a feed move (a real probe also stops just past contact).
  /// #5061-#5063 hold the target (program coordinates), #5070 = 0 (no contact), so probing loops
  /// end as they do there.
  void probe(const Words& w, int column) {
    const std::string name = codeName('G', motion_);
    if (feedMode_ == FeedMode::InverseTime)
      fail(column,
           "expected units-per-minute feed (G94) for " + name + ", found inverse time (G93)");
    const Vector3d start = pos_;
    const Vector3d end = target(w, false);
    const double distance = (end - start).norm();
    // LinuxCNC 2.9 refuses a zero-length probe only where no contact is an error (G38.2,
    // G38.4); its stand-alone interpreter backs off any probe of non-zero length.
    const bool mustTouch = motion_ == 382 || motion_ == 384;
    if (distance == 0.0 && mustTouch)
      fail(column,
           "expected a probe target away from the start point, found the start point "
           "itself");
    if (distance > 0.0) {
      const double feed = feedFor(distance, w, column);
      const double backoff = inch_ ? 0.01 * kInch : 0.254;  // mm
      emitLinear(MoveKind::Line, end, feed);
      out_.moves.back().feedSource = FeedSource::Probe;
      emitLinear(MoveKind::Line, end + (start - end) * (backoff / distance), feed);
      out_.moves.back().feedSource = FeedSource::Probe;
    }
    const Vector3d program = (end - workOffset()) / unit();
    for (int a = 0; a < 3; ++a)
      params_[5061 + static_cast<std::size_t>(a)] = program[a];
    params_[5070] = 0.0;
  }

  void arc(const Words& w, int column) {
    const PlaneAxes ax = planeAxes(plane_);
    const Vector3d end = target(w, false);
    const bool ccw = motion_ == 30;
    const double tol = (inch_ ? kArcToleranceInch : kArcToleranceMm) * unit();
    Move m = base(MoveKind::Arc);
    m.end = end;
    int turns = 1;
    if (w.has('P')) {
      const double p = w.get('P');
      if (p < 1.0 || std::abs(p - std::round(p)) > 1e-9)
        fail(w.column('P'), "expected a whole number of turns P >= 1, found P" + num(p));
      turns = static_cast<int>(std::lround(p));
    }
    m.turns = ccw ? turns : -turns;
    const char offPlane = plane_ == Plane::XY ? 'K' : plane_ == Plane::XZ ? 'J' : 'I';
    // grbl ignores the off-plane word (FreeCAD's grbl post writes K0 on G17 arcs).
    if (w.has(offPlane) && options_.dialect != Dialect::Grbl)
      fail(w.column(offPlane), std::string("expected ") + ax.ia + "/" + ax.ib +
                                   " centre words for an arc in the " + planeName(plane_) +
                                   " plane, found " + offPlane +
                                   " (--dialect grbl ignores it, as grbl does)");
    const double sa = pos_[ax.a], sb = pos_[ax.b], ea = end[ax.a], eb = end[ax.b];
    double ca = 0.0, cb = 0.0;
    if (w.has('R')) {
      if (w.has(ax.ia) || w.has(ax.ib))
        fail(w.column('R'), std::string("expected either R or ") + ax.ia + "/" + ax.ib +
                                " for an arc, found both");
      const double radius = w.get('R') * unit();
      if (std::abs(ea - sa) < 1e-12 && std::abs(eb - sb) < 1e-12)
        fail(w.column('R'),
             "expected an R-form arc to end elsewhere than it starts (use I/J for a full circle), "
             "found the same point");
      const double ma = (sa + ea) / 2.0, mb = (sb + eb) / 2.0;
      double half = std::hypot(ea - ma, eb - mb);
      const double r = std::abs(radius);
      if (half - r > tol)
        fail(w.column('R'), "expected an arc radius that reaches the end point (at least " +
                                length(half / unit()) + "), found R" + num(w.get('R')));
      if (half / r > 1.0 - 1e-12) half = r;
      const double chordAngle = std::atan2(eb - sb, ea - sa);
      const double theta = ((!ccw && radius > 0.0) || (ccw && radius < 0.0)) ? chordAngle - kHalfPi
                                                                             : chordAngle + kHalfPi;
      const double offset = r * std::cos(std::asin(half / r));
      ca = ma + offset * std::cos(theta);
      cb = mb + offset * std::sin(theta);
    } else {
      if (!w.has(ax.ia) && !w.has(ax.ib))
        fail(column, std::string("expected ") + ax.ia + "/" + ax.ib +
                         " centre words or R for an arc in the " + planeName(plane_) +
                         " plane, found neither");
      const Vector3d offset = workOffset();
      const double ia = w.has(ax.ia) ? w.get(ax.ia) * unit() : 0.0;
      const double ib = w.has(ax.ib) ? w.get(ax.ib) * unit() : 0.0;
      if (arcIncremental_) {
        ca = sa + ia;
        cb = sb + ib;
      } else {
        ca = ia + offset[ax.a];
        cb = ib + offset[ax.b];
      }
      const double r1 = std::hypot(sa - ca, sb - cb);
      const double r2 = std::hypot(ea - ca, eb - cb);
      if (r1 < 0.1 * tol || r2 < 0.1 * tol)
        fail(column, "expected an arc of non-zero radius, found radius 0");
      if (std::abs(r1 - r2) > tol)
        fail(column, "expected the arc's end on its circle (radius to start " +
                         length(r1 / unit()) + ", to end " + length(r2 / unit()) +
                         "), found them " + length(std::abs(r1 - r2) / unit()) +
                         " apart, more than " + length(tol / unit()));
    }
    m.center = pos_;
    m.center[ax.a] = ca;
    m.center[ax.b] = cb;
    m.start = pos_;  // (the programmed start, also right after G40: arcs are refused there)
    pos_ = end;
    m.feed = feedFor(moveLength(m), w, column);
    if (comp_.offsetting()) {
      try {
        comp_.arc(std::move(m));
      } catch (const CompensationError& e) {
        fail(column, e.what());
      }
      return;
    }
    out_.moves.push_back(std::move(m));
  }

  /// A straight move while compensation offsets the path: it goes to `end` as programmed (in
  /// pos_), the tool to its offset (CutterComp.h).
  void compensated(MoveKind kind, const Vector3d& end, double feed, int column) {
    Move m = base(kind);
    m.start = pos_;
    m.end = end;
    m.feed = feed;
    pos_ = end;
    try {
      comp_.straight(std::move(m));
    } catch (const CompensationError& e) {
      fail(column, e.what());
    }
  }

  /// G40, G41, G41.1, G42, G42.1 (`code` x 10).
  void compensation(int code, const Words& w) {
    const int column = w.gColumn(code);
    if (code == 400) {
      const bool offsetting = comp_.offsetting();
      Vector3d at;
      try {
        at = comp_.off();
      } catch (const CompensationError& e) {
        fail(column, e.what());
      }
      if (offsetting) {
        physicalStart_ = at;
        arcNotAllowed_ = true;
      }
      return;
    }
    if (plane_ == Plane::YZ)
      fail(column,
           "expected G17 or G18 (the XY or XZ plane) for cutter radius compensation, "
           "found G19 (YZ)");
    const auto side =
        code == 410 || code == 411 ? CutterCompensation::Left : CutterCompensation::Right;
    double diameter = 0.0;  // mm
    if (code == 411 || code == 421) {
      if (!w.has('D'))
        fail(column, "expected a D word (the tool's diameter) with " + codeName('G', code) +
                         ", found none");
      if (w.has('L'))
        fail(w.column('L'), "expected no L word (a lathe tool's orientation) with " +
                                codeName('G', code) +
                                ", found one (lathe tools are not "
                                "interpreted)");
      diameter = w.get('D') * unit();
    } else {
      int tool = tool_;
      if (w.has('D')) {
        const double d = w.get('D');
        if (!(d >= 0.0) || std::abs(d - std::round(d)) >= 1e-4)
          fail(w.column('D'),
               "expected a tool number D with " + codeName('G', code) + ", found D" + num(d));
        tool = static_cast<int>(std::lround(d));
        if (!toolDiameters_.count(tool))
          fail(w.column('D'),
               "expected a tool of the tool table in D (its radius offsets the "
               "path), found D" +
                   std::to_string(tool) +
                   (options_.toolTable.empty() ? " and no tool table (--tool-table)"
                                               : ", which the table does not have"));
      }
      const auto it = toolDiameters_.find(tool);
      diameter = it == toolDiameters_.end() ? 0.0 : it->second;
    }
    try {
      comp_.on(side, diameter / 2.0, physicalStart_ ? *physicalStart_ : pos_, unit(), plane_);
    } catch (const CompensationError& e) {
      fail(column, e.what());
    }
  }

  /// Codes LinuxCNC refuses while compensation is on.
  void refuseWithCompensation(const Words& w, bool onBefore) {
    auto refuse = [&](int column, const std::string& what) {
      fail(column, "expected G40 before " + what + ", found cutter radius compensation on");
    };
    if (const auto g = w.gIn(2); g && onBefore) refuse(w.gColumn(*g), "changing the plane");
    if (const auto g = w.gIn(8))
      refuse(w.gColumn(*g), "a tool length offset (" + codeName('G', *g) + ")");
    if (const auto g = w.gIn(12)) refuse(w.gColumn(*g), "changing the coordinate system");
    for (const auto& [code, c] : w.g)
      if (code == 280 || code == 300 || code == 920 || code == 921 || code == 922 || code == 923 ||
          code == 530 || code == 100)
        refuse(c, codeName('G', code));
  }

  void spline(const Words& w, int column) {
    if (plane_ != Plane::XY)
      fail(column, "expected the XY plane (G17) for G5/G5.1 splines, found " +
                       std::string(planeName(plane_)));
    if (w.has('Z'))
      fail(w.column('Z'), "expected no Z word on a G5/G5.1 spline (they are planar), found Z");
    const Vector3d end = target(w, false);
    const Eigen::Vector2d p0(pos_.x(), pos_.y());
    const Eigen::Vector2d p3(end.x(), end.y());
    std::vector<Eigen::Vector2d> pts;
    if (motion_ == 50) {
      Eigen::Vector2d i;
      if (w.has('I') || w.has('J')) {
        if (!(w.has('I') && w.has('J')))
          fail(column, "expected both I and J (or neither after another G5) on G5, found one");
        i = Eigen::Vector2d(w.get('I'), w.get('J')) * unit();
      } else {
        if (!lastCubic_) fail(column, "expected I and J on the first G5 of a curve, found neither");
        i = -*lastCubic_;
      }
      if (!(w.has('P') && w.has('Q')))
        fail(column, "expected P and Q on G5, found " + std::string(w.has('P') ? "no Q" : "no P"));
      const Eigen::Vector2d pq(w.get('P') * unit(), w.get('Q') * unit());
      pts = flattened(
          column, [&] { return gcode::flattenCubic(p0, p0 + i, p3 + pq, p3, kSplineTolerance); });
      lastCubic_ = pq;
    } else {
      if (!w.has('I') && !w.has('J')) fail(column, "expected I and/or J on G5.1, found neither");
      const Eigen::Vector2d i(w.has('I') ? w.get('I') * unit() : 0.0,
                              w.has('J') ? w.get('J') * unit() : 0.0);
      pts = flattened(column,
                      [&] { return gcode::flattenQuadratic(p0, p0 + i, p3, kSplineTolerance); });
    }
    emitSpline(pts, w, column);
  }

  /// Runs a flattening, turning its work-limit Error into an error at this line.
  template <class F>
  std::vector<Eigen::Vector2d> flattened(int column, F f) const {
    try {
      return f();
    } catch (const GcodeError&) {
      throw;
    } catch (const Error& e) {
      fail(column, e.what());
    }
  }

  void emitSpline(const std::vector<Eigen::Vector2d>& pts, const Words& w, int column) {
    Move m = base(MoveKind::Spline);
    for (const Eigen::Vector2d& p : pts)
      m.points.emplace_back(p.x(), p.y(), pos_.z());
    m.end = m.points.back();
    pos_ = m.end;
    m.feed = feedFor(moveLength(m), w, column);
    out_.moves.push_back(std::move(m));
  }

  void nurbsPoint(const Words& w, int column) {
    if (plane_ != Plane::XY)
      fail(column,
           "expected the XY plane (G17) for G5.2 NURBS, found " + std::string(planeName(plane_)));
    if (nurbs_.empty()) {
      nurbsOrder_ = w.has('L') ? static_cast<int>(std::lround(w.get('L'))) : 3;
      if (nurbsOrder_ < 2)
        fail(w.column('L'), "expected a NURBS order L >= 2, found L" + std::to_string(nurbsOrder_));
      nurbs_.push_back({Eigen::Vector2d(pos_.x(), pos_.y()), 1.0});
      nurbsLine_ = line_;
    }
    const Vector3d p = target(w, false);
    const double weight = w.has('P') ? w.get('P') : 1.0;
    if (weight <= 0.0)
      fail(w.column('P'), "expected a positive NURBS weight P, found P" + num(weight));
    if (w.has('X') || w.has('Y')) nurbs_.push_back({Eigen::Vector2d(p.x(), p.y()), weight});
  }

  void nurbsEnd(const Words& w, int column) {
    if (nurbs_.size() < 2) fail(column, "expected G5.2 control points before G5.3, found none");
    if (static_cast<int>(nurbs_.size()) < nurbsOrder_)
      fail(column, "expected at least L = " + std::to_string(nurbsOrder_) +
                       " NURBS control points, found " + std::to_string(nurbs_.size()));
    std::vector<Eigen::Vector2d> cp;
    std::vector<double> weights;
    for (const auto& [p, wt] : nurbs_) {
      cp.push_back(p);
      weights.push_back(wt);
    }
    const auto pts = flattened(
        column, [&] { return gcode::flattenNurbs(cp, weights, nurbsOrder_, kSplineTolerance); });
    const int saved = line_;
    recordBlock();  // the G5.3 line carries the curve's F; the move reports its G5.2 line
    line_ = nurbsLine_;
    emitSpline(pts, w, column);
    line_ = saved;
    nurbs_.clear();
    motion_ = 800;  // G5.3 ends the NURBS block; LinuxCNC then needs a new motion word
  }

  // ---------------------------------------------------------------- canned cycles (G17)
  void cycle(const Words& w, int column, bool explicitMotion) {
    if (plane_ != Plane::XY)
      fail(column, "expected the XY plane (G17) for canned cycles, found " +
                       std::string(planeName(plane_)));
    const bool newCycle = explicitMotion && (!cycleActive_ || motionBefore_ != motion_);
    if (newCycle) {
      if (!w.has('R'))
        fail(column, "expected an R word (retract plane) when a canned cycle starts, found none");
      if (!w.has('Z'))
        fail(column, "expected a Z word (hole bottom) when a canned cycle starts, found none");
    }
    if (newCycle && (motion_ == 820 || motion_ == 890) && !w.has('P'))
      fail(column, "expected a P word (dwell seconds) when " + codeName('G', motion_) +
                       " starts, found none");
    cycleActive_ = true;
    const Vector3d offset = workOffset();
    // The initial level is the Z where this run of canned-cycle blocks began (LinuxCNC's
    // cycle_il): G98 returns there, and G91 measures R from it.
    if (!cycleInitialValid_) {
      cycleInitial_ = pos_.z();
      cycleInitialValid_ = true;
    }
    double oldZ = cycleInitial_;  // machine mm
    // R and Z: absolute in program coordinates (G90), or R from the current Z and Z from R (G91).
    if (w.has('R')) cycleR_ = w.get('R');
    if (w.has('Z')) cycleZ_ = w.get('Z');
    if (w.has('Q')) cycleQ_ = w.get('Q');
    double r, bottom;
    if (incremental_) {
      r = oldZ + cycleR_ * unit();
      bottom = r + cycleZ_ * unit();
    } else {
      r = cycleR_ * unit() + offset.z();
      bottom = cycleZ_ * unit() + offset.z();
    }
    if (bottom > r)
      fail(w.has('Z') ? w.column('Z') : column,
           "expected the hole bottom Z below the retract plane R, found it above");
    if ((motion_ == 830 || motion_ == 730) && !(cycleQ_ > 0.0))
      fail(column, "expected a positive peck depth Q for " + codeName('G', motion_) + ", found Q" +
                       num(cycleQ_));
    if ((motion_ == 830 || motion_ == 730) && (r - bottom) / (cycleQ_ * unit()) > kMaxPecks)
      fail(column, "expected at most " + std::to_string(kMaxPecks) + " pecks, found Q" +
                       num(cycleQ_) + " over a depth of " + length((r - bottom) / unit()));
    int repeats = 1;
    if (w.has('L')) {
      const double l = w.get('L');
      if (!(l >= 0.0 && l <= kMaxPecks))
        fail(w.column('L'),
             "expected a repeat count L in 0.." + std::to_string(kMaxPecks) + ", found L" + num(l));
      repeats = static_cast<int>(std::lround(l));
    }
    // Below the R plane: climb to R first, where the tool is.
    if (oldZ < r) {
      emitLinear(MoveKind::Rapid, Vector3d(pos_.x(), pos_.y(), r));
      oldZ = r;
    }
    const double clear = retractToR_ ? r : oldZ;
    // The first positioning rapid runs at the current height with G99 and at the initial
    // level with G98 (LinuxCNC 2.9 as packaged in Debian 12); later repeats at `clear`.
    double level = retractToR_ ? std::max(pos_.z(), r) : oldZ;
    double x = pos_.x(), y = pos_.y();
    const Vector3d program = programPosition();
    for (int i = 0; i < repeats; ++i) {
      if (w.has('@') || w.has('^')) {
        const Eigen::Vector2d xy =
            polarTarget(w, Eigen::Vector2d((x - offset.x()) / unit(), (y - offset.y()) / unit()));
        x = xy.x() * unit() + offset.x();
        y = xy.y() * unit() + offset.y();
      } else if (incremental_) {
        x += w.has('X') ? w.get('X') * unit() : 0.0;
        y += w.has('Y') ? w.get('Y') * unit() : 0.0;
      } else {
        x = (w.has('X') ? w.get('X') : program.x()) * unit() + offset.x();
        y = (w.has('Y') ? w.get('Y') : program.y()) * unit() + offset.y();
      }
      emitLinear(MoveKind::Rapid, Vector3d(x, y, level));
      emitLinear(MoveKind::Rapid, Vector3d(x, y, r));
      const double f = [&] { return feedFor(1.0, w, column); }();
      auto feedTo = [&](double z) {
        emitLinear(
            MoveKind::Line, Vector3d(x, y, z),
            feedMode_ == FeedMode::InverseTime ? feedFor(std::abs(z - pos_.z()), w, column) : f);
      };
      auto rapidTo = [&](double z) { emitLinear(MoveKind::Rapid, Vector3d(x, y, z)); };
      const double delta = kPeckClearanceInch * kInch;
      switch (motion_) {
        case 810:
        case 820:
          feedTo(bottom);
          rapidTo(clear);
          break;
        case 830:
        case 730: {
          const double q = cycleQ_ * unit();
          for (double depth = r - q; depth > bottom; depth -= q) {
            feedTo(depth);
            if (motion_ == 830) {
              rapidTo(r);
              rapidTo(depth + delta);
            } else {
              rapidTo(depth + delta);
            }
          }
          feedTo(bottom);
          rapidTo(clear);
          break;
        }
        case 850:
        case 890:
          feedTo(bottom);
          feedTo(r);
          if (clear > r) rapidTo(clear);
          break;
        default:
          break;
      }
      level = clear;
    }
  }

  struct Modal {
    Plane plane;
    bool inch;
    bool incremental;
    bool arcIncremental;
    FeedMode feedMode;
    bool retractToR;
    double feed;
    double spindle;
    int motion;
  };

  const ReaderOptions& options_;
  mutable Toolpath out_;
  mutable std::optional<Vector3d> physicalStart_;  ///< see comp_
  const Block* currentBlock_ = nullptr;            ///< the line being executed
  mutable bool blockRecorded_ = false;
  std::vector<std::unique_ptr<SourceFile>> files_;
  int file_ = 0;
  int line_ = 0;
  std::vector<Frame> frames_;
  std::map<std::pair<int, int>, long> repeats_;
  std::vector<double> params_;
  std::unordered_map<std::string, double> globals_;
  std::unordered_map<std::string, double> topLocals_;
  std::map<int, double> toolLengths_;    ///< mm
  std::map<int, double> toolDiameters_;  ///< mm (the radius compensation uses)
  /// G41/G42: the moves go through it while it is on (CutterComp.h).
  CutterCompensation comp_{[this](Move m) { out_.moves.push_back(std::move(m)); }};
  // physicalStart_ (declared above, with out_): where the next move starts when that is not
  // pos_: after G40, the offset point the tool is at (pos_ is the programmed point, as
  // LinuxCNC has it).
  bool arcNotAllowed_ = false;  ///< the move after G40 must be straight
  bool startKnown_ = false;     ///< the start position is where the tool is (see ReaderOptions)
  std::optional<Modal> saved_;
  std::optional<LatheProfile> profile_;

  Vector3d pos_{0.0, 0.0, 0.0};
  Plane plane_ = Plane::XY;
  bool inch_ = false;
  bool incremental_ = false;
  bool arcIncremental_ = true;
  FeedMode feedMode_ = FeedMode::UnitsPerMinute;
  bool retractToR_ = false;
  bool diameterMode_ = false;  ///< G7 (lathe diameter mode); G8 radius mode is the default
  double feed_ = 0.0;          ///< mm/min (G94), mm/rev (G95) or 1/min (G93)
  double spindleSpeed_ = 0.0;
  int spindleDirection_ = 0;
  int tool_ = 0;
  int preparedTool_ = 0;
  double toolLength_ = 0.0;
  bool otherAxes_ = false;                     ///< the current line moves a rotary or UVW axis
  std::array<double, 6> otherAxisPosition_{};  ///< A, B, C, U, V, W (program units)
  int motion_ = 800;        ///< G80: axis words need a motion word first, as in LinuxCNC
  int motionBefore_ = 800;  ///< motion mode before the current block
  bool cycleActive_ = false;
  bool cycleInitialValid_ = false;
  double cycleInitial_ = 0.0;  ///< mm, machine Z where the current run of cycles began
  double cycleR_ = 0.0, cycleZ_ = 0.0, cycleQ_ = 0.0;
  std::optional<Eigen::Vector2d> lastCubic_;
  std::vector<std::pair<Eigen::Vector2d, double>> nurbs_;
  int nurbsOrder_ = 3;
  int nurbsLine_ = 0;
};

}  // namespace

Toolpath readProgram(const std::string& path, const ReaderOptions& options) {
  return readProgramText(readFile(path), path, options);
}

Toolpath readPrograms(const std::vector<std::string>& paths, const ReaderOptions& options) {
  Toolpath all;
  ReaderOptions o = options;
  for (const std::string& path : paths) {
    Toolpath one = readProgram(path, o);
    const int files = static_cast<int>(all.files.size());
    const int blocks = static_cast<int>(all.blocks.size());
    if (all.moves.size() + one.moves.size() > options.maxMoves)
      throw GcodeError(path, 1, 1,
                       "expected at most " + std::to_string(options.maxMoves) +
                           " moves in the programs together, found more");
    // The first program is taken whole (CAMotics' tiger: 67,000 moves, whose copy grown one
    // at a time was a third of the run's heap at its peak), the others appended.
    if (all.moves.empty() && all.blocks.empty()) {
      all.moves = std::move(one.moves);
      all.blocks = std::move(one.blocks);
    } else {
      all.moves.reserve(all.moves.size() + one.moves.size());
      for (Move& m : one.moves) {
        m.file += files;
        m.block += blocks;
        all.moves.push_back(std::move(m));
      }
      all.blocks.reserve(all.blocks.size() + one.blocks.size());
      for (SourceBlock& b : one.blocks) {
        b.file += files;
        all.blocks.push_back(std::move(b));
      }
    }
    all.files.insert(all.files.end(), one.files.begin(), one.files.end());
    all.inch = one.inch;
    if (all.latheLine == 0 && one.latheLine != 0) {
      all.latheLine = one.latheLine;
      all.lathe = one.lathe;
    }
    if (!all.moves.empty()) {
      o.start = all.moves.back().end;
      o.startTool = all.moves.back().tool;
      o.startKnown = true;
    }
  }
  return all;
}

Toolpath readProgramText(const std::string& text, const std::string& name,
                         const ReaderOptions& options) {
  Interpreter interpreter(options);
  return interpreter.run(makeSource(name, text));
}

}  // namespace engage
