#include "stock/DexelSolid.h"

#include "cutters/Geometry.h"
#include "cutters/Numbers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace engage::dexel {
namespace {

/// Where on the outline of a step's slice (the discs of radius W along the track) the point
/// nearest a column lies: its curvature at radius W (1/mm; positive where the slice is convex).
struct OutlineCurvature {
  enum class Kind { Side, Cap, ArcOuter, ArcInner } kind = Kind::Side;
  double arcRadius = 0.0;
  double at(double w) const {
    switch (kind) {
      case Kind::Side:
        return 0.0;
      case Kind::Cap:
        return w > 1e-9 ? 1.0 / w : 1e9;
      case Kind::ArcOuter:
        return 1.0 / std::max(arcRadius + w, 1e-9);
      case Kind::ArcInner:
        return arcRadius - w > 1e-9 ? -1.0 / (arcRadius - w) : 0.0;
    }
    return 0.0;
  }
};

/// The XY distance from q to the step's path (its tip's XY track), and in `normal` (when
/// given) the unit direction from the track's nearest point to q, in `curvature` (when given)
/// which part of the slice's outline faces q.
double pathDistance(const StepPath& p, const Eigen::Vector2d& q, Eigen::Vector2d* normal = nullptr,
                    OutlineCurvature* curvature = nullptr) {
  Eigen::Vector2d foot;
  OutlineCurvature outline;
  if (p.kind == StepPath::Kind::ArcXY) {
    const Eigen::Vector2d c = p.center.head<2>(), a = p.start.head<2>() - c;
    const Eigen::Vector2d v = q - c;
    const double r = a.norm();
    double t = std::atan2(a.x() * v.y() - a.y() * v.x(), a.dot(v));  // angle from the start
    if (p.sweepRad < 0) t = -t;
    if (t < 0) t += 2.0 * kPi;
    if (t <= std::abs(p.sweepRad) && v.norm() > 1e-12) {
      foot = c + v * (r / v.norm());
      outline.kind =
          v.norm() >= r ? OutlineCurvature::Kind::ArcOuter : OutlineCurvature::Kind::ArcInner;
      outline.arcRadius = r;
    } else {
      const Eigen::Vector2d s = p.start.head<2>(), e = p.end.head<2>();
      foot = (q - s).squaredNorm() <= (q - e).squaredNorm() ? s : e;
      outline.kind = OutlineCurvature::Kind::Cap;
    }
  } else {
    const Eigen::Vector2d a = p.start.head<2>(), v = p.end.head<2>() - a;
    const double vv = v.squaredNorm();
    const double u = vv < 1e-24 ? 0.0 : (q - a).dot(v) / vv;
    foot = a + v * std::clamp(u, 0.0, 1.0);
    if (vv < 1e-24 || u <= 0.0 || u >= 1.0) outline.kind = OutlineCurvature::Kind::Cap;
  }
  const Eigen::Vector2d d = q - foot;
  const double rho = d.norm();
  if (normal) *normal = rho > 1e-12 ? Eigen::Vector2d(d / rho) : Eigen::Vector2d(1.0, 0.0);
  if (curvature) *curvature = outline;
  return rho;
}

/// Half the width, in ray spacings, of a square column seen along the unit direction n: how
/// far from a straight boundary with that normal the column's centre can be while the boundary
/// still crosses it (1/2 along the grid, up to 1/sqrt 2 at 45 deg).
double columnReach(const Eigen::Vector2d& n) {
  return 0.5 * (std::abs(n.x()) + std::abs(n.y()));
}

/// Share of a square column (side h) on the inner side of a boundary that crosses it straight,
/// with outward unit normal n, the column's centre at signed distance d outside it (mm): the
/// distribution function at -d of n . x over the square, the sum of two uniform variables of
/// widths |n_x| h and |n_y| h. Along the grid it is the linear 1/2 - d/h, which is not the
/// area at other angles: the rays' offsets to a wall at a rational slope take a few values
/// only, and the linear share's sum over them is off (by half a percent per step on a slot at
/// 30 deg to the grid at D/20; bench_stock_accuracy).
/// averageCover: its mean over a piece of the ray along which d goes linearly from dA to dB
/// (the distribution's integral in closed form), so that a piece across which the boundary
/// moves (a ramp's floor, a taper's side) counts what it covers rather than its middle's share.
class ColumnShare {
 public:
  explicit ColumnShare(const Eigen::Vector2d& n) : nx_(n.x()), ny_(n.y()) {
    a_ = std::abs(n.x());
    b_ = std::abs(n.y());
    if (a_ < b_) std::swap(a_, b_);
    outer_ = 0.5 * (a_ + b_);
    inner_ = 0.5 * (a_ - b_);
  }
  double cover(double d, double h) const { return distribution(-d / h); }
  /// The share less what an outline of curvature kappa (1/mm, positive where the inner side is
  /// convex) leaves out of the straight one: the sagitta kappa (s h)^2 / 2 along the chord
  /// s0..s1 (in h) that the straight outline cuts across the square, integrated, h kappa
  /// (s1^3 - s0^3) / 6; kept within [0, 1]. Only where the outline's radius is at least 2h
  /// (the chord's half, at most h / sqrt 2, within a third of the radius: the parabola within
  /// 4 % of the circle's sagitta); a V-bit's tip keeps the straight share. Without it the
  /// straight share overcuts a V-bit's groove and a slot's round front by a few hundredths of
  /// a percent.
  double curvedCover(double share, double d, double h, double kappa) const {
    if (kappa == 0.0 || std::abs(kappa) * h > 0.5) return share;
    const double t = -d / h;
    double s0 = -1e300, s1 = 1e300;
    const double n[2] = {nx_, ny_}, tau[2] = {-ny_, nx_};
    for (int i = 0; i < 2; ++i) {
      if (std::abs(tau[i]) < 1e-12) {
        if (std::abs(t * n[i]) > 0.5) return share;
        continue;
      }
      double lo = (-0.5 - t * n[i]) / tau[i], hi = (0.5 - t * n[i]) / tau[i];
      if (lo > hi) std::swap(lo, hi);
      s0 = std::max(s0, lo);
      s1 = std::min(s1, hi);
    }
    if (!(s1 > s0)) return share;
    return std::clamp(share - h * kappa * (s1 * s1 * s1 - s0 * s0 * s0) / 6.0, 0.0, 1.0);
  }
  double averageCover(double dA, double dB, double h) const {
    const double tA = -dA / h, tB = -dB / h;
    if (std::abs(tB - tA) < 1e-9) return distribution(0.5 * (tA + tB));
    return (antiderivative(tB) - antiderivative(tA)) / (tB - tA);
  }

