// Five-axis modes: tool centre point control (Fanuc G43.4, and G43.5 with the tool's axis as I,
// J, K; Haas G234; cancelled by G49 or G43), Haas's dynamic work offset (G254, G255) and Fanuc's
// tilted work plane (G68.2, G53.1, G69). Under any of them X, Y, Z are the tool tip on the part
// (Move::tipHeld); under G68.2 they are in the plane's frame (Move::frame, Toolpath::frames).

#include "engine/gcode/Interpreter.h"

#include <Eigen/Geometry>

namespace engage::gcode {
namespace {

Eigen::Matrix3d turn(double degrees, const Vector3d& about) {
  return Eigen::AngleAxisd(degrees * kPi / 180.0, about).toRotationMatrix();
}

}  // namespace

void Interpreter::holdTip(bool held) {
  if (held == tipHeld_) return;
  tipHeld_ = held;
  if (!options_.machine || !options_.machine->kinematics.rotary()) return;
  // The kinematics work in the work frame (the machine file's G54); the interpreter in the
  // machine's coordinates until run() moves its moves over.
  const Kinematics& k = options_.machine->kinematics;
  const Vector3d w0 = options_.machine->workOffset;
  pos_ = held ? Vector3d(k.pose(pos_ - w0, rotaryNow(), false).tip + w0)
              : Vector3d(k.joints(pos_ - w0, rotaryNow()) + w0);
}

void Interpreter::tipModes(const Words& w) {
  if (const auto g = w.gIn(8)) {
    tcpCode_ = *g == G_43_4 || *g == G_43_5 || *g == G_234;
    tcpVector_ = *g == G_43_5;
  }
  if (const auto g = w.gIn(23)) dwo_ = *g == G_254;
  const auto plane = w.gIn(16);
  if (frame_ != 0 && !(plane && *plane == G_69))
    for (const auto& [code, column] : w.g)
      if ((gGroup(code) == 0 && code != G_4) || gGroup(code) == 12)
        fail(column, "expected G69 (the tilted work plane off) before " + codeName('G', code) +
                         ", found G68.2 in force");
  if (plane && *plane == G_69 && frame_ != 0) {
    pos_ = out_.frames[frame_ - 1].toWork(pos_);
    frame_ = 0;
  }
  if (!(plane && *plane == G_68_2)) {
    holdTip(tipWanted());
  } else {
    const int column = w.gColumn(G_68_2);
    if (frame_ != 0)
      fail(column, "expected G69 before another G68.2, found a tilted work plane in force");
    if (comp_.on()) fail(column, "expected G40 before G68.2, found cutter radius compensation on");
    if (w.has('@') || w.has('^'))
      fail(column, "expected X, Y, Z, I, J, K with G68.2, found polar words");
    holdTip(true);
    // The plane's origin (X, Y, Z, work coordinates) and its turn: Euler angles I about Z, J
    // about the turned X, K about the twice-turned Z (degrees, counter-clockwise positive).
    const Vector3d w0 = workOffset();
    Vector3d origin = Vector3d::Zero();
    for (int a = 0; a < 3; ++a)
      if (w.has(static_cast<char>('X' + a))) origin[a] = w.get(static_cast<char>('X' + a)) * unit();
    auto angle = [&](char c) { return w.has(c) ? w.get(c) : 0.0; };
    FeatureFrame f;
    f.turn = turn(angle('I'), Vector3d::UnitZ()) * turn(angle('J'), Vector3d::UnitX()) *
             turn(angle('K'), Vector3d::UnitZ());
    // Stored coordinates are the plane's plus the work offset: work = w0 + origin + turn * (p -
    // w0).
    f.origin = w0 + origin - f.turn * w0;
    pos_ = f.turn.transpose() * (pos_ - f.origin);
    out_.frames.push_back(f);
    frame_ = static_cast<std::uint32_t>(out_.frames.size());
  }
  if (w.hasG(G_53_1)) alignToPlane(w.gColumn(G_53_1));
}

void Interpreter::alignToPlane(int column) {
  if (frame_ == 0) fail(column, "expected a tilted work plane (G68.2) before G53.1, found none");
  if (dwo_)
    fail(column,
         "expected G255 (the dynamic work offset off) before G53.1 turns the rotary axes, found "
         "G254 in force");
  const FeatureFrame& f = out_.frames[frame_ - 1];
  const Vector3d want = f.turn.col(2);
  const Vector3d from = rotaryNow();
  const bool rotary = options_.machine && options_.machine->kinematics.rotary();
  if (!rotary) {
    if ((want - Vector3d::UnitZ()).norm() <= 1e-9) return;
    fail(column,
         "expected the machine's rotary axes to turn the tool (a --machine file with "
         "\"kinematics\"), found G53.1 on a tilted plane without them");
  }
  const Kinematics& k = options_.machine->kinematics;
  const MachineSetup& machine = *options_.machine;
  const std::optional<Vector3d> to = k.anglesFor(want, from, machine.rotaryMin, machine.rotaryMax);
  if (!to) {
    auto n = [](double v) { return formatNumber(std::abs(v) < 5e-13 ? 0.0 : v); };
    fail(column, std::string("expected a tilted work plane whose Z the rotary axes of ") +
                     kinematicsTypeName(k.type) + " can reach, found Z along (" + n(want.x()) +
                     ", " + n(want.y()) + ", " + n(want.z()) + ")");
  }
  if ((*to - from).cwiseAbs().maxCoeff() <= 1e-9) return;
  // The linear joints hold still while the rotaries turn (TCP off): the tip goes where the
  // turned table or head takes it.
  const Vector3d w0 = options_.machine->workOffset;
  const Vector3d joints = k.joints(f.toWork(pos_) - w0, from) + w0;
  for (int a = 0; a < 3; ++a)
    otherAxisPosition_[static_cast<std::size_t>(a)] = (*to)[a];
  otherAxes_ = true;
  Move m = base(MoveKind::Rapid);
  m.start = m.end = joints;
  m.tipHeld = false;
  m.frame = 0;
  m.feed = 0.0;
  out_.moves.push_back(std::move(m));
  pos_ = f.turn.transpose() * (k.pose(joints - w0, *to, false).tip + w0 - f.origin);
}

void Interpreter::toolVector(const Words& w, int mode) {
  for (const char a : {'A', 'B', 'C'})
    if (w.has(a))
      fail(w.column(a), std::string("expected the tool's axis as I, J, K under G43.5 (tool centre "
                                    "point control type 2), found ") +
                            a + formatNumber(w.get(a)));
  if (w.hasG(G_43_5)) {
    if (w.has('Q') && w.get('Q') != 0.0)
      fail(w.column('Q'),
           "expected no tool inclination with G43.5 (engage does not read Q: give the inclined "
           "axis as I, J, K), found Q" +
               formatNumber(w.get('Q')));
    if (w.has('P') && w.get('P') != 0.0)
      fail(w.column('P'),
           "expected P0 (conventional control: the rotary axes turn evenly) with G43.5, found P" +
               formatNumber(w.get('P')) + " (tool posture control)");
  }
  const char first = w.has('I') ? 'I' : w.has('J') ? 'J' : 'K';
  if (!w.has(first)) return;  // (none: the axis stays)
  const int column = w.column(first);
  const bool rotary = options_.machine && options_.machine->kinematics.rotary();
  // Fanuc's alarm PS5421: the G43.5 line itself takes I, J, K only where the head turns the
  // tool.
  if (rotary && w.hasG(G_43_5) && options_.machine->kinematics.type != Kinematics::Type::HeadBC)
    fail(column, std::string("expected I, J, K on the G43.5 line only on a machine whose head "
                             "turns the tool, found them on ") +
                     kinematicsTypeName(options_.machine->kinematics.type) + " (" +
                     options_.machine->name + ")");
  if (mode != G_0 && mode != G_1)
    fail(column,
         "expected G0 or G1 with the tool's axis I, J, K under G43.5 (arcs take R), "
         "found " +
             codeName('G', mode));
  Vector3d v(w.has('I') ? w.get('I') : 0.0, w.has('J') ? w.get('J') : 0.0,
             w.has('K') ? w.get('K') : 0.0);
  auto n = [](double x) { return formatNumber(std::abs(x) < 5e-13 ? 0.0 : x); };
  const std::string given = "(" + n(v.x()) + ", " + n(v.y()) + ", " + n(v.z()) + ")";
  if (!(v.norm() > 1e-9))
    fail(column, "expected a tool axis I, J, K of some length, found " + given);
  v.normalize();
  if (frame_ != 0) v = out_.frames[frame_ - 1].turn * v;
  if (!rotary) {
    if ((v - Vector3d::UnitZ()).norm() <= 1e-9) return;
    fail(column,
         "expected the machine's rotary axes to turn the tool (a --machine file with "
         "\"kinematics\"), found the tool's axis " +
             given + " under G43.5");
  }
  const Kinematics& k = options_.machine->kinematics;
  const MachineSetup& m = *options_.machine;
  const std::optional<Vector3d> to = k.anglesFor(v, rotaryNow(), m.rotaryMin, m.rotaryMax);
  if (!to)
    fail(column, std::string("expected a tool axis the rotary axes of ") +
                     kinematicsTypeName(k.type) + " can reach, found " + given);
  for (int a = 0; a < 3; ++a) {
    double& at = otherAxisPosition_[static_cast<std::size_t>(a)];
    if ((*to)[a] != at) otherAxes_ = true;
    at = (*to)[a];
  }
}

}  // namespace engage::gcode
