#include "cutters/Sweep.h"

#include "cutters/Error.h"
#include "cutters/Geometry.h"
#include "cutters/Numbers.h"
#include "cutters/Tolerances.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace engage {
namespace {

constexpr double kTwoPi = 2.0 * kPi;
/// Height change below which a step counts as horizontal, mm.
constexpr double kFlatZ = 1e-9;

/// Is angle `a` within the sweep that starts at a0 and turns by `sweep` (signed)?
bool withinSweep(double a, double a0, double sweep) {
  if (std::abs(sweep) >= kTwoPi) return true;
  double d = sweep >= 0.0 ? a - a0 : a0 - a;
  d = std::fmod(d, kTwoPi);
  if (d < 0.0) d += kTwoPi;
  return d <= std::abs(sweep);
}

/// The point of the parallelogram `shape` closest to p. With `edge`, where it lies: the unit
/// direction of the edge it is inside of, zero at a corner, and NaN inside the face.
Eigen::Vector3d closestOnParallelogram(const Eigen::Vector3d& p, const Parallelogram& shape,
                                       Eigen::Vector3d* edge = nullptr) {
  const Eigen::Vector3d &o = shape.o, &a = shape.a, &b = shape.b;
  const Eigen::Vector3d v = p - o;
  const double av = a.dot(v), bv = b.dot(v);
  if (shape.det > 1e-12 * shape.aa * shape.bb) {
    const double s = (shape.bb * av - shape.ab * bv) / shape.det;
    const double w = (shape.aa * bv - shape.ab * av) / shape.det;
    if (s >= 0.0 && s <= 1.0 && w >= 0.0 && w <= 1.0) {
      if (edge) edge->setConstant(std::numeric_limits<double>::quiet_NaN());
      return o + s * a + w * b;
    }
  }
  // Outside (or degenerate): the nearest of the four edges o + t a, o + b + t a, o + t b,
  // o + a + t b (t in [0, 1]).
  const Eigen::Vector3d start[4] = {o, o + b, o, o + a};
  const double along[4] = {av, av - shape.ab, bv, bv - shape.ab};  // (p - start) . direction
  Eigen::Vector3d best = o;
  double bestDistance = 1e300, bestT = 0.0;
  int bestEdge = 0;
  for (int k = 0; k < 4; ++k) {
    const bool alongA = k < 2;
    const double len2 = alongA ? shape.aa : shape.bb;
    const double t = len2 > 0.0 ? std::clamp(along[k] / len2, 0.0, 1.0) : 0.0;
    const Eigen::Vector3d point = start[k] + t * (alongA ? a : b);
    const double dq = (point - p).squaredNorm();
    if (dq < bestDistance) {
      bestDistance = dq;
      best = point;
      bestT = t;
      bestEdge = k;
    }
  }
  if (edge)
    *edge = bestT > 0.0 && bestT < 1.0 ? Eigen::Vector3d((bestEdge < 2 ? a : b).normalized())
                                       : Eigen::Vector3d::Zero();
  return best;
}

/// The curvature of the surface {f = 0} at its point x with unit normal n (f a signed
/// distance): the symmetric matrix K on the tangent plane with f(x + u) ~ u^T K u / 2, from
/// second differences at spacing e along two tangents and their bisector.
template <typename F>
Eigen::Matrix3d tangentCurvature(F&& f, const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                                 double e) {
  const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  const double f0 = f(x);
  auto second = [&](const Eigen::Vector3d& t) {
    return (f(Eigen::Vector3d(x + e * t)) + f(Eigen::Vector3d(x - e * t)) - 2.0 * f0) / (e * e);
  };
  const double k11 = second(t1), k22 = second(t2);
  const double k12 = second(Eigen::Vector3d((t1 + t2) / std::sqrt(2.0))) - 0.5 * (k11 + k22);
  return k11 * t1 * t1.transpose() + k22 * t2 * t2.transpose() +
         k12 * (t1 * t2.transpose() + t2 * t1.transpose());
}

/// The curvature of the envelope that a surface of curvature K (at a point with normal n)
/// sweeps moving along v there: none along the motion, and across it the curvature of the
/// surface's contour seen along v, det K / K_vv (Koenderink), kept within K's principal
/// curvatures (a cutter's are both of one sign unless its sides lean inward).
Eigen::Matrix3d envelopeCurvature(const Eigen::Matrix3d& K, const Eigen::Vector3d& n,
                                  const Eigen::Vector3d& v) {
  Eigen::Vector3d a = v - v.dot(n) * n;
  if (a.norm() <= 1e-9 * v.norm()) return K;  // moving along the normal: the tool's own
  a.normalize();
  const Eigen::Vector3d b = n.cross(a);
  const double kaa = a.dot(K * a), kbb = b.dot(K * b), kab = a.dot(K * b);
  const double mean = 0.5 * (kaa + kbb);
  const double spread = std::sqrt(0.25 * (kaa - kbb) * (kaa - kbb) + kab * kab);
  double across = kbb;  // along a direction of no curvature the contour is the section
  if (std::abs(kaa) > 1e-3 * (std::abs(kaa) + std::abs(kbb) + std::abs(kab)))
    across = std::clamp((kaa * kbb - kab * kab) / kaa, mean - spread, mean + spread);
  return across * b * b.transpose();
}

/// The tip on the XY arc of `s` (radius r about its centre, start angle a0, radians) at
/// parameter u in [0, 1), its height linear in u.
Eigen::Vector3d onArc(const StepPath& s, double r, double a0, double u) {
  const double a = a0 + u * s.sweepRad;
  return {s.center.x() + r * std::cos(a), s.center.y() + r * std::sin(a),
          s.start.z() + u * (s.end.z() - s.start.z())};
}

/// The distance from q (relative to the tip) to `cutter` standing on `axis` (unit), mm.
double alongAxis(const AptCutter& cutter, const Eigen::Vector3d& q, const Eigen::Vector3d& axis) {
  const double z = q.dot(axis);
  return cutter.profileSignedDistance((q - z * axis).norm(), z);
}

/// `path` seen in the frame `toWorld` takes to the world (its axis there +Z): a line stays a
/// line; an arc becomes a polyline whose chords stray at most a thousandth of `resolution`
/// from it.
StepPath inToolFrame(const StepPath& path, const Eigen::Matrix3d& toWorld, double resolution) {
  const Eigen::Matrix3d toTool = toWorld.transpose();
  StepPath local;
  local.kind = path.kind == StepPath::Kind::Line ? StepPath::Kind::Line : StepPath::Kind::Polyline;
  local.start = toTool * path.start;
  local.end = toTool * path.end;
  if (path.kind == StepPath::Kind::ArcXY) {
    const double r = std::hypot(path.start.x() - path.center.x(), path.start.y() - path.center.y());
    // A chord of angle phi strays r (1 - cos(phi / 2)) ~ r phi^2 / 8 from its arc.
    const double phi = std::sqrt(8.0 * 1e-3 * resolution / std::max(r, 1e-9));
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(path.sweepRad) / phi)));
    for (int i = 0; i <= n; ++i)
      local.points.push_back(toTool * path.at(static_cast<double>(i) / n));
  } else {
    for (const Eigen::Vector3d& q : path.points)
      local.points.push_back(toTool * q);
  }
  return local;
}

