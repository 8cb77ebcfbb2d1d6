#include "engine/gcode/LineParser.h"
#include "cutters/Numbers.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace engage::gcode {

namespace {
constexpr double kDegree = kPi / 180.0;
/// LinuxCNC compares EQ/NE with this absolute tolerance.
constexpr double kEqualTolerance = 0.0001;
constexpr std::uint64_t kVacantBits = 0x7ff8'0000'0000'7acaULL;  // a quiet NaN, payload 0x7aca
}  // namespace

double vacantValue() {
  double v;
  std::memcpy(&v, &kVacantBits, sizeof v);
  return v;
}

bool isVacant(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof v);
  return bits == kVacantBits;
}

namespace {

/// A value in arithmetic: vacant reads as 0.
double arith(double v) {
  return isVacant(v) ? 0.0 : v;
}

/// EQ: two vacants are equal, a vacant and a number never.
bool equal(double a, double b) {
  if (isVacant(a) || isVacant(b)) return isVacant(a) && isVacant(b);
  return std::abs(a - b) < kEqualTolerance;
}

std::string shown(char c) {
  if (c == 0) return "the end of the line";
  const auto byte = static_cast<unsigned char>(c);
  if (byte < 0x20 || byte >= 0x7f) {
    // A control or non-ASCII byte prints as nothing on a terminal: name it.
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02X", byte);
    return std::string("the byte ") + hex + " (not text: is the file a G-code program?)";
  }
  return std::string("'") + c + "'";
}

/// The line without comments and blanks, lower-cased, with each character's source column.
class Compact {
 public:
  Compact(std::string_view line, std::vector<std::string>* comments) {
    text_.reserve(line.size());
    cols_.reserve(line.size());
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      if (c == '(') {
        const std::size_t close = line.find(')', i + 1);
        if (close == std::string_view::npos)
          throw ParseFailure{static_cast<int>(i + 1),
                             "expected ')' closing this comment, found the end of the line"};
        if (comments) comments->emplace_back(line.substr(i + 1, close - i - 1));
        i = close;
      } else if (c == ';') {
        if (comments) comments->emplace_back(line.substr(i + 1));
        break;
      } else if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
        continue;
      } else {
        text_.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
        cols_.push_back(static_cast<int>(i + 1));
      }
    }
    endColumn_ = static_cast<int>(line.size()) + 1;
  }
  const std::string& text() const { return text_; }
  int column(std::size_t p) const { return p < cols_.size() ? cols_[p] : endColumn_; }

 private:
  std::string text_;
  std::vector<int> cols_;
  int endColumn_ = 1;
};

class Parser {
 public:
  Parser(const Compact& c, const ParameterSource& params) : c_(c), s_(c.text()), params_(params) {}

  std::size_t pos() const { return p_; }
  void setPos(std::size_t p) { p_ = p; }
  bool atEnd() const { return p_ >= s_.size(); }
  char peek(std::size_t k = 0) const { return p_ + k < s_.size() ? s_[p_ + k] : 0; }
  int column() const { return c_.column(p_); }

  [[noreturn]] void fail(const std::string& expected) const {
    throw ParseFailure{column(), "expected " + expected + ", found " + shown(peek())};
  }
  [[noreturn]] void failAt(std::size_t p, const std::string& message) const {
    throw ParseFailure{c_.column(p), message};
  }

  bool accept(std::string_view token) {
    if (s_.compare(p_, token.size(), token) == 0) {
      p_ += token.size();
      return true;
    }
    return false;
  }
  void expect(char ch, const char* what) {
    if (peek() != ch) fail(what);
    ++p_;
  }

