#include "engine/gcode/Toolpath.h"

#include <algorithm>
#include <cmath>

namespace engage {
namespace {

constexpr double kTwoPi = 6.28318530717958647692;

}  // namespace

PlaneAxes planeAxes(Plane plane) {
  switch (plane) {
    case Plane::XY:
      return {0, 1, 2, 'I', 'J'};
    case Plane::XZ:
      return {2, 0, 1, 'K', 'I'};
    case Plane::YZ:
      return {1, 2, 0, 'J', 'K'};
  }
  return {0, 1, 2, 'I', 'J'};
}

const char* moveKindName(MoveKind kind) {
  switch (kind) {
    case MoveKind::Rapid:
      return "rapid";
    case MoveKind::Line:
      return "line";
    case MoveKind::Arc:
      return "arc";
    case MoveKind::Spline:
      return "spline";
  }
  return "line";
}

const char* planeName(Plane plane) {
  switch (plane) {
    case Plane::XY:
      return "XY";
    case Plane::XZ:
      return "XZ";
    case Plane::YZ:
      return "YZ";
  }
  return "XY";
}

double arcRadius(const Move& arc) {
  const PlaneAxes x = planeAxes(arc.plane);
  return std::hypot(arc.start[x.a] - arc.center[x.a], arc.start[x.b] - arc.center[x.b]);
}

double arcSweep(const Move& arc) {
  const PlaneAxes x = planeAxes(arc.plane);
  const double a0 = std::atan2(arc.start[x.b] - arc.center[x.b], arc.start[x.a] - arc.center[x.a]);
  const double a1 = std::atan2(arc.end[x.b] - arc.center[x.b], arc.end[x.a] - arc.center[x.a]);
  const int turns = std::abs(arc.turns);
  double sweep = a1 - a0;
  if (arc.turns > 0) {
    // Counter-clockwise: (0, 2 pi], a closed circle is a full turn.
    while (sweep <= 1e-12)
      sweep += kTwoPi;
    sweep += kTwoPi * (turns - 1);
  } else {
    while (sweep >= -1e-12)
      sweep -= kTwoPi;
    sweep -= kTwoPi * (turns - 1);
  }
  return sweep;
}

double moveLength(const Move& move) {
  switch (move.kind) {
    case MoveKind::Arc: {
      const PlaneAxes x = planeAxes(move.plane);
      const double planar = arcRadius(move) * std::abs(arcSweep(move));
      return std::hypot(planar, move.end[x.n] - move.start[x.n]);
    }
    case MoveKind::Spline: {
      double length = 0.0;
      Eigen::Vector3d previous = move.start;
      for (const Eigen::Vector3d& p : move.points) {
        length += (p - previous).norm();
        previous = p;
      }
      return length;
    }
    case MoveKind::Rapid:
    case MoveKind::Line:
      break;
  }
  return (move.end - move.start).norm();
}

Eigen::Vector3d pointAt(const Move& move, double t) {
  t = std::clamp(t, 0.0, 1.0);
  switch (move.kind) {
    case MoveKind::Arc: {
      const PlaneAxes x = planeAxes(move.plane);
      const double r = arcRadius(move);
      const double a0 =
          std::atan2(move.start[x.b] - move.center[x.b], move.start[x.a] - move.center[x.a]);
      const double a = a0 + t * arcSweep(move);
      Eigen::Vector3d p;
      p[x.a] = move.center[x.a] + r * std::cos(a);
      p[x.b] = move.center[x.b] + r * std::sin(a);
      p[x.n] = move.start[x.n] + t * (move.end[x.n] - move.start[x.n]);
      if (t == 1.0) p = move.end;  // exact end point, not its round-off
      return p;
    }
    case MoveKind::Spline: {
      const double target = t * moveLength(move);
      double walked = 0.0;
      Eigen::Vector3d previous = move.start;
      for (const Eigen::Vector3d& p : move.points) {
        const double piece = (p - previous).norm();
        if (walked + piece >= target && piece > 0.0)
          return previous + (target - walked) / piece * (p - previous);
        walked += piece;
        previous = p;
      }
      return move.end;
    }
    case MoveKind::Rapid:
    case MoveKind::Line:
      break;
  }
  return move.start + t * (move.end - move.start);
}

}  // namespace engage
