#pragma once
/// \file Toolpath.h
/// The interpreted tool path: a list of moves in machine coordinates (mm), each pointing
/// back at its source file and line. Knows nothing of voxels or cutters.
///
/// Positions are the controlled point (the tool tip) in machine coordinates after work
/// offsets (G54-G59.3, G92), as LinuxCNC's interpreter reports them: tool length offsets
/// (G43) move the spindle, not the tip, and are not added.

#include "engine/kinematics/Kinematics.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace engage {

/// What a move does.
enum class MoveKind : std::uint8_t { Rapid, Line, Arc, Spline };

/// Arc plane (G17, G18, G19). Arcs turn about the plane's normal: +Z, +Y, +X respectively.
enum class Plane { XY, XZ, YZ };

/// Where a feed move's feed comes from: the F word (under the feed mode), the spindle
/// (G33, G33.1: pitch K x spindle speed), or a probing move (G38.x: the F word, but the
/// controller stops it on contact).
enum class FeedSource { Word, Spindle, Probe };

/// Feed mode the move was programmed in (G94, G93, G95).
enum class FeedMode { UnitsPerMinute, InverseTime, UnitsPerRevolution };

/// A plane's in-plane axes (a, b) and normal n, indices 0-2 for X-Z, such that (a, b, n) is
/// right-handed, and the letters of the arc-centre words for a and b: XY (x, y, z; I, J),
/// XZ (z, x, y; K, I), YZ (y, z, x; J, K).
struct PlaneAxes {
  int a, b, n;
  char ia, ib;
};
PlaneAxes planeAxes(Plane plane);

/// "rapid", "line", "arc", "spline".
const char* moveKindName(MoveKind kind);
/// "XY", "XZ", "YZ".
const char* planeName(Plane plane);

/// A tilted work plane (Fanuc G68.2): a move under it keeps its coordinates as programmed (in
/// the plane's frame, plus the work offset); the work frame's are `origin + turn * xyz` (mm).
struct FeatureFrame {
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  Eigen::Vector3d origin{0.0, 0.0, 0.0};
  Eigen::Vector3d toWork(const Eigen::Vector3d& xyz) const { return origin + turn * xyz; }
};

/// One interpreted move.
struct Move {
  MoveKind kind = MoveKind::Line;
  Eigen::Vector3d start{0.0, 0.0, 0.0};  ///< mm, machine coordinates
  Eigen::Vector3d end{0.0, 0.0, 0.0};    ///< mm
  /// Arcs: the centre, in the plane, at the start's height along the plane normal. mm.
  Eigen::Vector3d center{0.0, 0.0, 0.0};
  Plane plane = Plane::XY;
  /// Arcs: + counter-clockwise (G3), - clockwise (G2) about the plane normal; the magnitude
  /// is the P word (number of turns, 1 by default). 0 for other moves.
  int turns = 0;
  /// Splines: the line pieces approximating the curve within 0.001 mm, ending at `end`
  /// (the start is `start`). Empty for other moves.
  std::vector<Eigen::Vector3d> points;
  double feed = 0.0;        ///< programmed feed of the tool tip, mm/min (0 for rapids)
  double spindleRpm = 0.0;  ///< signed: + M3, - M4, 0 stopped
  int tool = 0;             ///< tool number in the spindle
  int file = 0;             ///< index into Toolpath::files
  int line = 0;             ///< 1-based source line
  int block = 0;            ///< index into Toolpath::blocks: the executed line it came from
  bool otherAxes = false;   ///< its line also commands A, B, C, U, V or W (not in the path)
  /// The rotary axes A, B, C at the move's start and end, degrees (the machine's kinematics
  /// turn the tool relative to the part by them: engine/kinematics/Kinematics.h).
  Eigen::Vector3d rotaryStart{0.0, 0.0, 0.0};
  Eigen::Vector3d rotaryEnd{0.0, 0.0, 0.0};
  /// X, Y, Z are the tool tip on the part (tool centre point control: Fanuc G43.4, Haas G234,
  /// Haas G254, a tilted work plane), not the machine's joints; see Kinematics.h.
  bool tipHeld = false;
  /// The program gives the tool's axis as I, J, K, not the rotary axes (Fanuc G43.5): a
  /// writer splitting the move writes the axis.
  bool axisVector = false;
  /// The tilted work plane the move was programmed in: 1 + its index in Toolpath::frames, 0
  /// for none.
  std::uint32_t frame = 0;
  /// Spindle and Probe feeds are not the schedule's to change (see fixedFeed()).
  FeedSource feedSource = FeedSource::Word;
  /// Spindle-synchronised motion and probing: a feed schedule must leave the feed as it is.
  bool fixedFeed() const { return feedSource != FeedSource::Word; }

