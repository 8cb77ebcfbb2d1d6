#pragma once
/// \file Pocket.h
/// A small contour-parallel pocketing generator, the way the paper's examples were machined
/// (Figs 9, 11, 13: "contour method"): the pocket boundary (closed loops of lines and arcs,
/// islands allowed) is offset inward by the tool radius and then by the stepover until
/// nothing is left (polygon offsets by Clipper, Debian libpolyclipping), the rings are cut
/// from the inside out, level by level, and written as G-code with arcs fitted back where
/// the rings are round (an offset arc is a concentric arc).
///
/// Units: mm inside; the program is written in inches or millimetres.

#include "engine/gcode/Toolpath.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace engage {

/// A line or an arc in XY, mm. Arcs run from start to end about center, counter-clockwise
/// when `ccw`, and sweep at most half a turn (longer ones are split).
struct Element {
  bool arc = false;
  Eigen::Vector2d start{0.0, 0.0}, end{0.0, 0.0};
  Eigen::Vector2d center{0.0, 0.0};  ///< arcs
  bool ccw = false;                  ///< arcs: counter-clockwise (G3)
};

/// A closed loop: the end of each element is the start of the next, the last ends where the
/// first starts.
using Loop = std::vector<Element>;

/// A closed polygon as a loop of lines.
Loop polygonLoop(const std::vector<Eigen::Vector2d>& corners);

/// The closed loops of a boundary program: its feed moves (G1/G2/G3 in XY; Z is ignored;
/// splines become lines), split at rapids; each loop must end where it starts (within
/// 1e-4 mm). Throws Error naming the line of a loop that does not close, and Error when
/// there is no loop.
std::vector<Loop> boundaryLoops(const Toolpath& boundary);

/// A closed ring of the tool-centre path at one offset. Its lines and arcs are the exact
/// offsets of the boundary's lines and arcs (an offset arc is a concentric arc) and arcs of
/// radius `offset` about the boundary's inside corners, meeting where those curves cross.
struct Ring {
  std::vector<Element> elements;  ///< end of the last is the start of the first
  double offset = 0.0;            ///< distance from the boundary, mm
  int level = 0;                  ///< depth level (0: first)
  bool island = false;            ///< a ring around an island (material inside it)
  bool linked = false;            ///< reached from the previous ring's end by a straight feed move
};

/// Settings of the generator. Lengths mm, feeds mm/min.
struct PocketOptions {
  double toolRadius = 0.0;   ///< offset of the wall pass: the tool's radius at the floor
  double stepover = 0.0;     ///< between rings (at most 2 x toolRadius)
  double top = 0.0;          ///< Z of the stock top
  double depth = 0.0;        ///< pocket depth below `top`
  double stepDown = 0.0;     ///< depth per level (0: the whole depth at once)
  double safeZ = 0.0;        ///< retract height (must be above `top`)
  double feed = 0.0;         ///< cutting feed
  double plungeFeed = 0.0;   ///< feed of the vertical entries
  bool climb = true;         ///< climb milling with a clockwise (M3) spindle; else conventional
  double tolerance = 0.002;  ///< arc fitting and flattening tolerance
  bool inch = false;         ///< write the program in inches (G20)
};

/// The floor of a level, mm: top - min((level + 1) x stepDown, depth).
double levelZ(const PocketOptions& options, int level);

/// The rings, in cutting order (per level: each region from the inside out; regions that
/// split are cut one after the other). Throws ParameterError for bad options, Error when the
/// tool does not fit in the pocket.
std::vector<Ring> pocketRings(const std::vector<Loop>& boundary, const PocketOptions& options);

/// The whole program as G-code text: header comments (`comments`, one per line), units,
/// the rings with their links (a straight feed move where the next ring starts within two
/// stepovers and the link stays inside the pocket, else retract, rapid and plunge), M2.
/// `ringLines`, when given, receives the 1-based program line of each ring's first element.
std::string writePocketProgram(const std::vector<Ring>& rings, const PocketOptions& options,
                               const std::vector<std::string>& comments,
                               std::vector<int>* ringLines = nullptr);

}  // namespace engage