  double number() {
    const std::size_t start = p_;
    bool digits = false;
    bool dot = false;
    while (!atEnd()) {
      const char ch = peek();
      if (std::isdigit(static_cast<unsigned char>(ch))) {
        digits = true;
      } else if (ch == '.' && !dot) {
        dot = true;
      } else {
        break;
      }
      ++p_;
    }
    if (!digits) {
      p_ = start;
      fail("a number");
    }
    // from_chars on the exact span: strtod would read "0x.1" (G0X.1) as a hex float.
    double v = 0.0;
    const auto r = std::from_chars(s_.data() + start, s_.data() + p_, v);
    if (r.ec != std::errc())
      failAt(start, "expected a number within the range of a double, found " +
                        std::string(s_.substr(start, std::min<std::size_t>(p_ - start, 20))) +
                        (p_ - start > 20 ? "..." : ""));
    return v;
  }

  /// A real value: number, [expression], #parameter, function, with optional unary sign.
  double real() {
    const char ch = peek();
    if (ch == '-') {
      ++p_;
      return -arith(real());
    }
    if (ch == '+') {
      ++p_;
      return arith(real());
    }
    if (ch == '[') return bracket();
    if (ch == '#') return parameterValue();
    if (std::isdigit(static_cast<unsigned char>(ch)) || ch == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(ch))) return function();
    fail("a number, [expression], #parameter or function");
  }

  double bracket() {
    expect('[', "'['");
    const double v = expression(5);
    expect(']', "']' closing the expression");
    return v;
  }

  /// Binary operators by precedence level: 1 **, 2 * / mod, 3 + -, 4 comparisons, 5 logic.
  double expression(int level) {
    if (level == 0) return real();
    double left = expression(level - 1);
    for (;;) {
      const std::size_t opAt = p_;
      if (level == 4 && accept("eq")) {
        left = equal(left, expression(3)) ? 1.0 : 0.0;
        continue;
      }
      if (level == 4 && accept("ne")) {
        left = equal(left, expression(3)) ? 0.0 : 1.0;
        continue;
      }
      if (level == 1 && accept("**")) {
        left = std::pow(arith(left), arith(expression(0)));
      } else if (level == 2 && peek() == '*' && peek(1) != '*') {
        ++p_;
        left = arith(left) * arith(expression(1));
      } else if (level == 2 && peek() == '/') {
        ++p_;
        const double right = arith(expression(1));
        if (right == 0.0) failAt(opAt, "expected a non-zero divisor, found division by zero");
        left = arith(left) / right;
      } else if (level == 2 && accept("mod")) {
        const double right = arith(expression(1));
        if (right == 0.0) failAt(opAt, "expected a non-zero divisor, found MOD by zero");
        double m = std::fmod(arith(left), right);
        if (m < 0.0) m += std::abs(right);
        left = m;
      } else if (level == 3 && peek() == '+') {
        ++p_;
        left = arith(left) + arith(expression(2));
      } else if (level == 3 && peek() == '-') {
        ++p_;
        left = arith(left) - arith(expression(2));
      } else if (level == 4 && accept("gt")) {
        left = arith(left) > arith(expression(3)) ? 1.0 : 0.0;
      } else if (level == 4 && accept("ge")) {
        left = arith(left) >= arith(expression(3)) ? 1.0 : 0.0;
      } else if (level == 4 && accept("lt")) {
        left = arith(left) < arith(expression(3)) ? 1.0 : 0.0;
      } else if (level == 4 && accept("le")) {
        left = arith(left) <= arith(expression(3)) ? 1.0 : 0.0;
      } else if (level == 5 && accept("and")) {
        const double right = arith(expression(4));
        left = (arith(left) != 0.0 && right != 0.0) ? 1.0 : 0.0;
      } else if (level == 5 && accept("or")) {
        const double right = arith(expression(4));
        left = (arith(left) != 0.0 || right != 0.0) ? 1.0 : 0.0;
      } else if (level == 5 && accept("xor")) {
        const double right = arith(expression(4));
        left = ((arith(left) != 0.0) != (right != 0.0)) ? 1.0 : 0.0;
      } else {
        return left;
      }
    }
  }

  double function() {
    const std::size_t start = p_;
    std::string name;
    while (std::isalpha(static_cast<unsigned char>(peek())))
      name.push_back(s_[p_++]);
    if (name == "exists") {
      expect('[', "'[' after EXISTS");
      expect('#', "a #<name> parameter in EXISTS");
      const std::string n = parameterName();
      expect(']', "']' closing EXISTS");
      double unused = 0.0;
      return params_.named(n, unused) ? 1.0 : 0.0;
    }
    if (name == "atan") {
      const double y = arith(bracket());
      expect('/', "'/' in ATAN[y]/[x]");
      const double x = arith(bracket());
      return std::atan2(y, x) / kDegree;
    }
    static const char* const known[] = {"abs", "acos",  "asin", "cos", "exp",  "fix",
                                        "fup", "round", "ln",   "sin", "sqrt", "tan"};
    bool isKnown = false;
    for (const char* k : known)
      isKnown = isKnown || name == k;
    if (!isKnown) {
      p_ = start;
      failAt(start,
             "expected a number, [expression], #parameter or function, found '" + name + "'");
    }
    const double v = arith(bracket());
    auto domain = [&](bool ok, const char* what) {
      if (!ok)
        failAt(start,
               std::string("expected ") + what + ", found " + name + " of " + std::to_string(v));
    };
    if (name == "abs") return std::abs(v);
    if (name == "acos") {
      domain(v >= -1.0 && v <= 1.0, "an ACOS argument in [-1, 1]");
      return std::acos(v) / kDegree;
    }
    if (name == "asin") {
      domain(v >= -1.0 && v <= 1.0, "an ASIN argument in [-1, 1]");
      return std::asin(v) / kDegree;
    }
    if (name == "cos") return std::cos(v * kDegree);
    if (name == "exp") return std::exp(v);
    if (name == "fix") return std::floor(v);
    if (name == "fup") return std::ceil(v);
    if (name == "round") return std::round(v);
    if (name == "ln") {
      domain(v > 0.0, "a positive LN argument");
      return std::log(v);
    }
    if (name == "sin") return std::sin(v * kDegree);
    if (name == "sqrt") {
      domain(v >= 0.0, "a non-negative SQRT argument");
      return std::sqrt(v);
    }
    return std::tan(v * kDegree);
  }

  /// After '#<': the name up to '>' (the compact text has no blanks and is lower case).
  std::string parameterName() {
    expect('<', "'<' starting a parameter name");
    const std::size_t close = s_.find('>', p_);
    if (close == std::string::npos) fail("'>' closing the parameter name");
    std::string name = s_.substr(p_, close - p_);
    if (name.empty()) fail("a parameter name");
    p_ = close + 1;
    return name;
  }

  /// After '#': a numbered parameter index, read as a real value and rounded.
  int parameterNumber() {
    const std::size_t at = p_;
    const double v = arith(real());
    const double r = std::round(v);
    if (std::abs(v - r) > 1e-4)
      failAt(at, "expected an integer parameter number, found " + std::to_string(v));
    // Far outside any parameter range: say so before converting (a double that does not fit
    // an int must not be cast).
    if (!(std::abs(r) <= 1e9))
      failAt(at, "expected a parameter number in 1..5602, found " + std::to_string(v));
    return static_cast<int>(r);
  }

  double parameterValue() {
    const std::size_t at = p_;
    expect('#', "'#'");
    if (peek() == '<') {
      const std::string name = parameterName();
      double v = 0.0;
      if (!params_.named(name, v))
        failAt(at, "expected a parameter that has a value, found #<" + name + "> unset");
      return v;
    }
    const int n = parameterNumber();
    try {
      return params_.numbered(n);
    } catch (const std::out_of_range& e) {
      failAt(at, e.what());
    }
  }

 private:
  const Compact& c_;
  const std::string& s_;
  const ParameterSource& params_;
  std::size_t p_ = 0;
};

