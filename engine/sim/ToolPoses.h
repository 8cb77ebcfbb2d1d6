#pragma once
/// \file ToolPoses.h
/// Where the tool is over a move in the part's frame: the move's axis positions (X, Y, Z in
/// the work frame, A, B, C in degrees, interpolated linearly as a controller does) through the
/// machine's kinematics (engine/kinematics/Kinematics.h). A 3-axis move is its own tip path.

#include "cutters/Sweep.h"
#include "engine/gcode/Toolpath.h"

namespace engage {

/// Whether move `m` holds the tool off +Z in the part's frame anywhere (where it turns the
/// rotary axes, at 32 points along it).
bool tiltsTool(const Move& m, const Kinematics& k);
/// Whether any move of `path` does.
bool tiltsTool(const Toolpath& path);

/// The tip path of move `m` between fractions t0 and t1 of it, in the part's frame, with the
/// tool's axis at both ends: for a machine without rotary kinematics the move's own path (a
/// line, an XY arc or helix, or a polyline of 8 pieces for other arcs and splines); where the
/// rotary axes hold still, that path carried by the kinematics and the move's tilted work plane
/// (an XY arc stays one while the tool stays vertical and the plane level, else a polyline of
/// 8 pieces); where they turn, the tip at 8 pieces' ends.
StepPath stepPath(const Move& m, double t0, double t1, const Kinematics& k = {},
                  const FeatureFrame* frame = nullptr);
/// The same for a move of `path` (its kinematics and the move's tilted work plane).
StepPath stepPath(const Move& m, double t0, double t1, const Toolpath& path);

/// The tool's pose at move `m`'s axis positions `xyz` (the move's coordinates, mm) and `abc`
/// (degrees) in the part's frame: through its tilted work plane `frame` (if any) and the
/// kinematics, with the tip held where the machine or the move says so.
ToolPose movePose(const Move& m, const Kinematics& k, const FeatureFrame* frame,
                  const Eigen::Vector3d& xyz, const Eigen::Vector3d& abc);

/// How far any point of a tool reaching `reach` mm from its tip (the hypotenuse of its radius
/// and height) travels over move `m` in the part's frame, at most (mm): the move's length where
/// the tool keeps its axis and the kinematics do not carry the tip on a curve.
double moveTravel(const Move& m, const Kinematics& k, double reach);

/// The duration of feed move `m`, minutes, where it turns a rotary axis: inverse time (G93)
/// 1 / F, else as LinuxCNC takes F for it: along X, Y, Z where they move, in degrees per
/// minute of the rotary axes' motion where they alone move. 0 for rapids.
double rotaryMoveMinutes(const Move& m);

}  // namespace engage
