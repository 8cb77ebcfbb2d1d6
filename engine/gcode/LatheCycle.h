#pragma once
/// \file LatheCycle.h
/// LinuxCNC's lathe turning cycles G70 (finishing), G71 (roughing in passes along Z) and G72
/// (roughing in passes along X, facing), with their variants G7x.1 (no pockets) and G7x.2
/// (pockets only), as the geometry of the XZ plane: a profile in, the moves out.
///
/// The moves are those LinuxCNC 2.9's interpreter makes (its rs274 prints them): the profile
/// is normalised by mirrors (and for G72 a quarter turn) so that X and Z both decrease along
/// it, its corner finishes are shaped, it is offset by the finishing allowance in steps no
/// larger than half its shortest segment (gaps at convex corners closed by arcs), and cut in
/// passes I apart, each pass leaving by R at 45°; pockets (where the profile rises again) are
/// cut after the main passes, or not (G7x.1), or alone (G7x.2). Some of LinuxCNC's choices are
/// kept as they are so that the path is the one the machine runs: see LatheCycle.cpp.
///
/// Points of the XZ plane are complex numbers, real part Z, imaginary part X, in program
/// units; mirrors and the quarter turn are then one multiplication or conjugation.

#include <complex>
#include <stdexcept>
#include <vector>

namespace engage::gcode {

using LathePoint = std::complex<double>;  ///< Z + i X, program units

/// One profile element: a line, or an arc turning counter-clockwise (G3) or clockwise (G2)
/// about `centre` as seen in LinuxCNC's XZ plane (Z across, X up). A corner finish (the A
/// or C word of a profile line) is a segment of no length at the corner with `corner` set:
/// an arc for a fillet of radius A, a line for a chamfer of C; the cycle shapes it.
struct LatheSegment {
  bool arc = false;
  bool ccw = false;
  LathePoint start, end, centre;
  double corner = 0.0;
};

enum class LatheMoveKind { Rapid, Line, Arc };

/// One move of a cycle: to `end`; arcs about `centre`, counter-clockwise (G3) when ccw.
struct LatheMove {
  LatheMoveKind kind = LatheMoveKind::Line;
  LathePoint end, centre;
  bool ccw = false;
};

/// A G70/G71/G72 block's words (LinuxCNC's defaults where a word is absent).
struct LatheCycle {
  int code = 71;         ///< 70, 71 or 72
  int variant = 0;       ///< G71/G72: 0 (.0), 1 (.1: no pockets), 2 (.2: pockets only)
  LathePoint start;      ///< X and Z words, else the current position: where cutting starts
  double d = 0.0;        ///< D: finishing allowance (G71/G72); G70: first pass's distance
  double e = 0.0;        ///< E: G70 last pass's distance to the profile
  double passes = 1.0;   ///< P: G70 number of passes
  double depth = 1.0;    ///< I: G71/G72 depth of cut per pass
  double retract = 0.5;  ///< R: G71/G72 retraction (at 45° from the cut)
  double u = 0.0;        ///< U: G71/G72 shift of the profile along X
  double w = 0.0;        ///< W: G71/G72 shift of the profile along Z
};

/// A cycle LinuxCNC also refuses, or one too large to run (more than a million moves).
class LatheCycleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The cycle's moves (after the rapid to the start point, which the reader makes). `profile`
/// starts at `cycle.start`: its first segment runs from the start to the subroutine's first
/// point; with fewer than two segments there is no cycle (no moves), as in LinuxCNC. Throws
/// LatheCycleError.
std::vector<LatheMove> latheCycleMoves(std::vector<LatheSegment> profile, const LatheCycle& cycle);

}  // namespace engage::gcode