 private:
  double nx_ = 1.0, ny_ = 0.0;
  double a_ = 1.0, b_ = 0.0, outer_ = 0.5, inner_ = 0.5;

  double distribution(double t) const {
    if (t <= -outer_) return 0.0;
    if (t >= outer_) return 1.0;
    if (t < -inner_) return (t + outer_) * (t + outer_) / (2.0 * a_ * b_);
    if (t <= inner_) return 0.5 + t / a_;
    return 1.0 - (outer_ - t) * (outer_ - t) / (2.0 * a_ * b_);
  }
  /// The integral of the distribution from -outer to t.
  double antiderivative(double t) const {
    const double ab6 = 6.0 * a_ * b_;
    const double atInner = b_ * b_ * b_ / std::max(ab6, 1e-300);  // (outer - inner)^3 / 6ab
    if (t <= -outer_) return 0.0;
    if (t < -inner_) return (t + outer_) * (t + outer_) * (t + outer_) / ab6;
    auto middle = [&](double u) { return 0.5 * u + u * u / (2.0 * a_); };
    if (t <= inner_) return atInner + middle(t) - middle(-inner_);
    const double atOuter = atInner + middle(inner_) - middle(-inner_);  // at +inner
    if (t < outer_)
      return atOuter + (t - inner_) -
             (b_ * b_ * b_ - (outer_ - t) * (outer_ - t) * (outer_ - t)) / ab6;
    return atOuter + b_ - (b_ * b_ * b_) / std::max(ab6, 1e-300) + (t - outer_);
  }
};

/// The direction halfway between unit directions a and b (b where they are opposite).
Eigen::Vector2d meanDirection(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d n = a + b;
  return n.norm() > 1e-12 ? Eigen::Vector2d(n.normalized()) : b;
}

/// A piece of the swept solid along a ray: heights, the share of the column it covers, and the
/// cutter's outward normal there (the line the rest of a wall's column keeps), where the
/// outline's radius (1 / kappa) is at least 2 h: a tighter one (a V-bit's tip, a small ball's
/// bottom) is no line across a column, and has none.
Interval piece(double a, double b, double cover, const Eigen::Vector2d& n, double kappa, double h) {
  if (std::abs(kappa) * h > 0.5) return {a, b, cover};
  return {a, b, cover, static_cast<float>(n.x()), static_cast<float>(n.y())};
}

/// Lowest height above the tip where the cutter's radius reaches rho, from the profile in
/// closed form (its widening pieces, lines and the lower corner arc); the cutting height
/// beyond the widest radius. For cutters that widen upwards.
double lowestAt(const AptCutter& c, double rho) {
  for (const ProfileSegment& s : c.profile()) {
    const double x0 = s.start.x(), x1 = s.end.x();
    if (!(x1 > x0) || rho > x1) continue;  // pieces that do not widen, or end inside rho
    if (rho <= x0) return s.start.y();
    if (s.kind == ProfileSegment::Kind::Line)
      return s.start.y() + (rho - x0) * (s.end.y() - s.start.y()) / (x1 - x0);
    const double dx = rho - s.center.x();
    return s.center.y() - std::sqrt(std::max(0.0, s.radius * s.radius - dx * dx));
  }
  return c.height();
}

/// Minimum of f over [lo, hi] by golden-section search down to `tol` in t, with both ends
/// compared: exact for functions convex on the interval; +inf for an empty interval. Where
/// it is taken goes to `at` when given. With `endsFirst` (for f convex: along a line), an end
/// first: where f does not fall from it over `tol`, the minimum is within `tol` of it and the
/// search is skipped (most of a short step's columns, ahead of or behind the cutter, have it
/// at an end). Not along arcs, where f is not convex.
template <class F>
double minimumOn(const F& f, double lo, double hi, double tol, bool endsFirst,
                 double* at = nullptr) {
  if (!(hi >= lo)) return std::numeric_limits<double>::infinity();
  const double fLo = f(lo), fHi = f(hi);
  auto take = [&](double v, double t) {
    if (at) *at = t;
    return v;
  };
  if (endsFirst && hi - lo > 4.0 * tol) {
    const double fIn = f(lo + tol);
    if (fLo <= fIn) return take(fLo, lo);
    const double fOut = f(hi - tol);
    if (fHi <= fOut) return take(fHi, hi);
  }
  constexpr double g = 0.38196601125010515;  // 2 - golden ratio
  double a = lo, b = hi;
  double x1 = a + g * (b - a), x2 = b - g * (b - a);
  double f1 = f(x1), f2 = f(x2);
  while (b - a > tol) {
    if (f1 <= f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = a + g * (b - a);
      f1 = f(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = b - g * (b - a);
      f2 = f(x2);
    }
  }
  const double candidates[4][2] = {{f1, x1}, {f2, x2}, {fLo, lo}, {fHi, hi}};
  int best = 0;
  for (int k = 1; k < 4; ++k)
    if (candidates[k][0] < candidates[best][0]) best = k;
  return take(candidates[best][0], candidates[best][1]);
}

/// One column seen from a step that changes height (a ramp, or a helix piece about a vertical
/// axis): the XY distance rho(t) from the column's centre q to the tip's track and the tip's
/// height z(t), t in [0, 1].
struct RampColumn {
  const StepPath& p;
  Eigen::Vector2d q;

  double rho(double t) const { return (q - p.at(t).head<2>()).norm(); }
  double z(double t) const { return p.start.z() + t * (p.end.z() - p.start.z()); }

  /// The parameters where rho(t) <= a, an interval within [0, 1] (lo > hi when empty).
  /// Arcs: the step turns less than a half turn about its centre (the caller checks).
  std::pair<double, double> within(double a) const {
    constexpr std::pair<double, double> none{1.0, 0.0};
    if (a < 0.0) return none;
    if (p.kind == StepPath::Kind::Line) {
      const Eigen::Vector2d A = p.start.head<2>(), v = p.end.head<2>() - A, w = q - A;
      const double vv = v.squaredNorm(), b = v.dot(w), c = w.squaredNorm() - a * a;
      if (vv < 1e-24) return c <= 0.0 ? std::make_pair(0.0, 1.0) : none;  // no XY motion
      const double disc = b * b - vv * c;
      if (disc < 0.0) return none;
      const double r = std::sqrt(disc);
      return {std::max(0.0, (b - r) / vv), std::min(1.0, (b + r) / vv)};
    }
    // rho^2 = dq^2 + r^2 - 2 dq r cos(theta - phi) <= a^2 about the centre c.
    const Eigen::Vector2d c = p.center.head<2>(), s = p.start.head<2>() - c, v = q - c;
    const double r = s.norm(), dq = v.norm();
    if (dq * r < 1e-12) return std::abs(dq - r) <= a ? std::make_pair(0.0, 1.0) : none;
    const double k = (dq * dq + r * r - a * a) / (2.0 * dq * r);
    if (k > 1.0) return none;
    if (k <= -1.0) return {0.0, 1.0};
    const double half = std::acos(k);
    // Angle of q from the start, in the direction of travel, in (-pi, pi].
    double d0 = std::atan2(s.x() * v.y() - s.y() * v.x(), s.dot(v));
    if (p.sweepRad < 0) d0 = -d0;
    const double sweep = std::abs(p.sweepRad);
    // theta(t) - phi = sweep t - d0 must lie in [-half, half] (+ 2 pi n, n = -1, 0, 1).
    double lo = 1.0, hi = 0.0;
    for (int n = -1; n <= 1; ++n) {
      const double t0 = std::max(0.0, (d0 - half + 2.0 * kPi * n) / sweep);
      const double t1 = std::min(1.0, (d0 + half + 2.0 * kPi * n) / sweep);
      if (t1 >= t0) {
        lo = std::min(lo, t0);
        hi = std::max(hi, t1);
      }
    }
    return {lo, hi};
  }
};

/// The swept solid of one step that may change height (a line, or a helix piece of less
/// than a quarter turn about a vertical axis), of a cutter that widens upwards, along the ray
/// of column q (spacing h) below `rayTop`: appended to `solid` as intervals with the share of
/// the column covered. Each height is a one-dimensional minimum along the step (convex along
/// a line): the lowest the cutter comes within h/2 of q (below it, no cover), within -h/2
/// (above it, full cover), and between them the band, from the XY distance d of q to the
/// slice of the swept solid (the discs of radius W(z - z(t)) along the track) and the
/// direction to its nearest disc, each counted by ColumnShare. A band up to 2h tall (most:
/// the floors and rims of ramps and helices) takes d at its ends and middle and the parabola
/// through them, in four pieces of ColumnShare::averageCover; a taller one eight pieces, each
/// averaged between the minima at its ends. Accuracy against closed forms (ramps and helical
/// bores anywhere on the grid): docs/accuracy.md, bench_stock_accuracy. One function: it runs
/// for every ray of every ramp step, and its searches share the band's closed-form pieces.
void rampBand(const StepPath& path, const AptCutter& cutter, const Eigen::Vector2d& q, double h,
              double rayTop, std::vector<Interval>& solid) {
  const RampColumn col{path, q};
  const double R = cutter.maxRadius(), H = cutter.height();
  const double zLow = std::min(path.start.z(), path.end.z());
  // Near an interior minimum a miss of dt in t costs f''dt^2/2: 1e-2 of a step is below
  // 1e-5 mm for steps of a few ray spacings; minima at the ends are exact.
  constexpr double tTol = 1e-2;
  // Cheap dismissal first (most rays of a finishing pass): nothing of the cutter is lower
  // here than the lowest tip plus the profile's height at the track's distance.
  const double rhoMin = pathDistance(path, q);
  // The band is found with h/2 (a column's half width along the grid); each ray's own half
  // width seen from the track (columnReach, up to h / sqrt 2) makes the bands wider, the
  // loop slower and the totals no closer.
  const double margin = 0.5 * h;
  if (rhoMin - margin > R || rayTop <= zLow + lowestAt(cutter, std::max(0.0, rhoMin - margin)))
    return;
  const auto reach = col.within(R + margin);
  if (reach.first > reach.second) return;
  // A flat end mill on a straight step (most of a 3D program with one): the searches below in
  // closed form. Its bottom is flat out to its radius, where the ranges keep rho + delta, so
  // the lowest point is where z(t), linear, is least: an end of the range; and its side is
  // upright, so the slice's distance is rho(t) - R, least at q's foot on the segment (exact,
  // where the searches stop up to 1e-2 of the step short of the range's end).
  const bool line = path.kind == StepPath::Kind::Line;
  const bool flatLine = cutter.shape() == CutterShape::Flat && line;
  auto lowest = [&](double delta, std::pair<double, double> range) {
    auto f = [&](double t) {
      return col.z(t) + lowestAt(cutter, std::max(0.0, col.rho(t) + delta));
    };
    if (flatLine)  // (z alone: lowestAt at the range's ends may round to beyond the radius)
      return range.first > range.second ? std::numeric_limits<double>::infinity()
                                        : std::min(col.z(range.first), col.z(range.second));
    return minimumOn(f, range.first, range.second, tTol, line);
  };
  const double zNone = lowest(-margin, reach);
  if (zNone >= rayTop) return;
  const double top = std::max(path.start.z(), path.end.z()) + H;
  const double zFull = std::min(top, lowest(margin, col.within(R - margin)));
  const double bandTop = std::min(zFull, rayTop);
  const double dz = path.end.z() - path.start.z();
  // The XY distance from q to the slice at height zs, and the direction from its nearest disc;
  // +inf where no instance's side spans zs.
  // The curvature of the slice's outline at height zs, at most: its discs' radius there,
  // taken above the step's highest tip (the smallest).
  const double zHigh = std::max(path.start.z(), path.end.z());
  auto sliceCurvature = [&](double zs) {
    const double w = zs > zHigh ? cutter.radiusAt(std::min(zs - zHigh, H)) : 0.0;
    return w > 0.0 ? 1.0 / w : std::numeric_limits<double>::infinity();
  };
  auto slice = [&](double zs, Eigen::Vector2d& away) {
    // Tip heights z(t) in [zs - H, zs]: the instances whose side spans zs.
    double t0 = reach.first, t1 = reach.second;
    if (std::abs(dz) > 1e-12) {
      const double u0 = (zs - H - path.start.z()) / dz, u1 = (zs - path.start.z()) / dz;
      t0 = std::max(t0, std::min(u0, u1));
      t1 = std::min(t1, std::max(u0, u1));
    } else if (zs < path.start.z() || zs > path.start.z() + H) {
      return std::numeric_limits<double>::infinity();
    }
    double tNearest = 0.0;
    double d = std::numeric_limits<double>::infinity();
    if (flatLine) {
      if (t1 >= t0) {
        const Eigen::Vector2d A = path.start.head<2>(), v = path.end.head<2>() - A;
        const double vv = v.squaredNorm();
        tNearest = std::clamp(vv > 1e-24 ? v.dot(q - A) / vv : t0, t0, t1);
        d = col.rho(tNearest) - R;
      }
    } else {
      d = minimumOn([&](double t) { return col.rho(t) - cutter.radiusAt(zs - col.z(t)); }, t0, t1,
                    tTol, line, &tNearest);
    }
    away = q - path.at(tNearest).head<2>();
    const double norm = away.norm();
    away = norm > 1e-12 ? Eigen::Vector2d(away / norm) : Eigen::Vector2d(1.0, 0.0);
    return d;
  };
  if (bandTop - zNone > 2.0 * h) {
    // A tall band (a steep step's side, where d has kinks): eight pieces, each with the mean
    // share of a boundary moving linearly between the distances at its ends.
    constexpr int kTallPieces = 8;
    Eigen::Vector2d awayLow(1.0, 0.0), awayHigh(1.0, 0.0);
    double dLow = slice(zNone, awayLow);
    for (int k = 0; k < kTallPieces; ++k) {
      const double a = zNone + (bandTop - zNone) * k / kTallPieces;
      const double b = zNone + (bandTop - zNone) * (k + 1) / kTallPieces;
      const double dHigh = slice(b, awayHigh);
      double cover = 0.0;
      Eigen::Vector2d n = meanDirection(awayLow, awayHigh);
      if (std::isfinite(dLow) && std::isfinite(dHigh)) {
        cover = ColumnShare(n).averageCover(dLow, dHigh, h);
      } else {
        const double d = slice(0.5 * (a + b), n);
        if (std::isfinite(d)) cover = ColumnShare(n).cover(d, h);
      }
      if (cover > 0.0) solid.push_back(piece(a, b, cover, n, sliceCurvature(0.5 * (a + b)), h));
      dLow = dHigh;
      awayLow = awayHigh;
    }
  } else if (bandTop > zNone) {
    // The distance at the band's ends and middle, the parabola through them, and the band in
    // four pieces, each with the mean share over it of a boundary moving linearly between the
    // parabola's values at its ends; where a minimum has no instance to take (+inf), two
    // pieces by their middles.
    const double zs[3] = {zNone, 0.5 * (zNone + bandTop), bandTop};
    double d[3];
    Eigen::Vector2d away[3];
    for (int k = 0; k < 3; ++k)
      d[k] = slice(zs[k], away[k]);
    if (std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2])) {
      // d(s), s in [0, 1] over the band: d0 + s (4 d1 - 3 d0 - d2) + s^2 (2 d0 - 4 d1 + 2 d2).
      const double c1 = 4.0 * d[1] - 3.0 * d[0] - d[2], c2 = 2.0 * d[0] - 4.0 * d[1] + 2.0 * d[2];
      auto dAt = [&](double s) { return d[0] + s * (c1 + s * c2); };
      constexpr int kPieces = 4;
      for (int k = 0; k < kPieces; ++k) {
        const double s0 = static_cast<double>(k) / kPieces,
                     s1 = static_cast<double>(k + 1) / kPieces;
        const Eigen::Vector2d n =
            s1 <= 0.5 ? meanDirection(away[0], away[1]) : meanDirection(away[2], away[1]);
        const double cover = ColumnShare(n).averageCover(dAt(s0), dAt(s1), h);
        if (cover > 0.0)
          solid.push_back(piece(zNone + (bandTop - zNone) * s0, zNone + (bandTop - zNone) * s1,
                                cover, n,
                                sliceCurvature(zNone + (bandTop - zNone) * 0.5 * (s0 + s1)), h));
      }
    } else {
      for (int k = 0; k < 2; ++k) {
        Eigen::Vector2d n;
        const double dmZ = 0.5 * (zs[k] + zs[k + 1]);
        const double dm = slice(dmZ, n);
        const double cover = std::isfinite(dm) ? ColumnShare(n).cover(dm, h) : 0.0;
        if (cover > 0.0) solid.push_back(piece(zs[k], zs[k + 1], cover, n, sliceCurvature(dmZ), h));
      }
    }
  }
  if (bandTop < zFull) solid.push_back({bandTop, zFull, 1.0});  // (no material there)
  if (top > zFull) solid.push_back({zFull, top, 1.0});
}

}  // namespace