const char* const kOKeywords[] = {"endsub", "endwhile", "endif",  "endrepeat", "elseif",
                                  "else",   "sub",      "call",   "return",    "do",
                                  "while",  "if",       "repeat", "break",     "continue"};

/// Reads "o<label>keyword" at the parser's position; false when the keyword is unknown.
bool readOWordHead(const std::string& s, std::size_t& p, std::string& label, std::string& keyword) {
  if (p >= s.size() || s[p] != 'o') return false;
  ++p;
  label.clear();
  if (p < s.size() && s[p] == '<') {
    const std::size_t close = s.find('>', p);
    if (close == std::string::npos) return false;
    label = s.substr(p, close - p + 1);
    p = close + 1;
  } else {
    std::size_t start = p;
    while (p < s.size() && std::isdigit(static_cast<unsigned char>(s[p])))
      ++p;
    if (p == start) return false;
    // o0100 and o100 are the same label.
    while (start + 1 < p && s[start] == '0')
      ++start;
    label = s.substr(start, p - start);
  }
  for (const char* k : kOKeywords) {
    const std::size_t n = std::char_traits<char>::length(k);
    if (s.compare(p, n, k) == 0) {
      keyword = k;
      p += n;
      return true;
    }
  }
  keyword.clear();
  return false;
}

