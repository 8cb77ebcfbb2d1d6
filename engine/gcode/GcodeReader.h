#pragma once
/// \file GcodeReader.h
/// Interprets RS274/NGC milling programs as LinuxCNC does, into a Toolpath (mm, machine
/// coordinates after work offsets, see Toolpath.h).
///
/// Supported: G0 G1 G2 G3 (IJK centre, R form with negative R, full circles, helices, P turns,
/// all three planes), G4, G5 G5.1 G5.2/G5.3 (cubic, quadratic and NURBS splines, flattened to
/// 0.001 mm), G10 L1/L2/L10/L11/L20, G17 G18 G19, G20 G21, G28 G28.1 G30 G30.1, G40, G43 G43.1
/// G49, G53, G54-G59.3, G61 G61.1 G64, G73 G80 G81 G82 G83 G85 G89 with G98 G99 (XY plane),
/// G90 G91 G90.1 G91.1, G92 G92.1 G92.2 G92.3, G93 G94 G95, G96 G97, F S T M0 M1 M2 M3 M4 M5
/// M6 M7 M8 M9 M30 M48-M53 M60 M61 M62-M68 M70-M73, N, comments, %, block delete, parameters,
/// expressions, O-word subroutines (in the program or in <name>.ngc beside it), loops and
/// conditionals, and M98/M99 subprograms (O<n> in the program or <n>.ngc beside it) as
/// LinuxCNC 2.9 and Fanuc/Haas controls run them.
///
/// Rotary and UVW words are read but stay out of the XYZ path (the move is marked otherAxes);
/// the rotary axes' positions ride on each move (Move::rotaryStart, rotaryEnd), and a machine
/// with kinematics refuses a rotary word of an axis it does not have.
///
/// Probing G38.2-G38.5 runs to the target and backs off 0.254 mm, as LinuxCNC's stand-alone
/// interpreter has it (#5061-#5063 = target, #5070 = 0); G33/G33.1 feed at K x S; G7 reads X
/// words as diameters.
///
/// Cutter radius compensation G41, G41.1, G42, G42.1, G40 in G17 and G18, as LinuxCNC 2.9
/// (CutterComp.h), with radii from the tool table's D column or the D word.
///
/// Lathe programs: G7/G8 diameter mode and the turning cycles G70-G72 with their .1/.2
/// variants (LatheCycle.h), in the XZ plane.
///
/// Not supported, each a GcodeError naming the word: the threading cycle G76, boring cycles
/// G86-G88, canned cycles outside G17, user M codes M100-M199.

#include "cutters/Error.h"
#include "engine/gcode/Toolpath.h"
#include "engine/kinematics/Kinematics.h"

#include <cstddef>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace engage {

/// Which controller's reading of the words they differ on: LinuxCNC (the default); Fanuc (M98 P
/// with the repeat count in its leading digits, custom macro B: G65 calls with arguments, IF,
/// WHILE, GOTO, vacant variables, the system variables #2001-#5043 a program reads); Haas
/// (Fanuc's, with the NGC variables #10000-#10999 and M97 local subprograms); grbl (the
/// off-plane centre word of an arc, which FreeCAD's grbl post writes, ignored).
enum class Dialect { LinuxCNC, Fanuc, Haas, Grbl };

/// The machine a program runs on (engine/run/Machine.h reads it from a file), in its own
/// coordinates (mm): where G54's origin is, where G28 and G30 go, where the tool tip is when
/// the program starts, and how far the axes travel. Without one, the machine's coordinates are
/// the program's (G54 at the machine's zero) and the tool starts at the program's origin.
struct MachineSetup {
  std::string name;                           ///< the file it came from, for messages
  Eigen::Vector3d workOffset{0.0, 0.0, 0.0};  ///< G54's origin
  Eigen::Vector3d g28{0.0, 0.0, 0.0};
  Eigen::Vector3d g30{0.0, 0.0, 0.0};
  Eigen::Vector3d start{0.0, 0.0, 0.0};  ///< the tool tip when the program starts
  bool limited = false;                  ///< travel limits given
  bool startInch = false;                ///< "startup_units": "in" (G20 at power-on)
  bool startUnitsGiven = false;          ///< the file says "startup_units"
  Eigen::Vector3d travelMin{0.0, 0.0, 0.0}, travelMax{0.0, 0.0, 0.0};
  /// Degrees: the travel of the rotary axes A, B, C; infinite where the machine sets none.
  Eigen::Vector3d rotaryMin = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  Eigen::Vector3d rotaryMax = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  /// The kinematic chain ("kinematics"): which rotary axes turn the tool relative to the part.
  Kinematics kinematics;
};