/// Grows `box` to hold a cutter of radius `radius` and height `height` standing at `tip` on
/// the unit `axis` (its cylinder's box), mm.
void holdCylinder(Box3& box, const Eigen::Vector3d& tip, const Eigen::Vector3d& axis, double radius,
                  double height) {
  const Eigen::Vector3d top = tip + height * axis;
  for (int i = 0; i < 3; ++i) {
    const double across = radius * std::sqrt(std::max(0.0, 1.0 - axis[i] * axis[i]));
    box.min[i] = std::min(box.min[i], std::min(tip[i], top[i]) - across);
    box.max[i] = std::max(box.max[i], std::max(tip[i], top[i]) + across);
  }
}

}  // namespace

bool StepPath::tilted() const {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  return (axisStart - z).squaredNorm() > 1e-24 || (axisEnd - z).squaredNorm() > 1e-24;
}

bool StepPath::turning() const {
  return (axisStart - axisEnd).squaredNorm() > 1e-24;
}

Eigen::Matrix3d StepPath::toolToPart() const {
  if ((axisEnd - Eigen::Vector3d::UnitZ()).squaredNorm() <= 1e-24)
    return Eigen::Matrix3d::Identity();
  return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axisEnd).toRotationMatrix();
}

Eigen::Vector3d StepPath::axisAt(double u) const {
  u = std::clamp(u, 0.0, 1.0);
  if (axes.size() >= 2) {
    const std::size_t pieces = axes.size() - 1;
    const double at = u * static_cast<double>(pieces);
    const std::size_t i = std::min(pieces - 1, static_cast<std::size_t>(at));
    const double t = at - static_cast<double>(i);
    return ((1.0 - t) * axes[i] + t * axes[i + 1]).normalized();
  }
  const double angle = std::acos(std::clamp(axisStart.dot(axisEnd), -1.0, 1.0));
  if (angle < 1e-12) return axisStart;
  const double sinAngle = std::sin(angle);
  return ((std::sin((1.0 - u) * angle) * axisStart + std::sin(u * angle) * axisEnd) / sinAngle)
      .normalized();
}

double StepPath::turnRad() const {
  auto angle = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
  };
  if (axes.size() < 2) return angle(axisStart, axisEnd);
  double turn = 0.0;
  for (std::size_t i = 1; i < axes.size(); ++i)
    turn += angle(axes[i - 1], axes[i]);
  return turn;
}

Eigen::Vector3d StepPath::at(double u) const {
  u = std::clamp(u, 0.0, 1.0);
  switch (kind) {
    case Kind::Line:
      return start + u * (end - start);
    case Kind::ArcXY:
      if (u >= 1.0) return end;
      return onArc(*this, std::hypot(start.x() - center.x(), start.y() - center.y()),
                   std::atan2(start.y() - center.y(), start.x() - center.x()), u);
    case Kind::Polyline: {
      double target = u * length();
      for (std::size_t i = 1; i < points.size(); ++i) {
        const double l = (points[i] - points[i - 1]).norm();
        if (target <= l && l > 0.0) return points[i - 1] + target / l * (points[i] - points[i - 1]);
        target -= l;
      }
      return end;
    }
  }
  return end;
}

double StepPath::length() const {
  switch (kind) {
    case Kind::Line:
      break;
    case Kind::ArcXY:
      return std::hypot(
          std::hypot(start.x() - center.x(), start.y() - center.y()) * std::abs(sweepRad),
          end.z() - start.z());
    case Kind::Polyline: {
      double total = 0.0;
      for (std::size_t i = 1; i < points.size(); ++i)
        total += (points[i] - points[i - 1]).norm();
      return total;
    }
  }
  return (end - start).norm();
}

Eigen::Vector2d StepPath::feedDirectionAtEnd() const {
  Eigen::Vector3d tangent = end - at(std::max(0.0, 1.0 - 1e-3));
  if (kind == Kind::ArcXY) {
    const Eigen::Vector3d r = end - center;
    tangent =
        sweepRad >= 0 ? Eigen::Vector3d(-r.y(), r.x(), 0.0) : Eigen::Vector3d(r.y(), -r.x(), 0.0);
  }
  const Eigen::Vector2d u = tilted()
                                ? Eigen::Vector2d((toolToPart().transpose() * tangent).head<2>())
                                : tangent.head<2>();
  return u.norm() < 1e-12 ? Eigen::Vector2d(1.0, 0.0) : Eigen::Vector2d(u.normalized());
}