/// Skip a leading N line number.
void skipLineNumber(const std::string& s, std::size_t& p) {
  if (p < s.size() && s[p] == 'n') {
    std::size_t q = p + 1;
    while (q < s.size() && (std::isdigit(static_cast<unsigned char>(s[q])) || s[q] == '.'))
      ++q;
    if (q > p + 1) p = q;
  }
}

/// Where a compacted line's words start: after a block-delete '/' and an N word.
std::size_t wordsStart(const std::string& s) {
  std::size_t p = 0;
  if (!s.empty() && s[0] == '/') p = 1;
  skipLineNumber(s, p);
  return p;
}

/// A program number alone at p of a compacted line: an 'o' (or ':', as Fanuc and Haas take
/// it in ISO code) and only digits to its end (Fanuc and Haas posts write "O1001 (PART)";
/// M98 calls such a line's number).
bool isProgramNumber(const std::string& s, std::size_t p) {
  if (p + 1 >= s.size() || (s[p] != 'o' && s[p] != ':')) return false;
  for (std::size_t i = p + 1; i < s.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(s[i]))) return false;
  return true;
}

/// A loop number of DO or END: 1 to 3 on Fanuc and Haas controls; any whole number is read.
double loopNumber(Parser& in, const char* what) {
  if (!std::isdigit(static_cast<unsigned char>(in.peek())))
    in.fail(std::string("a loop number after ") + what);
  return in.number();
}

/// Reads the word after IF's condition or GOTO: a number, #parameter or [expression].
double jumpTarget(Parser& in) {
  if (in.atEnd()) in.fail("a line number after GOTO");
  return in.real();
}

/// #n=value or #<name>=value at the parser's position into block.assignments.
void readAssignment(Parser& in, Block& block, const ParameterSource& params) {
  const int column = in.column();
  in.setPos(in.pos() + 1);
  Assignment a;
  a.column = column;
  if (in.peek() == '<') {
    a.name = in.parameterName();
  } else {
    a.number = in.parameterNumber();
    try {
      params.numbered(a.number);  // range check before the line runs
    } catch (const std::out_of_range& e) {
      throw ParseFailure{column, e.what()};
    }
  }
  in.expect('=', "'=' in a parameter assignment");
  const std::size_t valueAt = in.pos();
  // An expression without brackets, as Fanuc macro B writes it (#1=#1+1); LinuxCNC's bracketed
  // and single values are among them.
  a.value = in.expression(5);
  if (!std::isfinite(a.value) && !isVacant(a.value))
    in.failAt(valueAt, "expected a finite value, found " +
                           std::string(std::isnan(a.value) ? "nan" : "an infinite one"));
  block.assignments.push_back(std::move(a));
}

