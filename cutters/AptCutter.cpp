#include "cutters/AptCutter.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "cutters/Tolerances.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace engage {
namespace {

std::string mm(const char* name, double v) {
  return std::string(name) + " = " + formatNumber(v) + " mm";
}
std::string deg(const char* name, double rad) {
  return std::string(name) + " = " + formatNumber(rad * kDegPerRad) + " deg";
}

void requireFinite(const char* name, double v) {
  if (!std::isfinite(v))
    throw ParameterError(std::string(name) + " = " + formatNumber(v) + " is not a finite number");
}

double distanceToSegment(const ProfileSegment& s, const Eigen::Vector2d& q) {
  if (s.kind == ProfileSegment::Kind::Line) {
    const Eigen::Vector2d d = s.end - s.start;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((q - s.start).dot(d) / len2, 0.0, 1.0) : 0.0;
    return (s.start + t * d - q).norm();
  }
  // Arc: counter-clockwise from start to end, spanning at most 180 deg (profile arcs lie
  // within [-90, 90] deg of the centre), so q is within its angular range when it is left
  // of the start radius and right of the end radius (no trigonometry: this is the hot path).
  const Eigen::Vector2d v = q - s.center;
  const Eigen::Vector2d a = s.start - s.center;
  const Eigen::Vector2d b = s.end - s.center;
  const double crossStart = a.x() * v.y() - a.y() * v.x();
  const double crossEnd = v.x() * b.y() - v.y() * b.x();
  if (crossStart >= 0.0 && crossEnd >= 0.0) return std::abs(v.norm() - s.radius);
  return std::min((q - s.start).norm(), (q - s.end).norm());
}

}  // namespace

double impliedCornerCenterHeight(double cornerRadius, double cornerCenterRadial,
                                 double bottomAngleRad) {
  return (cornerRadius + cornerCenterRadial * std::sin(bottomAngleRad)) / std::cos(bottomAngleRad);
}

std::string_view shapeName(CutterShape shape) {
  switch (shape) {
    case CutterShape::Flat:
      return "flat";
    case CutterShape::Ball:
      return "ball";
    case CutterShape::Bull:
      return "bull";
    case CutterShape::Taper:
      return "taper";
    case CutterShape::TaperedBall:
      return "tapered-ball";
    case CutterShape::Chamfer:
      return "chamfer";
    case CutterShape::General:
      return "apt";
  }
  return "apt";
}

AptCutter AptCutter::flat(double diameter, double fluteLength, int flutes) {
  requireFinite("diameter D", diameter);
  if (!(diameter > 0.0)) throw ParameterError(mm("diameter D", diameter) + " must be positive");
  AptParameters p;
  p.radius = diameter / 2.0;
  p.cornerCenterRadial = p.radius;
  p.height = fluteLength;
  return fromApt(p, flutes, CutterShape::Flat);
}

AptCutter AptCutter::ball(double diameter, double fluteLength, int flutes) {
  requireFinite("diameter D", diameter);
  if (!(diameter > 0.0)) throw ParameterError(mm("diameter D", diameter) + " must be positive");
  AptParameters p;
  p.radius = diameter / 2.0;
  p.cornerRadius = p.radius;
  p.cornerCenterHeight = p.radius;
  p.height = fluteLength;
  return fromApt(p, flutes, CutterShape::Ball);
}

AptCutter AptCutter::bull(double diameter, double cornerRadius, double fluteLength, int flutes) {
  requireFinite("diameter D", diameter);
  requireFinite("corner radius r_tc", cornerRadius);
  if (!(diameter > 0.0)) throw ParameterError(mm("diameter D", diameter) + " must be positive");
  if (!(cornerRadius > 0.0))
    throw ParameterError(mm("corner radius r_tc", cornerRadius) +
                         " must be positive for a bull endmill (use a flat endmill for 0)");
  AptParameters p;
  p.radius = diameter / 2.0;
  p.cornerRadius = cornerRadius;
  p.cornerCenterRadial = p.radius - cornerRadius;
  p.cornerCenterHeight = cornerRadius;
  p.height = fluteLength;
  return fromApt(p, flutes, CutterShape::Bull);
}

AptCutter AptCutter::taper(double tipDiameter, double taperAngleRad, double fluteLength,
                           int flutes) {
  requireFinite("tip diameter D", tipDiameter);
  if (!(tipDiameter > 0.0))
    throw ParameterError(mm("tip diameter D", tipDiameter) + " must be positive");
  AptParameters p;
  p.radius = tipDiameter / 2.0;
  p.cornerCenterRadial = p.radius;
  p.taperAngleRad = taperAngleRad;
  p.height = fluteLength;
  return fromApt(p, flutes, CutterShape::Taper);
}

