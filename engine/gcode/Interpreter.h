#pragma once
/// \file Interpreter.h
/// The RS274/NGC interpreter behind GcodeReader.h (private to engine/gcode/): the modal state,
/// parameters, call stack and the moves it emits. Its members are defined by concern, as
/// LinuxCNC splits rs274ngc: Interpreter.cpp (the run loop, one block, modal groups, parameters,
/// the tool table), InterpreterFlow.cpp (O-word control flow, subroutines, M98/M99),
/// InterpreterMotion.cpp (lines, arcs, splines, probing, threading, cutter compensation) and
/// InterpreterCycles.cpp (canned drilling cycles, lathe cycles). The G and M codes by name:
/// GcodeCodes.h.

#include "cutters/Numbers.h"
#include "engine/gcode/CutterComp.h"
#include "engine/gcode/GcodeCodes.h"
#include "engine/gcode/GcodeError.h"
#include "engine/gcode/GcodeReader.h"
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

namespace engage::gcode {

using Eigen::Vector3d;

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

/// One loaded source file with its O-word index.
struct SourceFile {
  std::string name;
  std::string folder;
  std::vector<std::string> lines;
  /// label -> (line index, keyword), in line order.
  std::unordered_map<std::string, std::vector<std::pair<int, std::string>>> labels;
  /// Fanuc/Haas macro B's index of the file, made by macroIndex() on the first GOTO, M97 or
  /// loop that needs it: each line's N number (NaN where it has none) and loop statement
  /// (WHILE .. DO m, DO m, END m: kind and m; None elsewhere), and the lines that open a
  /// program (an O number), in order.
  struct MacroIndex {
    std::vector<double> lineNumbers;
    std::vector<std::pair<gcode::MacroStatement::Kind, int>> loops;
    std::vector<int> programStarts;
  };
  const MacroIndex& macroIndex() const;

 private:
  mutable std::unique_ptr<MacroIndex> macroIndex_;
};

/// A source file from its text: its lines and the O-word labels they open.
std::unique_ptr<SourceFile> makeSource(const std::string& name, const std::string& text);

/// The text of the program at `path`, at most 1 GiB. Throws Error naming the file.
std::string readFile(const std::string& path);

/// The interpreter: modal state, parameters, call stack, and the moves it emits.
class Interpreter final : public gcode::ParameterSource {
 public:
  Interpreter(const ReaderOptions& options);

  Toolpath run(std::unique_ptr<SourceFile> main);

  /// With a machine: every move within its travel, then moved from the machine's coordinates
  /// into G54's frame.
  void toWorkFrame(const MachineSetup& m);
  /// A GcodeError at the move's line where it takes an axis beyond the machine's travel.
  void checkTravel(const MachineSetup& m, const Move& move) const;

  // ParameterSource
  double numbered(int n) const override;
  bool named(const std::string& name, double& value) const override;

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
    /// A G65 macro call (also m98: it ends with M99): the caller's locals #1-#33, back on
    /// return.
    bool g65 = false;
    std::array<double, 33> callerLocals{};
  };

  // ---------------------------------------------------------------- errors
  [[noreturn]] void fail(int column, const std::string& message) const;
  /// fail() with a compensation error, saying what to do when the program is one of CAM wear
  /// compensation read as control compensation.
  [[noreturn]] void failCompensation(int column, const CompensationError& e) const;

  // ---------------------------------------------------------------- units and frames
  double unit() const { return inch_ ? kInch : 1.0; }
  /// A length in program units with its unit, for messages.
  std::string length(double programValue) const;
  Vector3d workOffset() const;
  Vector3d programPosition() const { return (pos_ - workOffset()) / unit(); }
  Vector3d toMachine(const Vector3d& program) const { return program * unit() + workOffset(); }

  /// Converts every stored length parameter when G20/G21 changes the program units.
  void convertStoredLengths(double factor);

  // ---------------------------------------------------------------- tool table
  void readToolTable(const std::string& path);

  // ---------------------------------------------------------------- the run loop
  /// Runs lines from line_ on. With `returnDepth` > 0 it runs a call whose frame is at that
  /// depth and returns when the call does.
  void execute(std::size_t returnDepth = 0);

  void assign(const gcode::Assignment& a);

