// The machine's travel and work frame: every move within the joints' and rotary axes' travel
// (checkTravel), then the moves taken from the machine's coordinates into G54's frame.

#include "engine/gcode/Interpreter.h"

#include <algorithm>
#include <cmath>

namespace engage::gcode {

void Interpreter::checkTravel(const MachineSetup& m, const Move& move) const {
  auto refuse = [&](const std::string& travel, const std::string& found) {
    throw GcodeError(out_.files[static_cast<std::size_t>(move.file)], move.line, 1,
                     "expected moves within the travel of the machine (" + m.name + ": " + travel +
                         "), found one " + found);
  };
  for (int a = 0; a < 3; ++a)
    for (const double v : {move.rotaryStart[a], move.rotaryEnd[a]}) {
      if (v >= m.rotaryMin[a] - 1e-9 && v <= m.rotaryMax[a] + 1e-9) continue;
      const std::string axis(1, static_cast<char>('A' + a));
      auto deg = [](double x) { return formatNumber(x) + " deg"; };
      refuse(axis + " " + deg(m.rotaryMin[a]) + " to " + deg(m.rotaryMax[a]),
             "to " + axis + " " + deg(v));
    }
  if (!m.limited) return;
  // The travel limits are the joints'. They move evenly, and so stay between their ends, but
  // where the controller holds the tip while the rotary axes turn: there at every degree of
  // the turn too.
  const Kinematics& k = m.kinematics;
  const bool turning = move.tipHeld && k.rotary() && turnsRotary(move);
  const int pieces =
      turning ? std::max(1, static_cast<int>(std::ceil(
                                (move.rotaryEnd - move.rotaryStart).cwiseAbs().maxCoeff())))
              : 1;
  // The farthest beyond the travel, if any: its excess (mm), axis, value and sample.
  double worst = 1e-6, at = 0.0;
  int worstAxis = -1, worstSample = 0;
  for (int i = 1; i <= pieces; ++i) {
    const double t = static_cast<double>(i) / pieces;
    const Vector3d abc = move.rotaryStart + t * (move.rotaryEnd - move.rotaryStart);
    Vector3d joints = i == pieces ? move.end : pointAt(move, t);
    if (move.frame != 0) joints = out_.frames[move.frame - 1].toWork(joints);
    if (move.tipHeld && k.rotary()) joints = k.joints(joints - m.workOffset, abc) + m.workOffset;
    for (int a = 0; a < 3; ++a) {
      const double excess = std::max(m.travelMin[a] - joints[a], joints[a] - m.travelMax[a]);
      if (excess > worst) {
        worst = excess;
        at = joints[a];
        worstAxis = a;
        worstSample = i;
      }
    }
  }
  if (worstAxis < 0) return;
  auto mm = [](double x) { return formatNumber(x) + " mm"; };
  const std::string axis(1, static_cast<char>('X' + worstAxis));
  const bool end = worstSample == pieces;
  refuse(axis + " " + mm(m.travelMin[worstAxis]) + " to " + mm(m.travelMax[worstAxis]) +
             ", machine coordinates",
         (end ? "to " : "through ") + axis + " " + mm(at) +
             (end ? "" : " on its way, the rotary axes turning"));
}

void Interpreter::toWorkFrame(const MachineSetup& m) {
  for (const Move& move : out_.moves)
    checkTravel(m, move);
  // A plane's map of stored to work coordinates, both shifted: origin + turn * w0 - w0.
  for (FeatureFrame& f : out_.frames)
    f.origin += f.turn * m.workOffset - m.workOffset;
  for (Move& move : out_.moves) {
    move.start -= m.workOffset;
    move.end -= m.workOffset;
    move.workOffset -= m.workOffset;
    if (move.kind == MoveKind::Arc) move.center -= m.workOffset;
    for (Vector3d& p : move.points)
      p -= m.workOffset;
  }
}

}  // namespace engage::gcode