  // How the move was programmed, so that a writer can emit it back in the same terms.
  bool inch = false;                ///< G20
  bool incremental = false;         ///< G91
  bool absoluteArcCenters = false;  ///< G90.1
  FeedMode feedMode = FeedMode::UnitsPerMinute;
  /// Inverse time (G93): the move's duration, min (1 / F); 0 in the other modes.
  double minutes = 0.0;
  /// Machine minus program coordinates (work offset + G92), mm.
  Eigen::Vector3d workOffset{0.0, 0.0, 0.0};
};

/// Where a word sits on its source line: [begin, end) 0-based character positions.
struct WordSpan {
  char letter = 0;  ///< upper case; '@' and '^' for polar words
  int begin = 0;
  int end = 0;
};

/// One executed source line that produced moves, with the positions of its words.
struct SourceBlock {
  int file = 0;
  int line = 0;  ///< 1-based
  std::vector<WordSpan> words;
};

/// The whole interpreted program.
/// A tool change (M6 with the prepared T, or M61 Q) where the program makes it.
struct ToolLoad {
  int tool = 0;
  int file = 0;               ///< index into Toolpath::files
  int line = 0;               ///< 1-based line of the M6 or M61
  std::size_t firstMove = 0;  ///< the index of the first move made after it
};

struct Toolpath {
  std::vector<Move> moves;
  std::vector<ToolLoad> toolLoads;  ///< the tool changes, in execution order
  std::vector<std::string> files;   ///< source files (main program first, then subroutine files)
  std::vector<SourceBlock> blocks;  ///< executed lines that produced moves, in execution order
  bool inch = false;                ///< the program's units (the last G20/G21 seen)
  bool unitsSet = false;            ///< the program says G20 or G21 (else the start-up units)
  /// A lathe program: the first line that says so (G7 diameter mode, a turning cycle), 0 if
  /// none, and what it is.
  int latheLine = 0;
  std::string lathe;
  /// M codes taken as machine functions that move no axis (a chip conveyor, a user M code
  /// whose script lives on the machine): each with where it is (file index, 1-based line).
  struct InertCode {
    int code = 0;  ///< the M number
    int file = 0, line = 0;
  };
  std::vector<InertCode> inert;
  /// G41/G42 read as control compensation that offset the path by nothing (D0, or a tool no
  /// table gives a diameter): the control would offset by its register, which engage does not
  /// know. Where each is (file index, 1-based line).
  struct Place {
    int file = 0, line = 0;
  };
  std::vector<Place> unoffsetCompensation;
  /// The machine's kinematic chain (its machine file's): how the moves' rotary axes turn the
  /// tool relative to the part.
  Kinematics kinematics;
  /// The tilted work planes the moves refer to (Move::frame).
  std::vector<FeatureFrame> frames;
  /// Move `m`'s tilted work plane, or nullptr.
  const FeatureFrame* frameOf(const Move& m) const {
    return m.frame == 0 ? nullptr : &frames[m.frame - 1];
  }
};

/// Arcs: radius in the plane, mm.
double arcRadius(const Move& arc);
/// Arcs: signed swept angle, radians (+ counter-clockwise about the plane normal).
double arcSweep(const Move& arc);
/// Path length of a move, mm (helices include the axial travel).
double moveLength(const Move& move);
/// Whether move `m` turns a rotary axis.
inline bool turnsRotary(const Move& m) {
  return m.rotaryStart != m.rotaryEnd;
}
/// Position at arc length fraction t in [0, 1] along a move (arcs and helices exactly,
/// splines along their line pieces). mm.
Eigen::Vector3d pointAt(const Move& move, double t);

}  // namespace engage