  // ---------------------------------------------------------------- O-words
  const std::vector<std::pair<int, std::string>>& labelEntries(const std::string& label,
                                                               int column) const;
  /// First entry of `label` after line `from` whose keyword is one of `keywords`.
  int findForward(const std::string& label, int from, std::initializer_list<const char*> keywords,
                  int column, const char* expected) const;
  int findBackward(const std::string& label, int from, const char* keyword, int column) const;
  bool hasKeywordBefore(const std::string& label, int from, const char* keyword) const;

  void controlFlow(const Block& b);

  /// From a false if/elseif at line_, move to the next branch that runs.
  void nextBranch(const std::string& label, int column);

  void loopJump(const std::string& label, bool isBreak, int column);

  /// The file and line where `label` opens as `keyword` ("sub": an O-sub; "program": an M98
  /// subprogram's O line): in this file, the main file, files already read, then `fileName`
  /// (if not empty) beside the main file or on the search path, read in. Such a file without
  /// the label starts at its first line (line -1) when `wholeFile`. {-1, -1}: found nowhere.
  std::pair<int, int> findLabel(const std::string& label, const char* keyword,
                                const std::string& fileName, bool wholeFile);

  /// The file and line of subroutine `label`'s O-sub (findLabel; a <name> label may be in
  /// name.ngc).
  std::pair<int, int> findSubroutine(const std::string& label, int column);

  void call(const gcode::OWord& o);

  // ---------------------------------------------------------------- one block
  /// Slot of a word letter: A-Z, then '@' (polar radius) and '^' (polar angle).
  static std::size_t slot(char c);
  struct Words {
    std::array<std::optional<double>, 28> v;
    std::array<int, 28> col{};
    std::vector<std::pair<int, int>> g;       ///< (code x10, column)
    bool otherAxes = false;                   ///< A, B, C, U, V or W words on the line
    std::optional<gcode::CornerWord> corner;  ///< ",R" or ",C" on the line
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

  Words collect(const Block& b);

  /// Executes a block in LinuxCNC's order; true when the program ends.
  bool executeBlock(const Block& b);
  /// executeBlock's parts, in its order: codes that are read but not run (a GcodeError naming
  /// the word); feed mode, F, S, T, tool change and spindle; dwell, plane, units, cutter
  /// compensation, tool length, coordinate system and the distance and retract modes (G7
  /// halves the block's X word, hence `w` is changed).
  void refuseUnsupported(const Words& w) const;
  void feedSpindleAndTool(const Words& w);
  void modes(Words& w);
  /// Tool centre point control (G43.4, G234, G49), Haas's dynamic work offset (G254, G255) and
  /// Fanuc's tilted work plane (G68.2, G53.1, G69): whether X, Y, Z are the tip on the part,
  /// and in which frame.
  void tipModes(const Words& w);
  /// pos_ turned into the tip on the part (`held`) or the joints that put it there, at the
  /// current angles, and tipHeld_ set: a controller switching TCP on reads its position back.
  void holdTip(bool held);
  /// Whether the modes in force make X, Y, Z the tip on the part.
  bool tipWanted() const { return machineTcp() || tcpCode_ || dwo_ || frame_ != 0; }
  bool machineTcp() const { return options_.machine && options_.machine->kinematics.tcp; }
  /// The rotary axes A, B, C now, degrees.
  Vector3d rotaryNow() const {
    return {otherAxisPosition_[0], otherAxisPosition_[1], otherAxisPosition_[2]};
  }
  /// G53.1: the rotary axes turned (a rapid, the joints still) so the tool points along the
  /// tilted plane's Z.
  void alignToPlane(int column);
  /// G43.5 (Fanuc's tool centre point control type 2): the line's I, J, K (an omitted one 0)
  /// are the tool's axis at its end, in the program's frame (the tilted plane's under G68.2),
  /// and the rotary axes go to the chain's angles for it nearest the present ones. Rotary
  /// words, arcs and cycles with I, J, K, Q (the tool's inclination) and P1 (tool posture
  /// control) on the G43.5 line, and I, J, K on it on a machine that turns the table, are
  /// refused at their column as the controller refuses them.
  void toolVector(const Words& w, int mode);