/// Does the cutter's radius never shrink upwards (so that a vertical line at distance rho
/// from its axis meets it in one interval from the profile's lowest height at rho up)? For
/// the APT profile: unless its sides lean inward (beta < 0), the rule Sweep uses for convexity.
bool widensUpwards(const AptCutter& c) {
  return c.parameters().taperAngleRad >= 0.0;
}

/// The swept solid along the ray of column q (spacing h) below `rayTop` of a step that keeps
/// its height, or a plunge or retract (the cutter from its lowest to its highest position), of
/// a cutter that widens upwards, in closed form: appended to `solid`; false where it cannot
/// reach the ray's material.
bool steadySolid(const StepPath& path, const AptCutter& cutter, const Eigen::Vector2d& q, double h,
                 double rayTop, std::vector<Interval>& solid) {
  Eigen::Vector2d away;
  OutlineCurvature outline;
  const double rho = pathDistance(path, q, &away, &outline);
  const double margin = columnReach(away) * h;
  if (rho - margin > cutter.maxRadius()) return false;
  // Below the ray's highest material the cutter is narrower than the ray is far: the step
  // cannot reach it (one radius instead of the profile's inversion).
  const double z = std::min(path.start.z(), path.end.z());
  if (rayTop <= z || cutter.radiusAt(std::min(rayTop - z, cutter.height())) < rho - margin)
    return false;
  const double top = std::max(path.start.z(), path.end.z()) + cutter.height();
  // Full cover where the radius exceeds rho + margin, none below rho - margin (margin: the
  // column's half width seen from the track, h/2 to h/sqrt 2); across the band between (a
  // vertical wall: the whole height) pieces, each with the mean share of the boundary between
  // its ends, less its curvature.
  const double zFull =
      rho + margin <= cutter.maxRadius() ? z + lowestAt(cutter, rho + margin) : top;
  const double zNone = z + lowestAt(cutter, std::max(0.0, rho - margin));
  // Only the part of the band where this ray holds material matters.
  const double bandTop = std::min(zFull, rayTop);
  // The band split where the profile's pieces meet: a vertical piece (the same share all along)
  // in one, others in eight, which keep the share's rise with height for the steps after (one
  // mean over a V-bit's cone overcuts its groove). Split at the pieces' joints, so that a
  // ball's short arc does not fall inside one long piece down a deep slot.
  const ColumnShare share(away);
  // (A scratch buffer: this runs for every ray of every step.)
  static thread_local std::vector<double> cutsAt;
  cutsAt.assign(1, zNone);
  for (const ProfileSegment& seg : cutter.profile())
    for (double y : {seg.start.y(), seg.end.y()})
      if (z + y > zNone && z + y < bandTop) cutsAt.push_back(z + y);
  cutsAt.push_back(bandTop);
  std::sort(cutsAt.begin(), cutsAt.end());
  for (std::size_t g = 0; g + 1 < cutsAt.size() && bandTop > zNone; ++g) {
    const double za = cutsAt[g], zb = cutsAt[g + 1];
    if (!(zb > za)) continue;
    const double um = 0.5 * (za + zb) - z;
    bool vertical = false;
    for (const ProfileSegment& seg : cutter.profile())
      if (um >= std::min(seg.start.y(), seg.end.y()) && um <= std::max(seg.start.y(), seg.end.y()))
        vertical = seg.kind == ProfileSegment::Kind::Line && seg.start.x() == seg.end.x();
    const int pieces = vertical ? 1 : 8;
    double dLow = rho - cutter.radiusAt(za - z);
    for (int k = 0; k < pieces; ++k) {
      const double a = za + (zb - za) * k / pieces;
      const double b = za + (zb - za) * (k + 1) / pieces;
      const double w = cutter.radiusAt(0.5 * (a + b) - z);
      const double dHigh = rho - cutter.radiusAt(b - z);
      const double cover =
          share.curvedCover(share.averageCover(dLow, dHigh, h), rho - w, h, outline.at(w));
      if (cover > 0.0) solid.push_back(piece(a, b, cover, away, outline.at(w), h));
      dLow = dHigh;
    }
  }
  if (bandTop < zFull) solid.push_back({bandTop, zFull, 1.0});  // (no material there)
  if (top > zFull) solid.push_back({zFull, top, 1.0});
  return true;
}