Sweep::Sweep(const AptCutter& cutter, const StepPath& path, double resolution, double ceiling)
    : cutter_(cutter), path_(path), world_(path) {
  if (!(resolution > 0.0)) throw ParameterError("sweep resolution must be positive");
  if (path_.kind == StepPath::Kind::Polyline && path_.points.size() < 2)
    throw ParameterError("a polyline step needs at least two points");
  if (!(std::abs(path.axisStart.norm() - 1.0) < 1e-9 && std::abs(path.axisEnd.norm() - 1.0) < 1e-9))
    throw ParameterError("a step's tool axis must be a unit vector");
  if (path.tilted()) {
    ceiling = std::numeric_limits<double>::infinity();  // (a height says little of a tilted tool)
    if (!path.turning()) {
      rotated_ = true;
      toWorld_ = path.toolToPart();
      path_ = inToolFrame(path, toWorld_, resolution);
    } else {
      turning_ = true;
    }
  }
  // Tip positions that bound the path: ends, polyline points, and the arc's axis extremes.
  std::vector<Eigen::Vector3d> extremes{path_.start, path_.end};
  double length = path_.length();
  // (Polylines always sample: arcs in other planes, splines.)
  bool flatHeight =
      path_.kind != StepPath::Kind::Polyline && std::abs(path_.end.z() - path_.start.z()) <= kFlatZ;
  if (path_.kind == StepPath::Kind::ArcXY) {
    arcRadius_ = std::hypot(path_.start.x() - path_.center.x(), path_.start.y() - path_.center.y());
    arcStartRad_ =
        std::atan2(path_.start.y() - path_.center.y(), path_.start.x() - path_.center.x());
    for (int k = 0; k < 4; ++k) {
      const double a = k * kPi / 2.0;
      if (withinSweep(a, arcStartRad_, path_.sweepRad))
        extremes.emplace_back(path_.center.x() + arcRadius_ * std::cos(a),
                              path_.center.y() + arcRadius_ * std::sin(a), path_.start.z());
    }
  } else if (path_.kind == StepPath::Kind::Polyline) {
    extremes.insert(extremes.end(), path_.points.begin(), path_.points.end());
  }
  flat_ = flatHeight && !turning_;
  const auto& corners = cutter_.corners();
  lowerCorner_ = std::any_of(corners.begin(), corners.end(), [&](const ProfileCorner& c) {
    return c.at.y() < 0.5 * cutter_.height();
  });
  band_ = resolution;  // beyond one voxel from the surface only the sign matters
  vertical_ = !turning_ && path_.kind == StepPath::Kind::Line &&
              (path_.end.head<2>() - path_.start.head<2>()).norm() <= tol::kLengthMm;
  resolution_ = resolution;
  zLow_ = std::min(path_.start.z(), path_.end.z());
  zHigh_ = std::max(path_.start.z(), path_.end.z()) + cutter_.height();
  for (const Eigen::Vector3d& q : path_.points) {
    zLow_ = std::min(zLow_, q.z());
    zHigh_ = std::max(zHigh_, q.z() + cutter_.height());
  }
  // APT cutters are convex unless their sides lean inward (beta < 0).
  convexLine_ = !flat_ && !turning_ && path_.kind == StepPath::Kind::Line &&
                cutter_.parameters().taperAngleRad >= 0.0;
  // A ball end mill is a capsule about its axis (ball centre up to h - r above it) but for
  // its flat top; along a straight step it sweeps a parallelogram thickened by r.
  const AptParameters& ap = cutter_.parameters();
  capsuleLine_ = convexLine_ && !vertical_ && ap.cornerCenterRadial == 0.0 &&
                 ap.cornerRadius == ap.radius && ap.taperAngleRad == 0.0 &&
                 ap.bottomAngleRad == 0.0 && ap.height >= 2.0 * ap.radius;
  if (capsuleLine_) {
    capsule_.o = path_.start + Eigen::Vector3d(0.0, 0.0, ap.radius);
    capsule_.a = path_.end - path_.start;
    capsule_.b = Eigen::Vector3d(0.0, 0.0, ap.height - 2.0 * ap.radius);
    capsule_.aa = capsule_.a.dot(capsule_.a);
    capsule_.ab = capsule_.a.dot(capsule_.b);
    capsule_.bb = capsule_.b.dot(capsule_.b);
    capsule_.det = capsule_.aa * capsule_.bb - capsule_.ab * capsule_.ab;
  }
  Eigen::Vector3d lo = extremes.front();
  Eigen::Vector3d hi = extremes.front();
  for (const Eigen::Vector3d& e : extremes) {
    lo = lo.cwiseMin(e);
    hi = hi.cwiseMax(e);
  }
  // Below the ceiling every tip position holds at most the cutter's ceiling - zLow_ lowest.
  const double w = cutter_.maxRadiusBelow(ceiling - zLow_);
  bounds_.min = lo - Eigen::Vector3d(w, w, 0.0);
  bounds_.max = hi + Eigen::Vector3d(w, w, cutter_.height());
  bounds_.max.z() = std::max(bounds_.min.z(), std::min(bounds_.max.z(), ceiling));
  // A turning tool's points move by the tip's travel plus their reach times the turn.
  const double reachAll = std::hypot(cutter_.maxRadius(), cutter_.height());
  const double turn = path.turnRad();
  if (turning_) length += reachAll * turn;
  travel_ = std::max(length, 1e-9);
  if (!flat_ && !convexLine_) {
    const double spacing = resolution / 2.0;
    const int n = std::max(2, static_cast<int>(std::ceil(length / spacing)) + 1);
    samples_.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
      samples_[static_cast<std::size_t>(i)] = static_cast<double>(i) / (n - 1);
    sampleTips_.reserve(samples_.size());
    for (const double u : samples_) {
      sampleTips_.push_back(tip(u));
      if (turning_) sampleAxes_.push_back(path_.axisAt(u));
    }
  }
  if (rotated_) {
    // The tool's-frame box is loose once turned: the cylinders at the world path's extremes.
    Box3 box{Eigen::Vector3d::Constant(1e300), Eigen::Vector3d::Constant(-1e300)};
    std::vector<Eigen::Vector3d> ends{world_.start, world_.end};
    if (world_.kind == StepPath::Kind::ArcXY) {
      const double r =
          std::hypot(world_.start.x() - world_.center.x(), world_.start.y() - world_.center.y());
      const double a0 =
          std::atan2(world_.start.y() - world_.center.y(), world_.start.x() - world_.center.x());
      for (int k = 0; k < 4; ++k)
        if (withinSweep(k * kPi / 2.0, a0, world_.sweepRad))
          ends.emplace_back(world_.center.x() + r * std::cos(k * kPi / 2.0),
                            world_.center.y() + r * std::sin(k * kPi / 2.0), world_.start.z());
      // (a helix's height between its ends: its extremes are at the ends)
    }
    ends.insert(ends.end(), world_.points.begin(), world_.points.end());
    for (const Eigen::Vector3d& e : ends)
      holdCylinder(box, e, world_.axisStart, cutter_.maxRadius(), cutter_.height());
    bounds_ = box;
  } else if (turning_) {
    // Every instance's cylinder at the samples, grown by how far any point of the cutter
    // moves between two of them.
    Box3 box{Eigen::Vector3d::Constant(1e300), Eigen::Vector3d::Constant(-1e300)};
    for (std::size_t i = 0; i < samples_.size(); ++i)
      holdCylinder(box, sampleTips_[i], sampleAxes_[i], cutter_.maxRadius(), cutter_.height());
    // Between samples i and i + 1 a point of the cutter moves no further than the tip's path
    // between them (piecewise straight in u: exact at the polyline's points) plus its reach
    // times the axis's turn (the axis turns on one great circle between two samples).
    double gap = 0.0;
    for (std::size_t i = 0; i + 1 < samples_.size(); ++i) {
      double tipPath = 0.0;
      Eigen::Vector3d from = sampleTips_[i];
      if (path_.kind == StepPath::Kind::Polyline) {
        const double pieces = static_cast<double>(path_.points.size() - 1);
        for (std::size_t j = 1; j + 1 < path_.points.size(); ++j) {
          const double uj = static_cast<double>(j) / pieces;
          if (uj <= samples_[i] || uj >= samples_[i + 1]) continue;
          tipPath += (path_.points[j] - from).norm();
          from = path_.points[j];
        }
      }
      tipPath += (sampleTips_[i + 1] - from).norm();
      gap = std::max(
          gap, tipPath + reachAll * std::acos(std::clamp(sampleAxes_[i].dot(sampleAxes_[i + 1]),
                                                         -1.0, 1.0)));
    }
    gap_ = gap;
    box.min -= Eigen::Vector3d::Constant(gap);
    box.max += Eigen::Vector3d::Constant(gap);
    bounds_ = box;
    const double half = 0.5 * cutter_.height();
    middle0_ = sampleTips_.front() + half * sampleAxes_.front();
    middle1_ = sampleTips_.back() + half * sampleAxes_.back();
    reach_ = std::hypot(cutter_.maxRadius(), half);
    for (std::size_t i = 0; i < samples_.size(); ++i) {
      const Eigen::Vector3d m = sampleTips_[i] + half * sampleAxes_[i];
      middleSpread_ = std::max(middleSpread_, (closestOnSegment(m, middle0_, middle1_) - m).norm());
    }
    middleSpread_ += gap;
  }
}