AptCutter AptCutter::taperedBall(double ballDiameter, double taperAngleRad, double fluteLength,
                                 int flutes) {
  requireFinite("ball diameter D", ballDiameter);
  if (!(ballDiameter > 0.0))
    throw ParameterError(mm("ball diameter D", ballDiameter) + " must be positive");
  AptParameters p;
  p.radius = ballDiameter / 2.0;
  p.cornerRadius = p.radius;
  p.cornerCenterHeight = p.radius;
  p.taperAngleRad = taperAngleRad;
  p.height = fluteLength;
  return fromApt(p, flutes, CutterShape::TaperedBall);
}

AptCutter AptCutter::chamfer(double diameter, double includedAngleRad, double fluteLength,
                             int flutes) {
  requireFinite("diameter D", diameter);
  requireFinite("included tip angle", includedAngleRad);
  if (!(diameter > 0.0)) throw ParameterError(mm("diameter D", diameter) + " must be positive");
  if (!(includedAngleRad > 0.0 && includedAngleRad < kPi))
    throw ParameterError(deg("included tip angle", includedAngleRad) +
                         " must lie strictly between 0 and 180 deg");
  AptParameters p;
  p.radius = diameter / 2.0;
  p.cornerCenterRadial = p.radius;
  p.bottomAngleRad = kPi / 2.0 - includedAngleRad / 2.0;
  p.cornerCenterHeight = impliedCornerCenterHeight(0.0, p.radius, p.bottomAngleRad);
  p.height = fluteLength;
  if (std::isfinite(fluteLength) && fluteLength < p.cornerCenterHeight)
    throw ParameterError(mm("flute length h", fluteLength) + " must reach the top of the cone at " +
                         formatNumber(p.cornerCenterHeight) + " mm for a chamfer mill of " +
                         mm("diameter D", diameter));
  return fromApt(p, flutes, CutterShape::Chamfer);
}

AptCutter AptCutter::fromApt(const AptParameters& p, int flutes, CutterShape shape) {
  requireFinite("radius r", p.radius);
  requireFinite("corner radius r_tc", p.cornerRadius);
  requireFinite("corner centre offset e", p.cornerCenterRadial);
  requireFinite("corner centre height h_tc", p.cornerCenterHeight);
  requireFinite("taper angle beta", p.taperAngleRad);
  requireFinite("bottom angle delta", p.bottomAngleRad);
  requireFinite("cutting height h", p.height);
  if (!(p.radius > 0.0)) throw ParameterError(mm("radius r", p.radius) + " must be positive");
  if (p.cornerRadius < 0.0)
    throw ParameterError(mm("corner radius r_tc", p.cornerRadius) + " must not be negative");
  if (p.cornerRadius > p.radius * (1.0 + tol::kParameterRelative))
    throw ParameterError(mm("corner radius r_tc", p.cornerRadius) + " must not exceed the cutter " +
                         mm("radius r", p.radius));
  const double impliedE = std::max(0.0, p.radius - p.cornerRadius);
  if (std::abs(p.cornerCenterRadial - impliedE) >
      tol::kParameterRelative * p.radius + tol::kLengthMm)
    throw ParameterError(mm("corner centre offset e", p.cornerCenterRadial) +
                         " is inconsistent with r and r_tc: e must equal r - r_tc = " +
                         formatNumber(impliedE) + " mm");
  if (!(std::abs(p.taperAngleRad) < kPi / 2.0))
    throw ParameterError(deg("taper angle beta", p.taperAngleRad) +
                         " must lie strictly between -90 and 90 deg");
  if (!(p.bottomAngleRad >= 0.0 && p.bottomAngleRad < kPi / 2.0))
    throw ParameterError(deg("bottom angle delta", p.bottomAngleRad) + " must lie in [0, 90) deg");
  if (p.taperAngleRad + p.bottomAngleRad > kPi / 2.0 + tol::kAngleRad)
    throw ParameterError(deg("taper angle beta", p.taperAngleRad) + " and " +
                         deg("bottom angle delta", p.bottomAngleRad) +
                         " leave no room for the corner: beta + delta must not exceed 90 deg");
  if (!(p.height > 0.0))
    throw ParameterError(mm("cutting height h", p.height) + " must be positive");
  if (flutes < 1)
    throw ParameterError("flute count = " + std::to_string(flutes) + " must be at least 1");

  AptParameters q = p;
  q.cornerRadius = std::min(p.cornerRadius, p.radius);
  q.cornerCenterRadial = impliedE;
  const double impliedH = impliedCornerCenterHeight(q.cornerRadius, impliedE, q.bottomAngleRad);
  // A caller that leaves h_tc at 0 asks for the implied value; any other value must match it.
  if (p.cornerCenterHeight != 0.0 &&
      std::abs(p.cornerCenterHeight - impliedH) >
          tol::kParameterRelative * std::max(p.radius, impliedH) + tol::kLengthMm)
    throw ParameterError(mm("corner centre height h_tc", p.cornerCenterHeight) +
                         " is inconsistent with r_tc, e and delta: a lower line through the tip "
                         "tangent to the corner needs h_tc = " +
                         formatNumber(impliedH) + " mm");
  q.cornerCenterHeight = impliedH;
  return AptCutter(q, flutes, shape);
}

