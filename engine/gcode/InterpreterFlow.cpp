// O-word control flow (if/elseif/else, while, do, repeat, break, continue), O-word subroutines
// and their files, and Fanuc/Haas M98/M99 subprograms.

#include "engine/gcode/Interpreter.h"

#include <iterator>

namespace engage::gcode {

const std::vector<std::pair<int, std::string>>& Interpreter::labelEntries(const std::string& label,
                                                                          int column) const {
  const SourceFile& f = *files_[static_cast<std::size_t>(file_)];
  const auto it = f.labels.find(label);
  if (it == f.labels.end()) fail(column, "expected a known O-word label, found o" + label);
  return it->second;
}

int Interpreter::findForward(const std::string& label, int from,
                             std::initializer_list<const char*> keywords, int column,
                             const char* expected) const {
  for (const auto& [line, kw] : labelEntries(label, column))
    if (line > from)
      for (const char* k : keywords)
        if (kw == k) return line;
  fail(column, std::string("expected ") + expected + " for o" + label + ", found none");
}

int Interpreter::findBackward(const std::string& label, int from, const char* keyword,
                              int column) const {
  const auto& entries = labelEntries(label, column);
  for (auto it = entries.rbegin(); it != entries.rend(); ++it)
    if (it->first < from && it->second == keyword) return it->first;
  fail(column, std::string("expected O-") + keyword + " opening o" + label + ", found none");
}

bool Interpreter::hasKeywordBefore(const std::string& label, int from, const char* keyword) const {
  const SourceFile& f = *files_[static_cast<std::size_t>(file_)];
  const auto it = f.labels.find(label);
  if (it == f.labels.end()) return false;
  for (const auto& [line, kw] : it->second)
    if (line < from && kw == keyword) return true;
  return false;
}

void Interpreter::controlFlow(const Block& b) {
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

void Interpreter::nextBranch(const std::string& label, int column) {
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

void Interpreter::loopJump(const std::string& label, bool isBreak, int column) {
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

std::pair<int, int> Interpreter::findLabel(const std::string& label, const char* keyword,
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
    const std::filesystem::path p =
        folder.empty() ? std::filesystem::path(fileName) : std::filesystem::path(folder) / fileName;
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

std::pair<int, int> Interpreter::findSubroutine(const std::string& label, int column) {
  const bool named = label.size() > 2 && label.front() == '<';
  const auto found =
      findLabel(label, "sub", named ? label.substr(1, label.size() - 2) + ".ngc" : "", false);
  if (found.first < 0)
    fail(column, "expected a subroutine o" + label + " (in this program or as " +
                     (label.front() == '<' ? label.substr(1, label.size() - 2) : label) +
                     ".ngc beside it), found none");
  return found;
}

void Interpreter::call(const gcode::OWord& o) {
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

namespace {

/// A program number P or repeat count L of M97, M98 or G65: a whole number in 0..1e9; -1 when
/// it is not.
long wholeCount(double v) {
  if (!(v >= 0.0) || std::abs(v - std::round(v)) > 1e-9 || v > 1e9) return -1;
  return std::lround(v);
}

}  // namespace

void Interpreter::subprogramCall(const Words& w) {
  const int column = w.mColumn(M_98);
  if (!w.has('P')) fail(column, "expected a P word (the program number) with M98, found none");
  long program = wholeCount(w.get('P'));
  if (program < 0)
    fail(w.column('P'), "expected a program number P with M98, found P" + formatNumber(w.get('P')));
  long times = 1;
  if (w.has('L')) {
    times = wholeCount(w.get('L'));
    if (times < 0)
      fail(w.column('L'), "expected a repeat count L with M98, found L" + formatNumber(w.get('L')));
  } else if (options_.dialect == Dialect::Fanuc && program > 9999) {
    // (Haas numbers programs with five digits and counts with L only.)
    times = program / 10000;
    program %= 10000;
  }
  if (times == 0) return;
  const std::string label = std::to_string(program);
  const auto [targetFile, targetLine] = findLabel(label, "program", label + ".ngc", true);
  if (targetFile < 0)
    fail(w.column('P'), "expected a subprogram O" + label + " (in this program or as " + label +
                            ".ngc beside it), found none");
  enterSubprogram(targetFile, targetLine, times, column);
}

Interpreter::Frame& Interpreter::enterSubprogram(int file, int line, long times, int column) {
  if (frames_.size() >= 64)
    fail(column, "expected subprogram calls nested at most 64 deep, found deeper recursion");
  Frame f;
  f.file = file_;
  f.returnLine = line_ + 1;
  f.m98 = true;
  f.startFile = file;
  f.startLine = line;
  f.repeats = times - 1;
  frames_.push_back(std::move(f));
  file_ = file;
  line_ = line;  // (the run loop goes on with the next line)
  return frames_.back();
}

void Interpreter::localSubprogramCall(const Words& w) {
  const int column = w.mColumn(M_97);
  if (!w.has('P')) fail(column, "expected a P word (the line number N) with M97, found none");
  long times = 1;
  if (w.has('L')) {
    times = wholeCount(w.get('L'));
    if (times < 0)
      fail(w.column('L'), "expected a repeat count L with M97, found L" + formatNumber(w.get('L')));
  }
  if (times == 0) return;
  const int target = lineNumbered(w.get('P'), w.column('P'));
  enterSubprogram(file_, target - 1, times, column);
}

void Interpreter::macroCall(const Block& b) {
  int column = 1;
  for (const gcode::Word& word : b.words)
    if (word.letter == 'G' && codeOf(word.value) == G_65) column = word.column;
  if (!fanucLike())
    fail(column, "expected --dialect fanuc or haas for G65 (a Fanuc/Haas macro call), found the " +
                     dialectName() + " dialect");
  // Fanuc's argument specification I: the local each letter sets.
  static const std::map<char, int> local = {
      {'A', 1},  {'B', 2},  {'C', 3},  {'I', 4},  {'J', 5},  {'K', 6},  {'D', 7},
      {'E', 8},  {'F', 9},  {'H', 11}, {'M', 13}, {'Q', 17}, {'R', 18}, {'S', 19},
      {'T', 20}, {'U', 21}, {'V', 22}, {'W', 23}, {'X', 24}, {'Y', 25}, {'Z', 26}};
  std::optional<double> program, repeats;
  std::array<double, 33> locals;
  locals.fill(gcode::vacantValue());
  std::array<bool, 33> given{};
  for (const gcode::Word& word : b.words) {
    if (word.letter == 'G') {
      if (codeOf(word.value) != G_65)
        fail(word.column, "expected only G65 and its arguments on a macro call's line, found G" +
                              formatNumber(word.value));
      continue;
    }
    if (word.letter == 'P') {
      program = word.value;
    } else if (word.letter == 'L') {
      repeats = word.value;
    } else if (const auto it = local.find(word.letter); it != local.end()) {
      const std::size_t i = static_cast<std::size_t>(it->second - 1);
      if (given[i])
        fail(word.column, std::string("expected each argument once in G65 (argument "
                                      "specification I), found ") +
                              word.letter + " again");
      given[i] = true;
      locals[i] = word.value;
    } else {
      fail(word.column,
           std::string("expected a G65 argument (A-Z but G, L, N, O, P), found ") + word.letter);
    }
  }
  if (b.corner) fail(b.corner->column, "expected no corner word on a G65 line, found one");
  if (!program) fail(column, "expected a P word (the macro's program number) with G65, found none");
  const long number = wholeCount(*program);
  if (number < 0)
    fail(column, "expected a program number P with G65, found P" + formatNumber(*program));
  const long times = repeats ? wholeCount(*repeats) : 1;
  if (times < 0)
    fail(column, "expected a repeat count L with G65, found L" + formatNumber(*repeats));
  if (times == 0) return;
  const std::string label = std::to_string(number);
  const auto [targetFile, targetLine] = findLabel(label, "program", label + ".ngc", true);
  if (targetFile < 0)
    fail(column, "expected a macro program O" + label + " (in this program or as " + label +
                     ".ngc beside it), found none");
  Frame& f = enterSubprogram(targetFile, targetLine, times, column);
  f.g65 = true;
  for (std::size_t i = 0; i < 33; ++i) {
    f.callerLocals[i] = params_[i + 1];
    params_[i + 1] = locals[i];
  }
}

void Interpreter::subprogramReturn(int column) {
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
  if (f.g65)
    for (std::size_t i = 0; i < 33; ++i)
      params_[i + 1] = f.callerLocals[i];
  frames_.pop_back();
}

void Interpreter::macroFlow(const Block& b) {
  const gcode::MacroStatement& m = b.macro;
  if (!fanucLike())
    fail(m.column,
         "expected --dialect fanuc or haas for Fanuc/Haas custom macro B (IF, WHILE, "
         "DO, END, GOTO), found the " +
             dialectName() + " dialect (its control flow is O-words)");
  using K = gcode::MacroStatement;
  switch (m.kind) {
    case K::IfGoto:
      line_ = m.condition != 0.0 ? lineNumbered(m.target, m.column) : line_ + 1;
      return;
    case K::Goto:
      line_ = lineNumbered(m.target, m.column);
      return;
    case K::While:
      line_ = m.condition != 0.0 ? line_ + 1 : loopPartner(m, m.column) + 1;
      return;
    case K::End:
      line_ = loopPartner(m, m.column);  // the WHILE, evaluated again (or the DO)
      return;
    default:  // IF .. THEN (its assignment is the block's), DO
      ++line_;
      return;
  }
}

int Interpreter::lineNumbered(double n, int column) const {
  const SourceFile& f = *files_[static_cast<std::size_t>(file_)];
  const SourceFile::MacroIndex& ix = f.macroIndex();
  const int count = static_cast<int>(f.lines.size());
  // The program (O number) the current line is in: from its O line to the next one.
  const auto next = std::upper_bound(ix.programStarts.begin(), ix.programStarts.end(), line_);
  const int first = next == ix.programStarts.begin() ? 0 : *std::prev(next);
  const int last = next == ix.programStarts.end() ? count : *next;
  for (int pass = 0; pass < 2; ++pass)
    for (int i = pass == 0 ? line_ + 1 : first; i < (pass == 0 ? last : line_ + 1); ++i)
      if (std::abs(ix.lineNumbers[static_cast<std::size_t>(i)] - n) < 1e-9) return i;
  fail(column, "expected a line N" + formatNumber(n) + " in this program to go to, found none");
}

int Interpreter::loopPartner(const gcode::MacroStatement& m, int column) const {
  const SourceFile& f = *files_[static_cast<std::size_t>(file_)];
  const auto& loops = f.macroIndex().loops;
  const int loop = static_cast<int>(std::lround(m.target));
  const bool forward = m.kind != gcode::MacroStatement::End;
  int depth = 0;
  for (int i = forward ? line_ + 1 : line_ - 1;
       forward ? i < static_cast<int>(loops.size()) : i >= 0; i += forward ? 1 : -1) {
    const auto [kind, other] = loops[static_cast<std::size_t>(i)];
    if (kind == gcode::MacroStatement::None || other != loop) continue;
    const bool opens = kind != gcode::MacroStatement::End;
    if (opens == forward) {
      ++depth;  // (the same number nested: not on a Fanuc control, matched inside out here)
    } else if (depth > 0) {
      --depth;
    } else {
      return i;
    }
  }
  fail(column, forward ? "expected END " + std::to_string(loop) + " closing this loop, found none"
                       : "expected WHILE .. DO " + std::to_string(loop) + " or DO " +
                             std::to_string(loop) + " opening this END, found none");
}

}  // namespace engage::gcode