double Sweep::support(const Eigen::Vector3d& direction) const {
  const Eigen::Vector3d n =
      rotated_ ? Eigen::Vector3d(toWorld_.transpose() * direction) : direction;
  // The cutter's support is the profile's largest s rho + n_z z, s = |n_xy| (the profile
  // turned to face n): at a segment's ends, or inside an arc where its normal is (s, n_z).
  const Eigen::Vector2d w(n.head<2>().norm(), n.z());
  double best = -std::numeric_limits<double>::infinity();
  for (const ProfileSegment& seg : cutter_.profile()) {
    best = std::max({best, w.dot(seg.start), w.dot(seg.end)});
    if (seg.kind == ProfileSegment::Kind::Arc && w.squaredNorm() > 0.0) {
      const Eigen::Vector2d top = seg.center + seg.radius * w.normalized();
      // On the arc (counter-clockwise from start to end) when it lies between them.
      const Eigen::Vector2d a = seg.start - seg.center, b = seg.end - seg.center,
                            c = top - seg.center;
      auto angle = [](const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
        double t = std::atan2(from.x() * to.y() - from.y() * to.x(), from.dot(to));
        return t < 0.0 ? t + kTwoPi : t;
      };
      if (angle(a, c) <= angle(a, b)) best = std::max(best, w.dot(top));
    }
  }
  return best + std::max(n.dot(path_.start), n.dot(path_.end));
}

double Sweep::signedDistance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient,
                             Eigen::Matrix3d* curvature) const {
  if (!rotated_) return distance(p, gradient, curvature, nullptr);
  const double d = distance(toWorld_.transpose() * p, gradient, curvature, nullptr);
  if (gradient) *gradient = toWorld_ * *gradient;
  if (curvature) *curvature = toWorld_ * *curvature * toWorld_.transpose();
  return d;
}

double Sweep::distanceWithin(const Eigen::Vector3d& p, double within,
                             Eigen::Vector3d* gradient) const {
  if (!turning_) return signedDistance(p, gradient);
  if (!rotated_) return turningDistance(p, gradient, nullptr, nullptr, within);
  const double d = turningDistance(toWorld_.transpose() * p, gradient, nullptr, nullptr, within);
  if (gradient) *gradient = toWorld_ * *gradient;
  return d;
}

