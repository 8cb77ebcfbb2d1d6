#include "engine/sim/ToolPoses.h"

#include <algorithm>
#include <cmath>

namespace engage {
namespace {

constexpr int kPieces = 8;

Eigen::Vector3d rotaryAt(const Move& m, double t) {
  return m.rotaryStart + t * (m.rotaryEnd - m.rotaryStart);
}

/// The move's own tip path between t0 and t1 (the work frame).
StepPath workPath(const Move& m, double t0, double t1) {
  StepPath p;
  p.start = pointAt(m, t0);
  p.end = pointAt(m, t1);
  if (m.kind == MoveKind::Arc && m.plane == Plane::XY) {
    p.kind = StepPath::Kind::ArcXY;
    p.center = m.center;
    p.sweepRad = arcSweep(m) * (t1 - t0);
  } else if (m.kind == MoveKind::Arc || m.kind == MoveKind::Spline) {
    p.kind = StepPath::Kind::Polyline;
    for (int i = 0; i <= kPieces; ++i)
      p.points.push_back(pointAt(m, t0 + (t1 - t0) * i / kPieces));
  }
  return p;
}

}  // namespace

bool tiltsTool(const Move& m, const Kinematics& k) {
  if (!k.rotary()) return false;
  auto tilted = [&](double t) {
    return (k.axis(rotaryAt(m, t)) - Eigen::Vector3d::UnitZ()).squaredNorm() > 1e-24;
  };
  if (!turnsRotary(m)) return tilted(0.0);
  constexpr int kSamples = 32;
  for (int i = 0; i <= kSamples; ++i)
    if (tilted(static_cast<double>(i) / kSamples)) return true;
  return false;
}

bool tiltsTool(const Toolpath& path) {
  return std::any_of(path.moves.begin(), path.moves.end(),
                     [&](const Move& m) { return tiltsTool(m, path.kinematics); });
}

ToolPose movePose(const Move& m, const Kinematics& k, const FeatureFrame* frame,
                  const Eigen::Vector3d& xyz, const Eigen::Vector3d& abc) {
  return k.pose(frame ? frame->toWork(xyz) : xyz, abc, k.tcp || m.tipHeld);
}

StepPath stepPath(const Move& m, double t0, double t1, const Toolpath& path) {
  return stepPath(m, t0, t1, path.kinematics, path.frameOf(m));
}

StepPath stepPath(const Move& m, double t0, double t1, const Kinematics& k,
                  const FeatureFrame* frame) {
  StepPath p = workPath(m, t0, t1);
  if (!k.rotary() && !frame) return p;
  auto tipAt = [&](const Eigen::Vector3d& xyz, double t) {
    return movePose(m, k, frame, xyz, rotaryAt(m, t)).tip;
  };
  if (!turnsRotary(m)) {
    // The kinematics and the tilted plane carry the whole move rigidly (a turn and a shift).
    const Eigen::Vector3d axis = k.axis(m.rotaryStart);
    p.axisStart = p.axisEnd = axis;
    // (Only an XY arc asks whether the carrying turn keeps Z: two poses, not on every step.)
    auto keepsZ = [&] {
      const Eigen::Vector3d z = tipAt(p.start + Eigen::Vector3d::UnitZ(), t0) - tipAt(p.start, t0);
      return (z - Eigen::Vector3d::UnitZ()).squaredNorm() <= 1e-24;
    };
    const bool upright = (axis - Eigen::Vector3d::UnitZ()).squaredNorm() <= 1e-24;
    if (p.kind == StepPath::Kind::ArcXY && !(upright && keepsZ())) {
      // An XY arc with the tool tilted, or on a tilted plane: a polyline.
      p.kind = StepPath::Kind::Polyline;
      for (int i = 0; i <= kPieces; ++i)
        p.points.push_back(pointAt(m, t0 + (t1 - t0) * i / kPieces));
    }
    // (Where the carrying turn is about Z an XY arc stays an XY arc, its centre carried like a
    // tip at its height.)
    p.start = tipAt(p.start, t0);
    p.end = tipAt(p.end, t1);
    p.center = tipAt(p.center, t0);
    for (Eigen::Vector3d& q : p.points)
      q = tipAt(q, t0);
    return p;
  }
  // The axes turn: the tip's path at the ends of pieces of the step (a straight piece strays
  // from the curve a table's turn carries it on by its length squared over 8 radii).
  StepPath q;
  q.kind = StepPath::Kind::Polyline;
  for (int i = 0; i <= kPieces; ++i) {
    const double t = t0 + (t1 - t0) * i / kPieces;
    const ToolPose pose = movePose(m, k, frame, pointAt(m, t), rotaryAt(m, t));
    q.points.push_back(pose.tip);
    q.axes.push_back(pose.axis);
    if (i == 0) q.axisStart = pose.axis;
    if (i == kPieces) q.axisEnd = pose.axis;
  }
  q.start = q.points.front();
  q.end = q.points.back();
  return q;
}

double moveTravel(const Move& m, const Kinematics& k, double reach) {
  const double length = moveLength(m);
  if (!k.rotary() || !turnsRotary(m)) return length;  // (carried rigidly where they hold)
  // Pieces of the move: the tip's travel plus the reach times the axis's turn, summed (a
  // tilted plane turns the tip's path rigidly: it changes no length).
  constexpr int kSamples = 32;
  double travel = 0.0;
  ToolPose before = movePose(m, k, nullptr, pointAt(m, 0.0), rotaryAt(m, 0.0));
  for (int i = 1; i <= kSamples; ++i) {
    const double t = static_cast<double>(i) / kSamples;
    const ToolPose now = movePose(m, k, nullptr, pointAt(m, t), rotaryAt(m, t));
    const double turn = std::acos(std::clamp(before.axis.dot(now.axis), -1.0, 1.0));
    travel += (now.tip - before.tip).norm() + reach * turn;
    before = now;
  }
  return travel;
}

double rotaryMoveMinutes(const Move& m) {
  if (m.kind == MoveKind::Rapid) return 0.0;
  if (m.feedMode == FeedMode::InverseTime) return m.minutes;
  if (!(m.feed > 0.0)) return 0.0;
  const double length = moveLength(m);
  if (length > 0.0) return length / m.feed;
  // F in degrees per minute: not scaled by the inch (Move::feed is F x 25.4 under G20).
  return (m.rotaryEnd - m.rotaryStart).norm() / (m.inch ? m.feed / 25.4 : m.feed);
}

}  // namespace engage
