#include "engine/gcode/CutterComp.h"
#include "cutters/Numbers.h"

#include <cmath>

namespace engage {
namespace {

constexpr double kHalfPi = kPi / 2.0;
/// Angle below which two directions count as one corner kind or another (LinuxCNC's
/// TOLERANCE_CONCAVE_CORNER, radians).
constexpr double kCorner = 0.05;
/// A length equal to the radius within this share counts as longer than it, as in LinuxCNC,
/// whose radius (the tool table's diameter taken through another unit and back) comes out a
/// rounding below the table's: an inch program's entry move of exactly one radius, and its
/// hole of exactly the tool's diameter (useful-subroutines.ngc), run there.
constexpr double kRounding = 1e-12;
/// An offset arc may sweep this much more than its programmed arc before it counts as too short
/// for its corner: 0.001 rad in an inch program, 0.0254 rad in a mm one (radians per mm per
/// program unit), as LinuxCNC 2.9's rs274 (Debian 12) does, found by bisection on an arc entered
/// 1e-5 to 0.05 rad off tangent. A program's four decimals leave a tangent lead arc that much off.
constexpr double kTurnTolerance = 0.0254;

using V2 = Eigen::Vector2d;

double angleOf(const V2& v) {
  return std::atan2(v.y(), v.x());
}

V2 polar(double r, double angle) {
  return {r * std::cos(angle), r * std::sin(angle)};
}

/// Signed angle swept from `from` to `to` about `centre` by an arc of `turn` turns (+ ccw):
/// 0 < angle <= 2 pi for one ccw turn (a whole turn when from == to).
double sweptAngle(const V2& from, const V2& centre, int turn, const V2& to) {
  if (turn == 0) return 0.0;
  double alpha = angleOf(from - centre), beta = angleOf(to - centre);
  if (turn > 0) {
    if (beta <= alpha) beta += 2.0 * kPi;
    return beta - alpha + (turn - 1) * 2.0 * kPi;
  }
  if (alpha <= beta) alpha += 2.0 * kPi;
  return beta - alpha + (turn + 1) * 2.0 * kPi;
}

}  // namespace

V2 CutterCompensation::xy(const Eigen::Vector3d& p) const {
  return {p[axes_.a], p[axes_.b]};
}

void CutterCompensation::setXy(Eigen::Vector3d& p, const V2& v) const {
  p[axes_.a] = v.x();
  p[axes_.b] = v.y();
}

Eigen::Vector3d CutterCompensation::point(const V2& v, double height) const {
  Eigen::Vector3d p;
  p[axes_.a] = v.x();
  p[axes_.b] = v.y();
  p[axes_.n] = height;
  return p;
}

void CutterCompensation::on(Side side, double radius, const Eigen::Vector3d& position, double unit,
                            Plane plane) {
  unit_ = unit;
  plane_ = plane;
  axes_ = planeAxes(plane);
  if (side_ != Off)
    throw CompensationError("cannot turn cutter radius compensation on when it is on (G40 first)");
  if (radius < 0.0) {  // a negative radius in the table: the other side
    radius = -radius;
    side = side == Left ? Right : Left;
  }
  side_ = side;
  radius_ = radius;
  first_ = true;
  current_ = emitted_ = position;
  queue_.clear();
  endpointValid_ = false;
}

void CutterCompensation::enqueue(Move m, const V2& direction, double originalTurn) {
  queue_.push_back({std::move(m), direction, originalTurn});
}

void CutterCompensation::dequeue() {
  endpointValid_ = false;
  for (Held& h : queue_) {
    h.move.start = emitted_;
    if (h.move.kind == MoveKind::Arc) h.move.center[axes_.n] = emitted_[axes_.n];
    emitted_ = h.move.end;
    sink_(std::move(h.move));
  }
  queue_.clear();
}

void CutterCompensation::setEndpoint(const V2& p) {
  endpoint_ = p;
  endpointValid_ = true;
}

void CutterCompensation::moveEndpointAndFlush(const V2& p) {
  if (queue_.empty()) return;
  // Every held move ends at p: an inside corner's meeting point (several moves when the tool
  // went up and down again at the corner).
  for (Held& h : queue_) {
    Move& m = h.move;
    if (m.kind == MoveKind::Arc) {
      const V2 centre = xy(m.center);
      const double before = (xy(m.end) - centre).norm();
      setXy(m.end, p);
      if (std::abs((p - centre).norm() - before) > 0.01 * unit_)
        throw CompensationError(
            "cutter compensation made an arc whose ends are at different radii (an inside "
            "corner the arc cannot reach)");
      const double swept = sweptAngle(endpoint_, centre, m.turns, p);
      if (h.originalTurn != 0.0 && endpointValid_ &&
          std::abs(swept) > std::abs(h.originalTurn) + kTurnTolerance / unit_)
        throw CompensationError(
            "arc move in concave corner cannot be reached by the tool without gouging (the "
            "corner takes more of the arc than it sweeps)");
    } else {
      // The move must not turn back: it would have to be shorter than the corner's retreat.
      if (endpointValid_ && h.direction.dot(p - endpoint_) < 0.0)
        throw CompensationError(std::string("straight ") +
                                (m.kind == MoveKind::Rapid ? "traverse" : "feed") +
                                " in concave corner cannot be reached by the tool without "
                                "gouging (the move before it is shorter than the corner takes)");
      setXy(m.end, p);
    }
  }
  dequeue();
  setEndpoint(p);
}

Move CutterCompensation::cornerArc(const Move& like, const V2& end, const V2& centre,
                                   double z) const {
  Move a = like;
  a.kind = MoveKind::Arc;
  a.plane = plane_;
  a.end = point(end, z);
  a.center = point(centre, z);
  a.turns = side_ == Left ? -1 : 1;
  a.points.clear();
  return a;
}

void CutterCompensation::straight(Move m) {
  const V2 p = xy(m.end), c = xy(current_), op = xy(m.start);
  const double r = radius_;
  if (first_) {
    // The entry move: to the point a radius to the side of the end, across the move.
    if (!((p - c).norm() > r * (1.0 - kRounding)))
      throw CompensationError(
          "length of cutter compensation entry move is not greater than the tool radius");
    const double alpha = angleOf(p - c) + (side_ == Left ? kHalfPi : -kHalfPi);
    const V2 end = p + polar(r, alpha);
    setEndpoint(c);
    setXy(m.end, end);
    current_ = m.end;
    first_ = false;
    enqueue(std::move(m), polar(1.0, alpha), 0.0);
    return;
  }
  if (p == op) {  // no XY motion: stays at the offset point
    setXy(m.end, c);
    current_ = m.end;
    enqueue(std::move(m), V2::Zero(), 0.0);
    return;
  }
  double theta = angleOf(c - op), alpha = angleOf(p - op), beta = 0.0, gamma = 0.0;
  if (side_ == Left) {
    if (theta < alpha) theta += 2.0 * kPi;
    beta = theta - alpha - kHalfPi;
    gamma = kHalfPi;
  } else {
    if (alpha < theta) alpha += 2.0 * kPi;
    beta = alpha - theta - kHalfPi;
    gamma = -kHalfPi;
  }
  const V2 end = p + polar(r, alpha + gamma);
  V2 mid = op + polar(r, alpha + gamma);
  const bool frontArc = !queue_.empty() && queue_.front().move.kind == MoveKind::Arc;
  const int frontTurns = frontArc ? queue_.front().move.turns : 0;
  // An "h" shape (over the round top, then down beside the stem): LinuxCNC stays outside.
  const bool concave = beta < -kCorner || beta > kPi + kCorner ||
                       (beta > kPi - kCorner && frontArc &&
                        ((side_ == Right && frontTurns > 0) || (side_ == Left && frontTurns < 0)));
  if (!concave && beta > kCorner) {
    // Outside corner: round it on an arc about the programmed corner (a rapid goes straight).
    moveEndpointAndFlush(c);
    if (m.kind == MoveKind::Rapid) {
      Move rapid = m;
      rapid.end = point(mid, current_[axes_.n]);
      enqueue(std::move(rapid), V2::Zero(), 0.0);
    } else {
      enqueue(cornerArc(m, mid, op, current_[axes_.n]), V2::Zero(), 0.0);
    }
    dequeue();
    setEndpoint(mid);
  } else if (concave) {
    if (!frontArc) {
      // Line to line: the last move ends where the two offset lines meet.
      const double halfCorner = (beta + kPi) / 2.0;
      if (halfCorner == 0.0)
        throw CompensationError("zero degree inside corner is invalid for cutter compensation");
      mid = c + polar(r / std::tan(halfCorner), theta + gamma);
      moveEndpointAndFlush(mid);
    } else {
      // Arc to line: the last (offset) arc ends where it meets the offset line.
      const Move& prev = queue_.front().move;
      const V2 centre = xy(prev.center);
      const double oldRadius = (centre - xy(prev.end)).norm();
      const double base = angleOf(p - op);
      const double theta2 = prev.turns > 0 ? base + kHalfPi : base - kHalfPi;
      const bool inside = (side_ == Left && prev.turns > 0) || (side_ == Right && prev.turns < 0);
      const double programmedRadius = inside ? oldRadius + r : oldRadius - r;
      const double d = programmedRadius * std::cos(theta2 - angleOf(centre - op));
      const double l = (inside ? d - r : d + r) / oldRadius;
      if (l > 1.0 || l < -1.0)
        throw CompensationError(
            "arc to straight motion makes a corner the compensated tool can't fit in without "
            "gouging");
      const double sign = (inside == (prev.turns > 0)) ? -1.0 : 1.0;
      mid = centre + polar(oldRadius, sign * std::acos(l) + theta2 + kPi);
      moveEndpointAndFlush(mid);
    }
  } else {
    // Straight on (or a tangent arc to line).
    dequeue();
    setEndpoint(c);
  }
  const V2 direction = p - op;
  setXy(m.end, end);
  current_ = m.end;
  enqueue(std::move(m), direction, 0.0);
}

void CutterCompensation::entryArc(Move m) {
  // The programmed arc's centre is where the reader put it (from the tool's position, which is
  // not offset yet); the tool's arc keeps that centre's direction from the end and passes
  // through the tool's position.
  const V2 c = xy(current_), centre = xy(m.center), endP = xy(m.end);
  const double r = radius_;
  const bool inside = (side_ == Left && m.turns > 0) || (side_ == Right && m.turns < 0);
  if (inside && (centre - c).norm() <= r * (1.0 - kRounding))
    throw CompensationError("tool radius not less than arc radius with cutter compensation");
  if (!((endP - c).norm() > r * (1.0 - kRounding)))
    throw CompensationError(
        "radius of cutter compensation entry arc is not greater than the tool radius");
  const double gamma = inside ? angleOf(centre - endP) : angleOf(endP - centre);
  const V2 end = endP + polar(r, gamma);
  const double half = (c - end).norm() / 2.0;
  const double toCentre = angleOf(centre - end);
  const double corner = angleOf(c - end) - toCentre;
  if (std::abs(std::cos(corner)) < 1e-4)  // LinuxCNC's TOLERANCE_EQUAL
    throw CompensationError("tool radius not less than arc radius with cutter compensation");
  const V2 newCentre = end + polar(half / std::cos(corner), toCentre);
  setXy(m.end, end);
  m.center = point(newCentre, current_[axes_.n]);
  first_ = false;
  current_ = m.end;
  // No "too short for the corner" check on an entry arc: rs274 (2.9) makes none there (an
  // entry arc followed by an outside corner, which its own check refuses, runs).
  enqueue(std::move(m), V2::Zero(), 0.0);
}

void CutterCompensation::arc(Move m) {
  if (first_) {
    entryArc(std::move(m));
    return;
  }
  const V2 op = xy(m.start), c = xy(current_), centre = xy(m.center), endP = xy(m.end);
  const double r = radius_;
  const int turn = m.turns;
  const bool ccw = turn > 0;
  const double arcRadius = (centre - endP).norm();
  double theta = angleOf(c - op);
  theta = side_ == Left ? theta - kHalfPi : theta + kHalfPi;
  double delta = angleOf(centre - op);
  const double alpha = ccw ? delta - kHalfPi : delta + kHalfPi;
  double beta = side_ == Left ? theta - alpha : alpha - theta;
  beta = beta > 1.5 * kPi ? beta - 2.0 * kPi : beta < -kHalfPi ? beta + 2.0 * kPi : beta;
  const bool inside = (side_ == Left && ccw) || (side_ == Right && !ccw);
  double gamma = 0.0;
  if (inside) {
    gamma = angleOf(centre - endP);
    if (arcRadius <= r * (1.0 - kRounding))
      throw CompensationError("tool radius not less than arc radius with cutter compensation");
  } else {
    gamma = angleOf(endP - centre);
    delta += kPi;
  }
  const V2 newEnd = endP + polar(r, gamma);
  const double originalTurn = sweptAngle(op, centre, turn, endP);
  Move main = m;
  setXy(main.end, newEnd);
  const bool frontArc = !queue_.empty() && queue_.front().move.kind == MoveKind::Arc;
  if (beta < -kCorner || beta > kPi + kCorner || (std::abs(beta - kPi) < kCorner && !inside)) {
    // Inside corner: the last move ends where it meets this arc's offset.
    V2 mid;
    if (!frontArc) {
      const double across = arcRadius * std::sin(beta - kHalfPi);
      const double fromCentre = inside ? arcRadius - r : arcRadius + r;
      const double l = (inside ? across + r : across - r) / fromCentre;
      if (l > 1.0 || l < -1.0)
        throw CompensationError(
            "arc move in concave corner cannot be reached by the tool without gouging");
      const double angle =
          inside ? (turn > 0 ? theta + std::asin(l) : theta - std::asin(l))
                 : (turn > 0 ? theta + kPi - std::asin(l) : theta + kPi + std::asin(l));
      mid = centre + polar(fromCentre, angle);
    } else {
      const Move& prev = queue_.front().move;
      const V2 prevCentre = xy(prev.center);
      const double oldRadius = (prevCentre - xy(prev.end)).norm();
      const double newRadius = inside ? arcRadius - r : arcRadius + r;
      const double between = (prevCentre - centre).norm();
      if (oldRadius == 0.0 || between == 0.0)
        throw CompensationError(
            "arc to arc motion is invalid because the arcs have the same center");
      const double a = (oldRadius * oldRadius + between * between - newRadius * newRadius) /
                       (2.0 * oldRadius * between);
      if (a > 1.0 || a < -1.0)
        throw CompensationError(
            "arc to arc motion makes a corner the compensated tool can't fit in without gouging");
      const double pullback = std::acos(a);
      const double towards = angleOf(centre - prevCentre);
      const bool prevInside =
          (side_ == Left && prev.turns > 0) || (side_ == Right && prev.turns < 0);
      const double dir = prevInside == (turn > 0) ? towards + pullback : towards - pullback;
      mid = prevCentre + polar(oldRadius, dir);
    }
    moveEndpointAndFlush(mid);
  } else if (beta > kCorner) {
    // Outside corner: an arc about the programmed corner to where this arc's offset starts.
    const V2 mid = op + polar(r, delta);
    dequeue();
    enqueue(cornerArc(m, mid, op, current_[axes_.n]), V2::Zero(), 0.0);
    dequeue();
    setEndpoint(mid);
  } else {
    dequeue();
    setEndpoint(c);
  }
  current_ = main.end;
  enqueue(std::move(main), V2::Zero(), originalTurn);
}

Eigen::Vector3d CutterCompensation::off() {
  if (offsetting()) {
    moveEndpointAndFlush(xy(current_));
    dequeue();
  }
  side_ = Off;
  first_ = true;
  return current_;
}

void CutterCompensation::flush() {
  dequeue();
}

}  // namespace engage