double Sweep::instance(const Eigen::Vector3d& p, double u) const {
  if (!turning_) return cutter_.signedDistance(p - tip(u));
  return alongAxis(cutter_, p - tip(u), axis(u));
}

double Sweep::turningDistance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient,
                              Eigen::Matrix3d* curvature, double* closest, double within) const {
  // As the search below for steps that change height, each instance on its own axis.
  // (The samples' ends are the step's: u = 0 and 1.)
  const double band = std::min(band_, within);
  const double atEnd = alongAxis(cutter_, p - sampleTips_.back(), sampleAxes_.back());
  if (atEnd < -band) return atEnd;
  // No point of the cutter moves further than travel_ over the step, and the distance to it
  // changes no more: where the tool has gone t of it, the distance is at least the start's
  // less t and the end's less travel_ - t, so at least half their sum less travel_.
  const double atStart = alongAxis(cutter_, p - sampleTips_.front(), sampleAxes_.front());
  const double ends = 0.5 * (atStart + atEnd - travel_);
  if (ends > band) return ends;
  const double bound =
      (closestOnSegment(p, middle0_, middle1_) - p).norm() - middleSpread_ - reach_;
  if (bound > band) return bound;
  double best = 1.0;
  const double known[2] = {atStart, atEnd};
  const double d = sampled(p, best, band, std::isinf(within) ? -within : -band, known);
  if (std::isnan(best)) return d;  // (beyond the band: the sign is what counts)
  if (closest) *closest = best;
  if (std::abs(d) > within) return d;  // (no gradient wanted)
  // The closest instance's pose, once for the differences below.
  const Eigen::Vector3d tipBest = tip(best), axisBest = axis(best);
  auto f = [&](const Eigen::Vector3d& x) { return alongAxis(cutter_, x - tipBest, axisBest); };
  const double e = resolution_ / 8.0;
  if (gradient)
    *gradient = Eigen::Vector3d(f(p + Eigen::Vector3d(e, 0, 0)) - f(p - Eigen::Vector3d(e, 0, 0)),
                                f(p + Eigen::Vector3d(0, e, 0)) - f(p - Eigen::Vector3d(0, e, 0)),
                                f(p + Eigen::Vector3d(0, 0, e)) - f(p - Eigen::Vector3d(0, 0, e))) /
                (2.0 * e);
  if (gradient && curvature && std::abs(d) < 0.5 * gradient->lpNorm<1>() * resolution_) {
    // The swept distance g(x) = min over u of f(x, u), the instances' distance: where the
    // minimum is inside the step (f_u = 0 along it), its Hessian is f_xx - f_xu f_xu^T / f_uu.
    // A ball carried along loses its curvature along the motion (the envelope); a ball
    // turned about its centre (f independent of u) keeps its own. Differences at a quarter
    // `resolution` in space, and the parameter's share of as much travel.
    const Eigen::Vector3d n = gradient->normalized();
    const Eigen::Vector3d foot = p - d * n;
    const double ek = resolution_ / 4.0;
    *curvature = tangentCurvature(f, foot, n, ek);
    if (best > 0.0 && best < 1.0) {
      const double du = std::min(0.5, ek / travel_);
      const double ua = std::max(0.0, best - du), ub = std::min(1.0, best + du);
      const Eigen::Vector3d tipA = tip(ua), axisA = axis(ua), tipB = tip(ub), axisB = axis(ub);
      // f_u at x (a difference across [ua, ub]).
      auto fu = [&](const Eigen::Vector3d& x) {
        return (alongAxis(cutter_, x - tipB, axisB) - alongAxis(cutter_, x - tipA, axisA)) /
               (ub - ua);
      };
      const double fa = alongAxis(cutter_, foot - tipA, axisA),
                   fb = alongAxis(cutter_, foot - tipB, axisB), f0 = f(foot);
      const double fuu = 2.0 * ((fb - f0) / (ub - best) - (f0 - fa) / (best - ua)) / (ub - ua);
      const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
      const Eigen::Vector3d w = ((fu(foot + ek * t1) - fu(foot - ek * t1)) * t1 +
                                 (fu(foot + ek * t2) - fu(foot - ek * t2)) * t2) /
                                (2.0 * ek);
      const double ww = w.squaredNorm();
      if (fuu > 0.0 && ww > 0.0) {
        // Along w the envelope bends no further than the cutter's own least curvature (or
        // flat): the difference quotient's noise where f_uu is small stays bounded.
        const Eigen::Vector3d wn = w / std::sqrt(ww);
        const double along = wn.dot(*curvature * wn);
        const Eigen::Matrix2d k2{{t1.dot(*curvature * t1), t1.dot(*curvature * t2)},
                                 {t2.dot(*curvature * t1), t2.dot(*curvature * t2)}};
        const double least =
            std::min(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(k2, Eigen::EigenvaluesOnly)
                              .eigenvalues()
                              .minCoeff());
        const double cut = std::min(ww / fuu, along - least);
        if (cut > 0.0) *curvature -= cut * wn * wn.transpose();
      }
    }
  }
  return d;
}