/// How to read a program.
struct ReaderOptions {
  Dialect dialect = Dialect::LinuxCNC;
  /// With a machine, the moves come out relative to G54's origin (so that a stock given in
  /// the program's coordinates stays where it is) and G53 moves, G28 and G30 go where the
  /// machine puts them; a move beyond its travel is an error.
  std::optional<MachineSetup> machine;
  /// LinuxCNC tool table (T P Z D ... lines); empty: every tool has zero length.
  std::string toolTable;
  /// The tool table's lengths are in inches (LinuxCNC's stand-alone rs274 default) rather
  /// than mm.
  bool toolTableInch = false;
  /// Tool diameters (mm) by number for G41/G42 where the tool table gives none (a tool
  /// library of another format: Fusion 360, FreeCAD, a CAMotics project).
  std::map<int, double> toolDiameters;
  /// G41/G42 with a D register: the register holds only the wear, the CAM having written the
  /// tool centre's path (Fusion 360's and Mastercam's "wear" compensation, common on Haas and
  /// Fanuc controls), so the path is offset by nothing; G41.1/G42.1 still offset by their D.
  /// Off: the register holds the tool's radius (control compensation).
  bool wearCompensation = false;
  /// mm: the diameter G41/G42 take for every tool when neither toolTable nor toolDiameters
  /// gives any (the one --tool of a run without a tool library); 0: none known.
  double soleToolDiameter = 0.0;
  /// Where a probing move G38.2/G38.3 from `from` to `to` (mm, the moves' frame) with tool
  /// `tool` in the spindle first touches the stock: the fraction of the move, above 1 for no
  /// contact. Set, the probe stops there and #5061-#5063 and #5070 say so as on the machine
  /// (G38.2 without contact is an error); unset, it runs to its target and backs off 0.254 mm
  /// as LinuxCNC's stand-alone rs274 does.
  std::function<double(const Eigen::Vector3d& from, const Eigen::Vector3d& to, int tool)>
      probeContact;
  /// Skip lines that start with '/' (the block delete switch); off as in LinuxCNC's default.
  bool blockDelete = false;
  /// Folders searched for o<name> call subroutine files (<name>.ngc); the program's own
  /// folder is always searched first.
  std::vector<std::string> subroutinePath;
  /// Safety limit on executed lines (loops that never end): a GcodeError beyond it.
  long long maxExecutedLines = 50'000'000;
  /// Safety limit on moves (a lathe cycle with a tiny depth of cut in a loop): a GcodeError
  /// beyond it.
  /// 10 million moves hold about 1.8 GB; the option --max-moves raises it.
  std::size_t maxMoves = 10'000'000;
  /// Why maxMoves is what it is, for the error (" (what 4.0 GB holds: --max-memory)"); empty:
  /// the option.
  std::string maxMovesWhy;
  /// Where the tool tip starts (mm, the moves' frame) and the tool in the spindle. By
  /// default an assumption, the program origin with no tool (or the machine's start);
  /// `startKnown` says it is where the machine is (an earlier program left it, the next file of
  /// a CAMotics project; --start), so that a G43 before the first move shifts it as on the
  /// machine.
  Eigen::Vector3d start{0.0, 0.0, 0.0};
  int startTool = 0;
  bool startKnown = false;
  /// The machine's start-up units are inches (G20 until the program says G21): Haas and
  /// Fanuc machines set up in inches, whose posts may write neither.
  bool startInch = false;
};

/// Read and interpret a program file. Throws GcodeError ("file:line:col: expected ..., found
/// ...") for anything it cannot interpret, Error when the file cannot be read.
Toolpath readProgram(const std::string& path, const ReaderOptions& options = {});

/// Read several programs run one after the other on one machine (a CAMotics project's files):
/// each starts where the last left the tool, with the tool it left in the spindle; the moves,
/// files and blocks of all in one Toolpath.
Toolpath readPrograms(const std::vector<std::string>& paths, const ReaderOptions& options = {});

/// Interpret program text; `name` is used in messages and as Toolpath::files[0].
Toolpath readProgramText(const std::string& text, const std::string& name,
                         const ReaderOptions& options = {});

}  // namespace engage