/// rampBand, and where it finds nothing (its h/2 margin short of a column's corner that the
/// cutter reaches at the step's end or start), the cutter there as a plunge or retract takes
/// it: a retract after a ramp had taken up to 0.0012 mm^3 from nothing, the corners the ramp
/// left (tests/stock/ReferenceCuts.cpp). (Not the union with the two ends everywhere: their
/// approximate shares would be taken above the band's.)
/// A column beyond a straight step's lower end (its XY projection on the step there or past
/// it) meets that end's copy of the cutter alone: along the step every copy is both further
/// away and higher, so at each height the nearest disc is the lower end's. Its band is then
/// the one steadySolid gives that copy, as the step before left it (a plunge, a level pass,
/// the ramp's own step before): rampBand's own pieces of the same surface had differed from
/// those by a little, and what they covered beyond it was taken (a ball ramping up out of its
/// plunge took 3 % too much at D/20, 1.4 % at D/40).
void rampSolid(const StepPath& path, const AptCutter& cutter, const Eigen::Vector2d& q, double h,
               double rayTop, std::vector<Interval>& solid) {
  if (path.kind == StepPath::Kind::Line) {
    const Eigen::Vector2d a = path.start.head<2>(), v = path.end.head<2>() - a;
    const double vv = v.squaredNorm();
    const bool startLower = path.start.z() <= path.end.z();
    const double u = vv > 1e-18 ? v.dot(q - a) / vv : 0.5;
    if (vv > 1e-18 && (startLower ? u <= 0.0 : u >= 1.0)) {
      StepPath still;
      still.start = still.end = startLower ? path.start : path.end;
      if (!steadySolid(still, cutter, q, h, rayTop, solid)) return;
      // The higher copies' flutes reach higher: full cover up to the highest one's top where
      // the lower copy covers the column whole at its top.
      const double lowTop = still.start.z() + cutter.height();
      const double highTop = std::max(path.start.z(), path.end.z()) + cutter.height();
      if (!solid.empty() && solid.back().z1 >= lowTop && solid.back().f >= 1.0 && highTop > lowTop)
        solid.push_back({lowTop, highTop, 1.0});
      return;
    }
  }
  const std::size_t before = solid.size();
  rampBand(path, cutter, q, h, rayTop, solid);
  if (solid.size() > before) return;
  for (const Eigen::Vector3d& at : {path.start, path.end}) {
    StepPath still;
    still.start = still.end = at;
    steadySolid(still, cutter, q, h, rayTop, solid);
  }
}

}  // namespace engage::dexel