AptCutter::AptCutter(const AptParameters& p, int flutes, CutterShape shape)
    : p_(p), flutes_(flutes), shape_(shape) {
  using Seg = ProfileSegment;
  const double rt = p_.cornerRadius;
  const Eigen::Vector2d c(p_.cornerCenterRadial, p_.cornerCenterHeight);
  const double a1 = p_.bottomAngleRad - kPi / 2.0;  // corner arc start, tangent to lower line
  const double a2 = -p_.taperAngleRad;              // corner arc end, tangent to side line
  const Eigen::Vector2d p1 = c + rt * Eigen::Vector2d(std::cos(a1), std::sin(a1));
  const Eigen::Vector2d p2 = c + rt * Eigen::Vector2d(std::cos(a2), std::sin(a2));
  const double h = p_.height;
  const double tanB = std::tan(p_.taperAngleRad);

  auto addLine = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    if ((b - a).norm() > tol::kLengthMm)
      profile_.push_back(Seg{Seg::Kind::Line, a, b, Eigen::Vector2d::Zero(), 0.0});
  };
  auto addArc = [&](double from, double to) {
    if (rt > tol::kLengthMm && to - from > tol::kAngleRad)
      profile_.push_back(Seg{Seg::Kind::Arc,
                             c + rt * Eigen::Vector2d(std::cos(from), std::sin(from)),
                             c + rt * Eigen::Vector2d(std::cos(to), std::sin(to)), c, rt});
  };

  Eigen::Vector2d top;  // where the profile meets the top cap
  if (h <= p1.y()) {
    // The cutting height ends on the lower line (only possible for delta > 0).
    top = Eigen::Vector2d(h / std::tan(p_.bottomAngleRad), h);
    addLine({0.0, 0.0}, top);
  } else {
    addLine({0.0, 0.0}, p1);
    if (h <= p2.y()) {
      const double ah = std::asin(std::clamp((h - c.y()) / rt, -1.0, 1.0));
      addArc(a1, ah);
      top = Eigen::Vector2d(c.x() + rt * std::cos(ah), h);
    } else {
      addArc(a1, a2);
      top = Eigen::Vector2d(p2.x() + (h - p2.y()) * tanB, h);
      if (!(top.x() > 0.0)) {
        const double closeZ = p2.y() + p2.x() / -tanB;
        throw ParameterError(deg("taper angle beta", p_.taperAngleRad) +
                             " closes the side on the axis at z = " + formatNumber(closeZ) +
                             " mm, below the " + mm("cutting height h", h));
      }
      addLine(p2, top);
    }
  }
  if (!(top.x() > 0.0))
    throw ParameterError(mm("cutting height h", h) + " leaves no cutter: the radius at h is 0");
  addLine(top, {0.0, h});

  roundedBox_ =
      p_.taperAngleRad == 0.0 && p_.bottomAngleRad == 0.0 && p_.height >= 2.0 * p_.cornerRadius;
  maxRadius_ = 0.0;
  for (const Seg& s : profile_) {
    maxRadius_ = std::max({maxRadius_, s.start.x(), s.end.x()});
    if (s.kind == Seg::Kind::Arc && s.start.y() <= s.center.y() && s.end.y() >= s.center.y())
      maxRadius_ = std::max(maxRadius_, s.center.x() + s.radius);
  }
  // Outward normal at the start or end of a piece: right of the direction of travel (the
  // profile runs counter-clockwise round the solid), or radial for an arc.
  auto normalAt = [](const Seg& s, bool atEnd) {
    if (s.kind == Seg::Kind::Arc)
      return Eigen::Vector2d(((atEnd ? s.end : s.start) - s.center).normalized());
    const Eigen::Vector2d t = (s.end - s.start).normalized();
    return Eigen::Vector2d(t.y(), -t.x());
  };
  for (std::size_t i = 0; i + 1 < profile_.size(); ++i) {
    const Eigen::Vector2d before = normalAt(profile_[i], true);
    const Eigen::Vector2d after = normalAt(profile_[i + 1], false);
    // Convex (turning left) and sharp.
    if (before.x() * after.y() - before.y() * after.x() > std::sin(kPi / 180.0) &&
        profile_[i].end.x() > tol::kLengthMm)
      corners_.push_back(ProfileCorner{profile_[i].end, before, after});
  }
}

