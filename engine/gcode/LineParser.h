#pragma once
/// \file LineParser.h
/// Reads one line of RS274/NGC (LinuxCNC dialect) into a Block, evaluating expressions and
/// parameter references against the values they have before the line (assignments on the
/// line take effect after it, as in LinuxCNC).
///
/// Syntax: letters are case-insensitive; spaces and tabs are ignored outside comments;
/// `( )` comments, `;` comments to the end of the line; `/` block delete at the start;
/// numbers without exponents; `[expr]` with ** * / MOD + - EQ NE GT GE LT LE AND OR XOR,
/// functions ABS ACOS ASIN ATAN[a]/[b] COS EXP FIX FUP ROUND LN SIN SQRT TAN EXISTS (angles in
/// degrees); parameters #n, #[expr], #<name>; assignments #n=value, #<name>=value; O-words;
/// Fanuc/Haas macro statements (IF, WHILE, DO, END, GOTO).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace engage::gcode {

/// Fanuc's vacant variable (#0, a local a G65 call gave no argument for): a NaN of its own, so
/// that it passes through a bare reference (#2=#1 leaves #2 vacant; X#1 leaves X out) and reads
/// as 0 in arithmetic and ordering, equal only to another vacant in EQ and NE.
double vacantValue();
bool isVacant(double v);

/// Where a line parser reads and checks parameters.
class ParameterSource {
 public:
  virtual ~ParameterSource() = default;
  /// Value of numbered parameter n; throws std::out_of_range message text for a bad n.
  virtual double numbered(int n) const = 0;
  /// Value of a named parameter (name lower-cased, spaces removed); false when unset.
  virtual bool named(const std::string& name, double& value) const = 0;
};

/// One word such as G1 or X10.5: letter upper-cased ('@' and '^' for LinuxCNC's polar
/// radius and angle), value evaluated; 1-based column.
struct Word {
  char letter = 0;
  double value = 0.0;
  int column = 0;
  int endColumn = 0;  ///< 1-based column just after the word's last character
};

/// #n = v or #<name> = v.
struct Assignment {
  int number = 0;    ///< numbered parameter, when name is empty
  std::string name;  ///< named parameter (lower case)
  double value = 0.0;
  int column = 0;
};

/// An O-word statement: o100 sub, o<name> call [1] [2], o1 while [#1 LT 3], ...
struct OWord {
  std::string label;              ///< "100" or "<name>" (lower case)
  std::string keyword;            ///< sub endsub call return do while endwhile if elseif else endif
                                  ///< repeat endrepeat break continue
  std::vector<double> arguments;  ///< call arguments, or the one expression of while/if/...
  int column = 0;
};

/// One parsed line.
/// A Fanuc/Haas corner word after a G1 (", R 15": round the corner to the next move with
/// radius 15; ", C 8": chamfer it 8 from the corner along each move).
struct CornerWord {
  char kind = 'R';  ///< 'R' or 'C'
  double value = 0.0;
  int column = 0;
};

/// A Fanuc/Haas custom macro B statement: IF [c] GOTO n, IF [c] THEN #i=v, WHILE [c] DO m,
/// DO m, END m, GOTO n. Read in every dialect; run by the Fanuc and Haas ones.
struct MacroStatement {
  enum Kind { None, IfGoto, IfThen, While, Do, End, Goto };
  Kind kind = None;
  double condition = 1.0;  ///< IF, WHILE: the bracket's value (0: false)
  double target = 0.0;     ///< GOTO: the N number; WHILE .. DO, DO, END: the loop's number
  int column = 0;
};

struct Block {
  bool blockDelete = false;  ///< the line starts with '/'
  bool percent = false;      ///< the line is a '%' program delimiter
  std::vector<Word> words;
  std::optional<CornerWord> corner;
  std::vector<Assignment> assignments;
  bool hasOWord = false;
  OWord oword;
  /// IF [c] THEN keeps its assignments (in `assignments`) only where c holds.
  MacroStatement macro;
  std::vector<std::string> comments;
};

/// Thrown by the parser: column (1-based) and message "expected ..., found ...".
struct ParseFailure {
  int column;
  std::string message;
};

/// Parse one line. Throws ParseFailure.
Block parseLine(std::string_view line, const ParameterSource& params);

/// Only the O-word of a line, without evaluating anything (for indexing control flow);
/// false when the line has none. Never throws.
bool peekOWord(std::string_view line, std::string& label, std::string& keyword);

/// A line's macro loop statement without evaluating anything (for matching WHILE/DO with END):
/// kind While, Do or End and its loop number; None for any other line. Never throws.
MacroStatement::Kind peekMacroLoop(std::string_view line, int& loop);

/// A line's N number (after an optional '/'), for GOTO; false when it has none. Never throws.
bool peekLineNumber(std::string_view line, double& number);

/// A program number alone on its line ("O2000", "O0100 (POCKET)"), the label M98 P calls,
/// as a number without leading zeros; false for any other line. Never throws.
bool peekProgramNumber(std::string_view line, std::string& number);

}  // namespace engage::gcode