double Sweep::distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient,
                       Eigen::Matrix3d* curvature, double* closest) const {
  if (closest) *closest = std::numeric_limits<double>::quiet_NaN();
  if (curvature) curvature->setZero();
  if (turning_) return turningDistance(p, gradient, curvature, closest);
  const double e = resolution_ / 8.0;
  const double ek = resolution_ / 4.0;  // spacing of the curvature's second differences
  if (curvature) curvature->setZero();
  // The curvature is wanted only where the tangent plane crosses the cube of side
  // `resolution` about p (a voxel that the plane cuts).
  auto wanted = [&](double d) {  // (the gradient is of unit length up to round-off)
    return gradient && curvature && std::abs(d) < 0.5 * gradient->lpNorm<1>() * resolution_;
  };
  if (flat_) {
    // d = P(rho, z) with P the profile's distance: the gradient is P's (central differences
    // in the profile plane) along rho's gradient and the axis.
    Eigen::Vector2d gradRho = Eigen::Vector2d::Zero();
    const double rho = flatRho(p, gradient ? &gradRho : nullptr);
    const double z = p.z() - path_.start.z();
    if (gradient) {
      const double dRho =
          cutter_.profileSignedDistance(rho + e, z) - cutter_.profileSignedDistance(rho - e, z);
      const double dZ =
          cutter_.profileSignedDistance(rho, z + e) - cutter_.profileSignedDistance(rho, z - e);
      *gradient = Eigen::Vector3d(dRho * gradRho.x(), dRho * gradRho.y(), dZ) / (2.0 * e);
    }
    const double d = cutter_.profileSignedDistance(rho, z);
    if (wanted(d) && gradRho.squaredNorm() > 0.0) {
      const Eigen::Vector3d n = gradient->normalized();
      *curvature = alongPathCurvature(p - d * n, path_.start.z(), n, gradRho);
    }
    return d;
  }
  if (capsuleLine_ && p.z() <= zLow_ + cutter_.height() - cutter_.radius()) {
    // Below every instance's top less r: the distance to the thickened parallelogram is the
    // swept ball end mill's, exactly (the flat top is at least r away). Its surface is flat
    // off the parallelogram's face, a cylinder of radius r about an edge, a ball at a corner.
    const double r = cutter_.radius();
    Eigen::Vector3d edge;
    const Eigen::Vector3d q = closestOnParallelogram(p, capsule_, &edge);
    const Eigen::Vector3d off = p - q;
    const double dist = off.norm();
    const Eigen::Vector3d n = dist > 0.0 ? Eigen::Vector3d(off / dist) : Eigen::Vector3d::UnitZ();
    if (gradient) *gradient = n;
    if (!std::isnan(edge.x()) && wanted(dist - r))
      *curvature = (Eigen::Matrix3d::Identity() - n * n.transpose() - edge * edge.transpose()) / r;
    return dist - r;
  }
  // Cheap answers first; the search is needed only near the swept surface. A point deeper
  // than `band_` inside the tool at the step's end is inside the swept solid (the union's
  // distance is at most that); a point further than `band_` from the bounding capsule is
  // outside, and the capsule distance is a lower bound of the union's.
  const double atEnd = cutter_.signedDistance(p - path_.end);
  if (atEnd < -band_) return atEnd;
  const double below = zLow_ - p.z();
  const double above = p.z() - zHigh_;
  const double across =
      (path_.kind == StepPath::Kind::Line
           ? distanceToSegment(p.head<2>(), path_.start.head<2>(), path_.end.head<2>())
           : band_) -
      cutter_.maxRadius();
  const double bound = std::max({below, above, across});
  if (bound > band_) return bound;
  double best = 1.0;
  const double d = sampled(p, best);
  if (closest) *closest = best;
  if (gradient && vertical_) {
    // A plunge or a retract reaches its minimum over a whole range of tip heights beside the
    // tool; the cutter's gradient at one of them may be its corner's. Differentiate the
    // swept distance itself instead.
    auto f = [&](const Eigen::Vector3d& o) {
      double unused = 0.0;
      return sampled(p + o, unused);
    };
    *gradient = Eigen::Vector3d(f({e, 0, 0}) - f({-e, 0, 0}), f({0, e, 0}) - f({0, -e, 0}),
                                f({0, 0, e}) - f({0, 0, -e})) /
                (2.0 * e);
  } else if (gradient) {
    const Eigen::Vector3d q = p - tip(best);
    auto f = [&](const Eigen::Vector3d& o) { return cutter_.signedDistance(q + o); };
    *gradient = Eigen::Vector3d(f({e, 0, 0}) - f({-e, 0, 0}), f({0, e, 0}) - f({0, -e, 0}),
                                f({0, 0, e}) - f({0, 0, -e})) /
                (2.0 * e);
  }
  if (wanted(d)) {
    // The closest instance's surface; where that instance is inside the step, the envelope
    // of its motion.
    const Eigen::Vector3d n = gradient->normalized();
    if (vertical_) {
      // Along a plunge a whole range of instances can be closest (beside the tool), one of
      // them with its rim next to p: the swept distance's own second differences (plunges
      // are few).
      *curvature = tangentCurvature(
          [&](const Eigen::Vector3d& x) {
            double unused = 0.0;
            return sampled(x, unused);
          },
          Eigen::Vector3d(p - d * n), n, ek);
      return d;
    }
    if (path_.kind == StepPath::Kind::ArcXY && n.head<2>().squaredNorm() > 0.0) {
      // A helix: as the XY arc it turns along (its rise adds a slope of pitch / circumference
      // to the motion, a small change of the envelope's curvature).
      *curvature = alongPathCurvature(p - d * n, tip(best).z(), n,
                                      Eigen::Vector2d(n.head<2>().normalized()));
      return d;
    }
    *curvature =
        tangentCurvature([&](const Eigen::Vector3d& x) { return cutter_.signedDistance(x); },
                         Eigen::Vector3d(p - tip(best) - d * n), n, ek);
    if (best > 0.0 && best < 1.0) {
      const double du = std::min({1e-3, best, 1.0 - best});
      *curvature = envelopeCurvature(*curvature, n, tip(best + du) - tip(best - du));
    }
  }
  return d;
}

Eigen::Vector3d Sweep::axis(double u) const {
  // Between two samples the axis turns on the great circle through theirs, and their
  // normalised blend lies on that circle: the same axes as StepPath::axisAt without its
  // sines, at a parameter that differs by the cube of the samples' turn (1e-10 of it for a
  // 0.1 deg turn).
  if (sampleAxes_.size() < 2) return path_.axisAt(u);
  const std::size_t pieces = sampleAxes_.size() - 1;
  const double at = std::clamp(u, 0.0, 1.0) * static_cast<double>(pieces);
  const std::size_t i = std::min(pieces - 1, static_cast<std::size_t>(at));
  const double t = at - static_cast<double>(i);
  return ((1.0 - t) * sampleAxes_[i] + t * sampleAxes_[i + 1]).normalized();
}