double AptCutter::radiusAt(double z) const {
  if (!(z >= 0.0 && z <= p_.height)) return 0.0;
  for (const ProfileSegment& s : profile_) {
    const double z0 = s.start.y();
    const double z1 = s.end.y();
    if (!(z1 > z0) || z < z0 || z > z1) continue;  // horizontal pieces and the cap carry no W
    if (s.kind == ProfileSegment::Kind::Line)
      return s.start.x() + (z - z0) * (s.end.x() - s.start.x()) / (z1 - z0);
    const double dz = z - s.center.y();
    return s.center.x() + std::sqrt(std::max(0.0, s.radius * s.radius - dz * dz));
  }
  // Only z = 0 on a flat bottom reaches here: the bottom extends to the first piece's start.
  return profile_.front().end.x();
}

double AptCutter::maxRadiusBelow(double z) const {
  if (z >= p_.height) return maxRadius_;
  z = std::max(z, 0.0);
  double widest = 0.0;
  for (const ProfileSegment& s : profile_) {
    const double z0 = std::min(s.start.y(), s.end.y());
    const double z1 = std::min(std::max(s.start.y(), s.end.y()), z);
    if (z0 > z1) continue;  // the piece lies above z
    if (s.kind == ProfileSegment::Kind::Line) {
      // The line's radius at its ends within [z0, z1] (at z0 alone where it is horizontal).
      for (double at : {z0, z1}) {
        const double dz = s.end.y() - s.start.y();
        widest = std::max(
            widest, dz == 0.0 ? std::max(s.start.x(), s.end.x())
                              : s.start.x() + (at - s.start.y()) * (s.end.x() - s.start.x()) / dz);
      }
    } else {
      // An arc bulges outward (as radiusAt reads it): widest at the height nearest its centre's.
      const double dz = std::clamp(s.center.y(), z0, z1) - s.center.y();
      widest =
          std::max(widest, s.center.x() + std::sqrt(std::max(0.0, s.radius * s.radius - dz * dz)));
    }
  }
  return widest;
}

double AptCutter::profileSignedDistance(double rho, double z) const {
  if (roundedBox_) {
    // Flat, ball and bull cutters: the profile mirrored about the axis is a box of half-size
    // (r, h/2) whose bottom corners are rounded by r_tc; the exact distance of such a box in
    // closed form (this is the simulator's hot path).
    const double half = 0.5 * p_.height;
    const double y = z - half;
    const double rad = y < 0.0 ? p_.cornerRadius : 0.0;
    const double qx = std::abs(rho) - p_.radius + rad;
    const double qy = std::abs(y) - half + rad;
    const double ox = std::max(qx, 0.0);
    const double oy = std::max(qy, 0.0);
    return std::min(std::max(qx, qy), 0.0) + std::sqrt(ox * ox + oy * oy) - rad;
  }
  const Eigen::Vector2d q(std::abs(rho), z);
  double d = std::numeric_limits<double>::infinity();
  for (const ProfileSegment& s : profile_)
    d = std::min(d, distanceToSegment(s, q));
  const bool inside = z >= 0.0 && z <= p_.height && q.x() <= radiusAt(z);
  return inside ? -d : d;
}

double AptCutter::signedDistance(const Eigen::Vector3d& point) const {
  return profileSignedDistance(std::sqrt(point.x() * point.x() + point.y() * point.y()), point.z());
}

Box3 AptCutter::bounds() const {
  return Box3{Eigen::Vector3d(-maxRadius_, -maxRadius_, 0.0),
              Eigen::Vector3d(maxRadius_, maxRadius_, p_.height)};
}

}  // namespace engage