/// A macro B statement at the parser's position into block.macro; false when the line is not
/// one (its position unchanged).
bool readMacro(Parser& in, Block& block, const ParameterSource& params) {
  MacroStatement& m = block.macro;
  m.column = in.column();
  const std::size_t start = in.pos();
  if (in.accept("if[")) {
    in.setPos(in.pos() - 1);
    m.condition = in.bracket();
    if (in.accept("goto")) {
      m.kind = MacroStatement::IfGoto;
      m.target = jumpTarget(in);
    } else if (in.accept("then")) {
      m.kind = MacroStatement::IfThen;
      if (in.peek() != '#') in.fail("an assignment #i=value after THEN");
      readAssignment(in, block, params);
      if (m.condition == 0.0) block.assignments.clear();
    } else {
      in.fail("GOTO or THEN after IF's condition");
    }
  } else if (in.accept("while[")) {
    in.setPos(in.pos() - 1);
    m.kind = MacroStatement::While;
    m.condition = in.bracket();
    if (!in.accept("do")) in.fail("DO and a loop number after WHILE's condition");
    m.target = loopNumber(in, "DO");
  } else if (in.accept("goto")) {
    m.kind = MacroStatement::Goto;
    m.target = jumpTarget(in);
  } else if (in.accept("do") && std::isdigit(static_cast<unsigned char>(in.peek()))) {
    m.kind = MacroStatement::Do;
    m.target = loopNumber(in, "DO");
  } else if ((in.setPos(start), in.accept("end")) &&
             std::isdigit(static_cast<unsigned char>(in.peek()))) {
    m.kind = MacroStatement::End;
    m.target = loopNumber(in, "END");
  } else {
    in.setPos(start);
    return false;
  }
  if (!in.atEnd()) in.fail("the end of the macro statement");
  return true;
}

}  // namespace

Block parseLine(std::string_view line, const ParameterSource& params) {
  Block block;
  const Compact compact(line, &block.comments);
  const std::string& s = compact.text();
  Parser in(compact, params);
  if (s == "%") {
    block.percent = true;
    return block;
  }
  std::size_t p = 0;
  if (!s.empty() && s[0] == '/') {
    block.blockDelete = true;
    p = 1;
  }
  skipLineNumber(s, p);
  in.setPos(p);
  if (p < s.size() && s[p] == ':' && isProgramNumber(s, p)) return block;  // ":1001"

  if (readMacro(in, block, params)) return block;

  if (in.peek() == 'o') {
    OWord& o = block.oword;
    o.column = in.column();
    std::size_t q = p;
    // A program number alone on its line (Fanuc and Haas posts write "O1001 (PART)" after
    // the '%'): nothing to run.
    if (isProgramNumber(s, p)) return block;
    if (!readOWordHead(s, q, o.label, o.keyword)) {
      in.setPos(p + 1);
      in.fail(
          "an O-word label and keyword (sub, endsub, call, return, do, while, endwhile, if, "
          "elseif, else, endif, repeat, endrepeat, break, continue)");
    }
    in.setPos(q);
    block.hasOWord = true;
    if (o.keyword == "call") {
      while (in.peek() == '[')
        o.arguments.push_back(in.bracket());
    } else if (o.keyword == "while" || o.keyword == "if" || o.keyword == "elseif" ||
               o.keyword == "repeat") {
      if (in.peek() != '[') in.fail("'[' starting the condition of O-" + o.keyword);
      o.arguments.push_back(in.bracket());
    } else if ((o.keyword == "return" || o.keyword == "endsub") && in.peek() == '[') {
      o.arguments.push_back(in.bracket());
    }
    if (!in.atEnd()) in.fail("the end of the O-" + o.keyword + " line");
    return block;
  }

  while (!in.atEnd()) {
    const char letter = in.peek();
    const int column = in.column();
    if (letter == '#') {
      readAssignment(in, block, params);
      continue;
    }
    if (letter == ',') {  // a corner word: ",r15" or ",c8"
      in.setPos(in.pos() + 1);
      const char kind = in.peek();
      if (kind != 'r' && kind != 'c') in.fail("R or C after ',' (a corner word: ,R15 or ,C8)");
      if (block.corner) in.fail("one corner word on a line");
      in.setPos(in.pos() + 1);
      const std::size_t valueAt = in.pos();
      CornerWord c;
      c.kind = kind == 'r' ? 'R' : 'C';
      c.column = column;
      c.value = in.real();
      if (!std::isfinite(c.value) || !(c.value > 0.0))
        in.failAt(valueAt, std::string("expected a positive corner ,") + c.kind + ", found " +
                               formatNumber(c.value));
      block.corner = c;
      continue;
    }
    const bool polar = letter == '@' || letter == '^';
    if ((!std::isalpha(static_cast<unsigned char>(letter)) && !polar) || letter == 'o') {
      in.fail("a word letter (G, M, X, F, ...)");
    }
    if (letter == 'n') {
      in.fail("a word (N line numbers go first on the line)");
    }
    in.setPos(in.pos() + 1);
    Word w;
    w.letter = polar ? letter : static_cast<char>(std::toupper(static_cast<unsigned char>(letter)));
    w.column = column;
    const std::size_t valueAt = in.pos();
    w.value = in.real();
    if (isVacant(w.value)) continue;  // a vacant variable's word is left out (Fanuc)
    if (!std::isfinite(w.value))
      in.failAt(valueAt, std::string("expected a finite value of ") + w.letter + ", found " +
                             (std::isnan(w.value) ? "nan" : "an infinite one"));
    w.endColumn = compact.column(in.pos() - 1) + 1;
    block.words.push_back(w);
  }
  return block;
}