Eigen::Vector3d Sweep::tip(double u) const {
  if (turning_ && path_.kind == StepPath::Kind::Polyline) {
    // The points at even steps of the parameter the axis turns by (the kinematics' poses at
    // even shares of the move's time), not of the length.
    const std::size_t pieces = path_.points.size() - 1;
    const double at = std::clamp(u, 0.0, 1.0) * static_cast<double>(pieces);
    const std::size_t i = std::min(pieces - 1, static_cast<std::size_t>(at));
    return path_.points[i] +
           (at - static_cast<double>(i)) * (path_.points[i + 1] - path_.points[i]);
  }
  if (path_.kind != StepPath::Kind::ArcXY) return path_.at(u);
  // StepPath::at with the arc's radius and start angle kept (their hypot and atan2 were
  // half of a helix step's instructions); the same arithmetic, the same values.
  u = std::clamp(u, 0.0, 1.0);
  if (u >= 1.0) return path_.end;
  return onArc(path_, arcRadius_, arcStartRad_, u);
}

double Sweep::flatRho(const Eigen::Vector3d& p, Eigen::Vector2d* gradient, double* bend) const {
  const Eigen::Vector2d q(p.x(), p.y());
  Eigen::Vector2d from = q;  // the path point nearest in XY (rho's gradient points away)
  double rho = 0.0;
  double curve = 0.0;  // rho's second derivative across its gradient, 1/mm
  if (path_.kind == StepPath::Kind::Line) {
    const Eigen::Vector2d s0 = path_.start.head<2>(), s1 = path_.end.head<2>();
    from = closestOnSegment(q, s0, s1);
    rho = (q - from).norm();
    if (from == s0 || from == s1) curve = rho > 0.0 ? 1.0 / rho : 0.0;  // about an end
  } else {
    const Eigen::Vector2d c = path_.center.head<2>();
    // (The radius as the XY norm, not arcRadius_'s hypot: they differ in the last bit, and
    // that moves a volume in the sixth digit.)
    const double r = (path_.start.head<2>() - c).norm(), a0 = arcStartRad_;
    const Eigen::Vector2d v = q - c;
    if (v.norm() <= tol::kLengthMm) {
      rho = r;  // the centre: every arc point is r away
      from = q;
    } else if (withinSweep(std::atan2(v.y(), v.x()), a0, path_.sweepRad)) {
      from = c + r * v.normalized();
      rho = std::abs(v.norm() - r);
      curve = (v.norm() > r ? 1.0 : -1.0) / v.norm();  // circles about the centre
    } else {
      const Eigen::Vector2d s0 = path_.start.head<2>(), s1 = path_.end.head<2>();
      from = (q - s0).norm() <= (q - s1).norm() ? s0 : s1;
      rho = (q - from).norm();
      curve = rho > 0.0 ? 1.0 / rho : 0.0;
    }
  }
  if (gradient) *gradient = rho > 0.0 ? Eigen::Vector2d((q - from) / rho) : Eigen::Vector2d::Zero();
  if (bend) *bend = curve;
  return rho;
}

Eigen::Matrix3d Sweep::alongPathCurvature(const Eigen::Vector3d& foot, double tipZ,
                                          const Eigen::Vector3d& n,
                                          const Eigen::Vector2d& radial) const {
  // The profile's curvature along its tangent m (second differences of its distance), and
  // across it, along the path, the profile normal's radial part times the bend of the XY
  // distance's level lines (0 beside a line, 1 / rho about its ends or an arc's centre).
  const double ek = resolution_ / 4.0;
  Eigen::Vector2d g;
  double bend = 0.0;
  const Eigen::Vector2d at(flatRho(foot, &g, &bend), foot.z() - tipZ);
  if (g.squaredNorm() == 0.0) g = radial;  // the foot below the path
  const double nRho = n.head<2>().dot(g);
  const Eigen::Vector2d tangent(-n.z(), nRho);
  const double kProfile =
      (cutter_.profileSignedDistance(at.x() + ek * tangent.x(), at.y() + ek * tangent.y()) +
       cutter_.profileSignedDistance(at.x() - ek * tangent.x(), at.y() - ek * tangent.y()) -
       2.0 * cutter_.profileSignedDistance(at.x(), at.y())) /
      (ek * ek * tangent.squaredNorm());
  const Eigen::Vector3d m(tangent.x() * g.x(), tangent.x() * g.y(), tangent.y());
  const Eigen::Vector3d t(-g.y(), g.x(), 0.0);
  return kProfile * m * m.transpose() / m.squaredNorm() + nRho * bend * t * t.transpose();
}

double Sweep::localFaces(const Eigen::Vector3d& p, double radius, Eigen::Vector3d normals[2],
                         double distances[2], int& count, Eigen::Matrix3d* curvature) const {
  if (!rotated_) return facesInFrame(p, radius, normals, distances, count, curvature);
  const double d =
      facesInFrame(toWorld_.transpose() * p, radius, normals, distances, count, curvature);
  for (int i = 0; i < std::max(count, 1); ++i)
    normals[i] = toWorld_ * normals[i];
  if (curvature) *curvature = toWorld_ * *curvature * toWorld_.transpose();
  return d;
}