  /// M98 P<program> [L<times>]: runs O<program> (in this program, or <program>.ngc beside
  /// it) until its M99, L times. With --dialect fanuc and no L, a P of more than four digits
  /// carries the count in its leading digits (P30001234: O1234 three times).
  void subprogramCall(const Words& w);

  /// M99: back after the M98, M97 or G65 that called, or once more from the subprogram's
  /// start.
  void subprogramReturn(int column);

  /// Haas M97 P<n> [L<times>]: runs this program from its line N<n> until M99, L times.
  void localSubprogramCall(const Words& w);

  /// Fanuc/Haas G65 P<program> [L<times>] <arguments>: a macro call; the arguments A-Z
  /// (but G, L, N, O, P) into a fresh set of locals #1-#26 as Fanuc's argument
  /// specification I, the others vacant; the caller's back after the macro's M99. The run loop
  /// goes on with the line after the macro's O line (or the G65's, for L0).
  void macroCall(const Block& b);

  /// Starts a subprogram frame (M98, M97, G65) at file `file`, line `line` (the run loop goes
  /// on with the line after it), run `times` times.
  Frame& enterSubprogram(int file, int line, long times, int column);

  // ---------------------------------------------------------------- custom macro B
  /// Fanuc and Haas (custom macro B and G65): the dialects that run them.
  bool fanucLike() const {
    return options_.dialect == Dialect::Fanuc || options_.dialect == Dialect::Haas;
  }
  /// "LinuxCNC", "Fanuc", "Haas" or "grbl", for messages.
  std::string dialectName() const {
    switch (options_.dialect) {
      case Dialect::Fanuc:
        return "Fanuc";
      case Dialect::Haas:
        return "Haas";
      case Dialect::Grbl:
        return "grbl";
      default:
        return "LinuxCNC";
    }
  }
  /// IF .. GOTO, IF .. THEN, WHILE .. DO, DO, END, GOTO at line_.
  void macroFlow(const Block& b);
  /// The line GOTO n jumps to: the line N<n> of the program (O number) it is in, searched
  /// forward from the current line, then from the program's start.
  int lineNumbered(double n, int column) const;
  /// The END m closing the WHILE .. DO m / DO m at line_, or the WHILE / DO opening the END m
  /// there.
  int loopPartner(const gcode::MacroStatement& m, int column) const;
  /// A Fanuc or Haas system variable's value for reading (true), or false when `n` is an
  /// ordinary variable; throws std::out_of_range with the message for one that needs a
  /// machine.
  bool systemVariable(int n, double& value) const;
  /// Haas NGC variables without a legacy number (#10200-#10499, #10700-#10799).
  std::map<int, double> extendedVariables_;

  void saveModal();
  void restoreModal();

  void nonModal(int code, const Words& w);

  // ---------------------------------------------------------------- motion
  /// Target of the axis words in machine coordinates (mm).
  Vector3d target(const Words& w, bool machineCoords) const;

  /// LinuxCNC polar words in the XY plane, program units: @ radius and ^ angle (degrees)
  /// about the program origin; absolute in G90, added to the current radius and angle in G91.
  Eigen::Vector2d polarTarget(const Words& w, const Eigen::Vector2d& current) const;

  Move base(MoveKind kind) const;

  /// Index of the current executed line in Toolpath::blocks, recording it on first use.
  int recordBlock() const;
  int fileIndexInOutput() const;

  /// Feed of a move of `length` mm under the active feed mode, mm/min.
  double feedFor(double length, const Words& w, int column);

  void emitLinear(MoveKind kind, const Vector3d& end, double feed = 0.0);

  void motion(const Words& w, bool explicitMotion, bool machineCoords);

  /// G33 (spindle-synchronised line) and G33.1 (rigid tapping: in to the target and back
  /// out to the start). The feed is the pitch K times the spindle speed.
  void synchronised(const Words& w, int column);

  /// Note the first sign that the program is for a lathe.
  void markLathe(const std::string& what);

  /// G70-G72, LinuxCNC's lathe cycles: a rapid to the cycle's start point, the profile read
  /// from subroutine Q (readLatheProfile), and the cycle's moves (LatheCycle.h) run as
  /// G0/G1/G2/G3 blocks of the cycle's line, with absolute arc centres.
  void latheCycle(const Words& w, int column);