bool peekProgramNumber(std::string_view line, std::string& number) {
  try {
    const Compact compact(line, nullptr);
    const std::string& s = compact.text();
    const std::size_t p = wordsStart(s);
    if (!isProgramNumber(s, p)) return false;
    const std::size_t first = s.find_first_not_of('0', p + 1);
    number = first == std::string::npos ? "0" : s.substr(first);
    return true;
  } catch (const ParseFailure&) {
    return false;
  }
}

MacroStatement::Kind peekMacroLoop(std::string_view line, int& loop) {
  try {
    const Compact compact(line, nullptr);
    const std::string& s = compact.text();
    std::size_t p = wordsStart(s);
    MacroStatement::Kind kind = MacroStatement::None;
    if (s.compare(p, 6, "while[") == 0) {
      // the loop number after the condition's last "do"
      const std::size_t d = s.rfind("do");
      if (d == std::string::npos || d < p) return MacroStatement::None;
      p = d + 2;
      kind = MacroStatement::While;
    } else if (s.compare(p, 2, "do") == 0) {
      p += 2;
      kind = MacroStatement::Do;
    } else if (s.compare(p, 3, "end") == 0) {
      p += 3;
      kind = MacroStatement::End;
    } else {
      return MacroStatement::None;
    }
    const std::size_t digits = p;
    int n = 0;
    while (p < s.size() && std::isdigit(static_cast<unsigned char>(s[p])) && p - digits < 6)
      n = 10 * n + (s[p++] - '0');
    if (p == digits || p != s.size()) return MacroStatement::None;
    loop = n;
    return kind;
  } catch (const ParseFailure&) {
    return MacroStatement::None;
  }
}

bool peekLineNumber(std::string_view line, double& number) {
  try {
    const Compact compact(line, nullptr);
    const std::string& s = compact.text();
    const std::size_t n = !s.empty() && s[0] == '/' ? 1 : 0;
    std::size_t end = n;
    skipLineNumber(s, end);
    if (end == n) return false;
    const auto r = std::from_chars(s.data() + n + 1, s.data() + end, number);
    return r.ec == std::errc();
  } catch (const ParseFailure&) {
    return false;
  }
}

bool peekOWord(std::string_view line, std::string& label, std::string& keyword) {
  try {
    const Compact compact(line, nullptr);
    const std::string& s = compact.text();
    std::size_t p = wordsStart(s);
    return readOWordHead(s, p, label, keyword);
  } catch (const ParseFailure&) {
    return false;
  }
}

}  // namespace engage::gcode