double Sweep::facesInFrame(const Eigen::Vector3d& p, double radius, Eigen::Vector3d normals[2],
                           double distances[2], int& count, Eigen::Matrix3d* curvature) const {
  if (curvature) curvature->setZero();
  if (flat_ || vertical_) {
    // A height-keeping step sweeps the profile along its path; a plunge or retract sweeps it
    // up its axis, and only the lowest instance's lower corners stay on the surface.
    Eigen::Vector2d grad = Eigen::Vector2d::Zero();
    double rho = 0.0;
    if (flat_) {
      rho = flatRho(p, &grad);
    } else {
      const Eigen::Vector2d v = p.head<2>() - path_.start.head<2>();
      rho = v.norm();
      if (rho > 0.0) grad = v / rho;
    }
    const Eigen::Vector2d at(rho, p.z() - (flat_ ? path_.start.z() : zLow_));
    const ProfileCorner* nearest = nullptr;
    for (const ProfileCorner& c : cutter_.corners())
      if ((flat_ || c.at.y() < 0.5 * cutter_.height()) && (at - c.at).norm() < radius &&
          (!nearest || (at - c.at).norm() < (at - nearest->at).norm()))
        nearest = &c;
    if (nearest && grad.squaredNorm() > 0.0) {
      // The swept solid is the profile swept along the path: near the corner, inside both
      // faces' lines, lifted to 3D along rho's gradient.
      const Eigen::Vector2d* m[2] = {&nearest->normalBefore, &nearest->normalAfter};
      for (int i = 0; i < 2; ++i) {
        normals[i] = Eigen::Vector3d(m[i]->x() * grad.x(), m[i]->x() * grad.y(), m[i]->y());
        distances[i] = m[i]->dot(at - nearest->at);
      }
      count = 2;
      return flat_ ? cutter_.profileSignedDistance(rho, at.y())
                   : distance(p, nullptr, nullptr, nullptr);  // (p is in the step's frame)
    }
  }
  count = 1;
  double best = std::numeric_limits<double>::quiet_NaN();
  const double d = distance(p, &normals[0], curvature, &best);
  distances[0] = d;
  if (!flat_ && !vertical_ && std::abs(d) < radius && lowerCorner_) {
    // A step that changes height: near the rim of the closest instance the swept solid has
    // an edge that one plane cannot follow; say so (count 0) and let the caller sample.
    if (std::isnan(best)) sampled(p, best);  // (the distance was a bound)
    const Eigen::Vector3d q = p - tip(best);
    const Eigen::Vector3d a = turning_ ? axis(best) : Eigen::Vector3d::UnitZ();
    const double along = q.dot(a);
    const Eigen::Vector2d at((q - along * a).norm(), along);
    for (const ProfileCorner& c : cutter_.corners())
      if (c.at.y() < 0.5 * cutter_.height() && (at - c.at).norm() < radius) count = 0;
    if (count == 0 && curvature) curvature->setZero();
  }
  return d;
}

double Sweep::sampled(const Eigen::Vector3d& p, double& bestParameter, double looseBeyond,
                      double insideBelow, const double* ends) const {
  auto f = [&](double u) { return instance(p, u); };
  // The best of the candidates (value, parameter) seen so far.
  double bestValue = 0.0;
  bool any = false;
  auto consider = [&](double u, double v) {
    if (!any || v < bestValue) {
      bestValue = v;
      bestParameter = u;
      any = true;
    }
  };
  // Golden-section search on [a, b], keeping its two final points as candidates.
  auto golden = [&](double a, double b, int iterations) {
    constexpr double kGolden = 0.6180339887498949;
    double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
    double f1 = f(x1), f2 = f(x2);
    for (int it = 0; it < iterations; ++it) {
      if (f1 < f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - kGolden * (b - a);
        f1 = f(x1);
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + kGolden * (b - a);
        f2 = f(x2);
      }
    }
    consider(x1, f1);
    consider(x2, f2);
  };
  if (convexLine_) {
    // The signed distance of a convex solid is convex, and so is its composition with the
    // straight motion: golden-section search finds the minimum without sampling. Eight
    // iterations leave 2.1 % of the step: the distance changes at most by the step's travel
    // times that at its minimum (1 um for a 0.5 mm step descending 0.05 mm), and ten
    // iterations changed no removed volume beyond the sixth digit on the benchmark.
    consider(0.0, f(0.0));
    consider(1.0, f(1.0));
    golden(0.0, 1.0, 8);
    return bestValue;
  }
  std::size_t best = 0;
  // No point of the cutter moves further than gap_ between two samples (turning_), and the
  // distance to it changes no more: between samples i and i + 1, where the tool has gone x of
  // gap_ from i, the distance is at least v_i - x and v_(i+1) - (gap_ - x), so at least
  // (v_i + v_(i+1) - gap_) / 2. The least of those is a bound from below on the whole step.
  double lower = std::numeric_limits<double>::infinity(), last = 0.0;
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    const double v = !turning_        ? cutter_.signedDistance(p - sampleTips_[i])
                     : i == 0 && ends ? ends[0]
                     : i + 1 == samples_.size() && ends
                         ? ends[1]
                         : alongAxis(cutter_, p - sampleTips_[i], sampleAxes_[i]);
    if (!any || v < bestValue) best = i;
    consider(samples_[i], v);
    if (i > 0) lower = std::min(lower, 0.5 * (last + v - gap_));
    last = v;
  }
  if (bestValue < insideBelow) {  // inside by more than that: the minimum is lower still
    bestParameter = std::numeric_limits<double>::quiet_NaN();
    return bestValue;
  }
  // Beyond the surface by more than looseBeyond the bound has the swept distance's sign (and
  // inside, the samples' minimum: the swept distance is no higher).
  const double outside = turning_ ? lower : bestValue - gap_;
  if (outside > looseBeyond) {
    bestParameter = std::numeric_limits<double>::quiet_NaN();
    return outside;
  }
  if (bestValue < -(looseBeyond + gap_)) {
    bestParameter = std::numeric_limits<double>::quiet_NaN();
    return bestValue;
  }
  // Refine on the bracket around the best sample.
  golden(samples_[best > 0 ? best - 1 : 0], samples_[std::min(best + 1, samples_.size() - 1)], 12);
  return bestValue;
}

}  // namespace engage