  /// The profile of a lathe cycle from `start` (program units): subroutine `label` called
  /// and run as LinuxCNC does, its control lines and parameter assignments executed, its
  /// motion lines read into segments instead of moving (the position that #<_x>, #<_z> and
  /// #5420-#5422 report follows the profile's points meanwhile).
  std::vector<gcode::LatheSegment> readLatheProfile(const std::string& label, int column,
                                                    gcode::LathePoint start);

  /// One motion line of a lathe profile: a segment from the last point to its X and Z (or
  /// the last point moved by U and W), with a corner finish after it for an A (fillet) or
  /// C (chamfer) word.
  void profileBlock(const Block& b);

  /// G38.2-G38.5. Without a part to touch, the probe runs to its target and, as LinuxCNC's
  /// stand-alone interpreter has it, stops 0.254 mm (0.010 in) back towards the start:
  /// engage makes that back-off a feed move (a real probe also stops just past contact).
  /// #5061-#5063 hold the target (program coordinates), #5070 = 0 (no contact), so probing loops
  /// end as they do there.
  void probe(const Words& w, int column);

  void arc(const Words& w, int column);

  /// A straight move while compensation offsets the path: it goes to `end` as programmed (in
  /// pos_), the tool to its offset (CutterComp.h).
  void compensated(MoveKind kind, const Vector3d& end, double feed, int column);

  /// G40, G41, G41.1, G42, G42.1 (`code` x 10).
  void compensation(int code, const Words& w);

  /// Codes LinuxCNC refuses while compensation is on.
  void refuseWithCompensation(const Words& w, bool onBefore);

  void spline(const Words& w, int column);

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

  void emitSpline(const std::vector<Eigen::Vector2d>& pts, const Words& w, int column);

  void nurbsPoint(const Words& w, int column);

  void nurbsEnd(const Words& w, int column);

  // ---------------------------------------------------------------- canned cycles (G17)
  void cycle(const Words& w, int column, bool explicitMotion);

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
  /// A G1 with a corner word, waiting for the next move: its index in out_.moves and where
  /// the word is (for messages).
  struct PendingCorner {
    std::size_t move = 0;
    gcode::CornerWord word;
    int file = 0, line = 0;
  };
  std::optional<PendingCorner> corner_;
  /// Round or chamfer the corner between the pending corner's move and the move after it.
  void applyCorner();
  [[noreturn]] void failCorner(const std::string& found) const;
  const Block* currentBlock_ = nullptr;  ///< the line being executed
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
  bool arcNotAllowed_ = false;           ///< the move after G40 must be straight
  bool compensationByRegister_ = false;  ///< the last G41/G42 took its radius from a D register
  bool startKnown_ = false;  ///< the start position is where the tool is (see ReaderOptions)
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
  bool tcpCode_ = false;     ///< G43.4, G43.5 or G234 in force (until G43, G43.1, G49)
  bool tcpVector_ = false;   ///< G43.5 in force: I, J, K are the tool's axis
  bool dwo_ = false;         ///< G254 in force (until G255)
  std::uint32_t frame_ = 0;  ///< the tilted work plane in force: 1 + index in out_.frames
  bool tipHeld_ = false;     ///< pos_ is the tip on the part, not the joints (Move::tipHeld)
  bool otherAxes_ = false;   ///< the current line moves a rotary or UVW axis
  std::array<double, 6> otherAxisPosition_{};  ///< A, B, C, U, V, W (program units)
  int motion_ = G_80;        ///< G80: axis words need a motion word first, as in LinuxCNC
  int motionBefore_ = G_80;  ///< motion mode before the current block
  bool cycleActive_ = false;
  bool cycleInitialValid_ = false;
  double cycleInitial_ = 0.0;  ///< mm, machine Z where the current run of cycles began
  double cycleR_ = 0.0, cycleZ_ = 0.0, cycleQ_ = 0.0;
  std::optional<Eigen::Vector2d> lastCubic_;
  std::vector<std::pair<Eigen::Vector2d, double>> nurbs_;
  int nurbsOrder_ = 3;
  int nurbsLine_ = 0;
};

}  // namespace engage::gcode
