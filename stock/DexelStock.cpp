#include "stock/DexelStock.h"

#include "cutters/Error.h"
#include "cutters/Geometry.h"
#include "stock/TriangleMesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace engage {
namespace {

constexpr double kPi = 3.14159265358979323846;
/// Precision of a ray's entry into and exit from a swept solid, mm.
constexpr double kZTolerance = 1e-4;
/// Angular bins of the engagement arc.
constexpr int kAngleBins = 256;
/// Steps whose boxes hold at least this many columns (together) have their tiles removed side
/// by side where there are cores (fewer: one after another, a thread's start costing more than
/// it saves); a column of a step that keeps its height (a closed form) counts less.
constexpr long kParallelColumns = 40, kParallelFlatColumns = 256;
/// Columns a tile holds along x and along y (DexelStock::removeSteps).
constexpr int kTile = 16;

using Interval = DexelStock::Interval;
using Intervals = std::vector<Interval>;

/// Shares within this of each other are the same: one cover computed twice by different sums
/// (a retract over what its step's end cut) would otherwise take 1e-18 mm^3 from nothing.
constexpr double kSameShare = 1e-12;

/// The cell of a column's losses at voxel height k, the column grown to hold it (by at least 8
/// cells, so that a cut going deeper step by step does not copy the column every step).
DexelStock::Lost& lostCell(DexelStock::LostColumn& column, int k) {
  auto& cells = column.cells;
  if (cells.empty()) {
    column.top = k;
    cells.resize(1);
  }
  const int bottom = column.top - static_cast<int>(cells.size()) + 1;
  if (k < bottom) {
    cells.resize(cells.size() + static_cast<std::size_t>(std::max(bottom - k, 8)));
  } else if (k > column.top) {
    const auto more = static_cast<std::size_t>(std::max(k - column.top, 8));
    cells.insert(cells.begin(), more, DexelStock::Lost{});
    column.top += static_cast<int>(more);
  }
  return cells[static_cast<std::size_t>(column.top - k)];
}

/// Leave at most `keep` of the column's material in [a, b] (keep = 1 - the share the cutter
/// covers); returns the material removed, mm (length x share).
double cut(Intervals& iv, double a, double b, double keep) {
  if (!(b > a)) return 0.0;
  // Most calls change nothing (air, or material already cut as far): no copy then.
  if (std::none_of(iv.begin(), iv.end(), [&](const Interval& x) {
        return x.z1 > a && x.z0 < b && x.f > keep + kSameShare;
      }))
    return 0.0;
  double removed = 0.0;
  // Scratch buffers reused from call to call (a removal calls this for every band piece of
  // every ray it reaches): no allocation once they have grown.
  static thread_local Intervals out, merged;
  out.clear();
  for (const Interval& x : iv) {
    if (x.z1 <= a || x.z0 >= b || x.f <= keep + kSameShare) {
      out.push_back(x);
      continue;
    }
    const double lo = std::max(x.z0, a), hi = std::min(x.z1, b);
    removed += (hi - lo) * (x.f - keep);
    if (x.z0 < lo) out.push_back({x.z0, lo, x.f});
    if (keep > 1e-9) out.push_back({lo, hi, keep});
    if (hi < x.z1) out.push_back({hi, x.z1, x.f});
  }
  // Neighbours with one share become one interval.
  merged.clear();
  for (const Interval& x : out) {
    if (!merged.empty() && merged.back().z1 >= x.z0 - 1e-12 && merged.back().f == x.f)
      merged.back().z1 = x.z1;
    else
      merged.push_back(x);
  }
  iv.assign(merged.begin(), merged.end());
  return removed;
}

/// Share of [a0, a1] covered by [b0, b1].
double overlap(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0)) / (a1 - a0);
}

void checkMemory(double rays) {
  const double pages = static_cast<double>(sysconf(_SC_PHYS_PAGES));
  const double pageSize = static_cast<double>(sysconf(_SC_PAGE_SIZE));
  const double bytes = rays * DexelStock::kBytesPerRay;
  if (pages > 0 && pageSize > 0 && bytes > 0.5 * pages * pageSize)
    throw ParameterError("a dexel stock of " + std::to_string(static_cast<long long>(rays)) +
                         " rays needs about " +
                         std::to_string(static_cast<long long>(bytes / 1e9)) +
                         " GB, more than half of this machine's memory; use a larger spacing");
}

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
/// widths |n_x| h and |n_y| h. Along the grid it is the linear 1/2 - d/h used before, which is
/// not the area at other angles: the rays' offsets to a wall at a rational slope take a few
/// values only, and the linear share's sum over them is off (a slot at 30 deg to the grid had
/// steps 0.55 % off at D/20, 0.047 % with this share, 0.012 % with curvedCover; a side cut 0.89 %,
/// now 0.54 %; bench_stock_accuracy).
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
  /// 4 % of the circle's sagitta); a V-bit's tip keeps the straight share. Without it a
  /// 90 deg V-bit's groove of 41.05 mm^3 came out +0.10 %, now +0.013 %, and a slot's steps at
  /// 30 deg 0.047 %, now 0.012 % (its round front).
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

/// Does the cutter's radius never shrink upwards (so that a vertical line at distance rho
/// from its axis meets it in one interval from the profile's lowest height at rho up)? For
/// the APT profile: unless its sides lean inward (beta < 0), the rule Sweep uses for convexity.
bool widensUpwards(const AptCutter& c) {
  return c.parameters().taperAngleRad >= 0.0;
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
/// at an end). Along arcs, not convex, that made a helical bore's worst step 0.47 -> 0.54 %.
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
  // mean over a V-bit's cone made its groove +2 %). With eight pieces over the whole band, a
  // ball's 1.3 mm arc fell in the first of 1 mm pieces down an 8 mm deep slot (CAMotics' heart
  // cut out -0.6 %).
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
      if (cover > 0.0) solid.push_back({a, b, cover});
      dLow = dHigh;
    }
  }
  if (bandTop < zFull) solid.push_back({bandTop, zFull, 1.0});  // (no material there)
  if (top > zFull) solid.push_back({zFull, top, 1.0});
  return true;
}

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
/// averaged between the minima at its ends.
/// Measured against the closed forms at D/20 (bench_stock_accuracy), worst step / worst total
/// over 8 ramps of 2-10 deg anywhere on the grid: flat 0.23 / 0.034 %, taper 0.069 / 0.018 %
/// (the linear share at the middles of up to 8 pieces before: 0.88 / 0.17 %, 0.24 / 0.16 %);
/// a helical bore's steps 0.47 % (0.71 %), over 8 placements 0.33 % (0.79 %), their mean
/// 0.055 % (0.14 %). Tried: one parabola for tall bands too (a steep rapid up out of the stock
/// with a bull nose -2.3 %), one per 2h of band (tiger's loop 1.5x as long), four per tall
/// band (helix 0.61 %); tall bands by their middles' exact share (a rapid rising 12 mm
/// through 1112 mm^3 +0.18 %, now +0.003 %); eight pieces between minima everywhere (2x as
/// long); two linear pieces between three minima (a helix's mean -0.2 %, a curved d under
/// its chords); halving a piece where its middle is off the chord (fooled on tapers, 0.37 %).
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
  // The band is found with h/2 (a column's half width along the grid) as before; with each
  // ray's own half width seen from the track (columnReach, up to h / sqrt 2) the bands grew
  // and CAMotics' tiger took 1.2x as long, the ramps' totals no closer (0.115 against 0.088 %).
  const double margin = 0.5 * h;
  if (rhoMin - margin > R || rayTop <= zLow + lowestAt(cutter, std::max(0.0, rhoMin - margin)))
    return;
  const auto reach = col.within(R + margin);
  if (reach.first > reach.second) return;
  // A flat end mill on a straight step (most of a 3D program with one): the searches below in
  // closed form. Its bottom is flat out to its radius, where the ranges keep rho + delta, so
  // the lowest point is where z(t), linear, is least: an end of the range; and its side is
  // upright, so the slice's distance is rho(t) - R, least at q's foot on the segment. CAMotics'
  // tiger's loop 0.65 -> 0.38 s, flower_mold's 0.55 -> 0.29 s (one core); their removed
  // volumes +0.007 % and +0.024 %; the ramps anywhere on the grid (bench_stock_accuracy)
  // worst step 0.233 -> 0.248 %, total 0.034 -> 0.042 % (the searches had stopped up to 1e-2
  // of the step short of the range's end), the thin cuts' figures unchanged.
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
      if (std::isfinite(dLow) && std::isfinite(dHigh)) {
        cover = ColumnShare(meanDirection(awayLow, awayHigh)).averageCover(dLow, dHigh, h);
      } else {
        Eigen::Vector2d away;
        const double d = slice(0.5 * (a + b), away);
        if (std::isfinite(d)) cover = ColumnShare(away).cover(d, h);
      }
      if (cover > 0.0) solid.push_back({a, b, cover});
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
          solid.push_back({zNone + (bandTop - zNone) * s0, zNone + (bandTop - zNone) * s1, cover});
      }
    } else {
      for (int k = 0; k < 2; ++k) {
        Eigen::Vector2d n;
        const double dm = slice(0.5 * (zs[k] + zs[k + 1]), n);
        const double cover = std::isfinite(dm) ? ColumnShare(n).cover(dm, h) : 0.0;
        if (cover > 0.0) solid.push_back({zs[k], zs[k + 1], cover});
      }
    }
  }
  if (bandTop < zFull) solid.push_back({bandTop, zFull, 1.0});  // (no material there)
  if (top > zFull) solid.push_back({zFull, top, 1.0});
}

/// rampBand, and where it finds nothing (its h/2 margin short of a column's corner that the
/// cutter reaches at the step's end or start), the cutter there as a plunge or retract takes
/// it: a retract after a ramp had taken up to 0.0012 mm^3 from nothing, the corners the ramp
/// left (tests/stock/ReferenceCuts.cpp). (The union with the two ends everywhere made ramps
/// of a taper 0.17 % off: their approximate shares above the band's.)
void rampSolid(const StepPath& path, const AptCutter& cutter, const Eigen::Vector2d& q, double h,
               double rayTop, std::vector<Interval>& solid) {
  const std::size_t before = solid.size();
  rampBand(path, cutter, q, h, rayTop, solid);
  if (solid.size() > before) return;
  for (const Eigen::Vector3d& at : {path.start, path.end}) {
    StepPath still;
    still.start = still.end = at;
    steadySolid(still, cutter, q, h, rayTop, solid);
  }
}

}  // namespace

double DexelStock::memoryBound(const Box3& b, double spacing) {
  const double nx = std::ceil((b.max.x() - b.min.x()) / spacing - 1e-9);
  const double ny = std::ceil((b.max.y() - b.min.y()) / spacing - 1e-9);
  return nx * ny * kBytesPerRay;
}

DexelStock::DexelStock(const Box3& b, double spacing) : h_(spacing) {
  if (!(spacing > 0.0 && std::isfinite(spacing)))
    throw ParameterError("dexel spacing must be positive, found " + std::to_string(spacing) +
                         " mm");
  if (!(b.max.x() > b.min.x() && b.max.y() > b.min.y() && b.max.z() > b.min.z()))
    throw ParameterError("the stock box is empty");
  const double nx = std::ceil((b.max.x() - b.min.x()) / spacing - 1e-9);
  const double ny = std::ceil((b.max.y() - b.min.y()) / spacing - 1e-9);
  checkMemory(nx * ny);
  nx_ = static_cast<int>(nx);
  ny_ = static_cast<int>(ny);
  x0_ = b.min.x();
  y0_ = b.min.y();
  weight_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_), 0.0);
  rays_.assign(weight_.size(), {});
}

DexelStock DexelStock::box(const Box3& b, double spacing) {
  DexelStock s(b, spacing);
  // The grid starts at the box's corner: every column is covered whole but the last row and
  // column, covered by their share of the box.
  for (int j = 0; j < s.ny_; ++j)
    for (int i = 0; i < s.nx_; ++i) {
      const double x = s.x0_ + i * spacing, y = s.y0_ + j * spacing;
      const double share = overlap(x, x + spacing, b.min.x(), b.max.x()) *
                           overlap(y, y + spacing, b.min.y(), b.max.y());
      if (share <= 0.0) continue;
      s.weight_[s.index(i, j)] = share;
      s.rays_[s.index(i, j)] = {{b.min.z(), b.max.z(), 1.0}};
    }
  return s;
}

DexelStock DexelStock::fromColumns(double x0, double y0, double spacing, int nx, int ny,
                                   std::vector<std::vector<Interval>> rays) {
  if (nx <= 0 || ny <= 0 ||
      rays.size() != static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny))
    throw ParameterError("dexel columns: expected " + std::to_string(nx) + " x " +
                         std::to_string(ny) + " rays, found " + std::to_string(rays.size()));
  Box3 b;
  b.min = {x0, y0, 1e300};
  b.max = {x0 + nx * spacing, y0 + ny * spacing, -1e300};
  for (const auto& r : rays)
    if (!r.empty()) {
      b.min.z() = std::min(b.min.z(), r.front().z0);
      b.max.z() = std::max(b.max.z(), r.back().z1);
    }
  if (!(b.max.z() > b.min.z())) throw ParameterError("the stock holds no material");
  DexelStock s(b, spacing);
  s.nx_ = nx;  // (the box's rounding could add a column)
  s.ny_ = ny;
  s.weight_.assign(rays.size(), 1.0);
  s.rays_ = std::move(rays);
  return s;
}

DexelStock DexelStock::fromMesh(const std::string& path, double spacing) {
  const TriangleMesh mesh = readMesh(path);
  if (mesh.triangles.empty()) throw Error("'" + path + "' holds no triangles");
  if (const std::size_t open = boundaryEdgeCount(mesh))
    throw ParameterError("'" + path + "' is not closed: " + std::to_string(open) +
                         " edges belong to one triangle only");
  Box3 b;
  b.min = Eigen::Vector3d::Constant(1e300);
  b.max = Eigen::Vector3d::Constant(-1e300);
  for (const auto& p : mesh.points) {
    const Eigen::Vector3d q(p[0], p[1], p[2]);
    b.min = b.min.cwiseMin(q);
    b.max = b.max.cwiseMax(q);
  }
  DexelStock s(b, spacing);
  // Every ray through the column centres: the heights where it crosses the triangles,
  // sorted, paired inside-outside. A ray through an edge or a vertex meets several triangles
  // at one height: those facing the same way count once (it crosses the surface once), those
  // facing opposite ways (a silhouette it grazes) both count (an empty interval).
  struct Hit {
    double z;
    bool up;
  };
  std::vector<std::vector<Hit>> hits(s.rays_.size());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a(mesh.points[t[0]][0], mesh.points[t[0]][1], mesh.points[t[0]][2]);
    const Eigen::Vector3d bb(mesh.points[t[1]][0], mesh.points[t[1]][1], mesh.points[t[1]][2]);
    const Eigen::Vector3d c(mesh.points[t[2]][0], mesh.points[t[2]][1], mesh.points[t[2]][2]);
    const double det = (bb.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (bb.y() - a.y());
    if (std::abs(det) < 1e-18) continue;  // vertical: no ray crosses it
    const double xl = std::min({a.x(), bb.x(), c.x()}), xh = std::max({a.x(), bb.x(), c.x()});
    const double yl = std::min({a.y(), bb.y(), c.y()}), yh = std::max({a.y(), bb.y(), c.y()});
    const int i0 = std::max(0, static_cast<int>(std::ceil((xl - s.x0_) / spacing - 0.5)));
    const int i1 = std::min(s.nx_ - 1, static_cast<int>(std::floor((xh - s.x0_) / spacing - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((yl - s.y0_) / spacing - 0.5)));
    const int j1 = std::min(s.ny_ - 1, static_cast<int>(std::floor((yh - s.y0_) / spacing - 0.5)));
    constexpr double kEdge = 1e-12;  // barycentric slack: edges belong to both triangles
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double x = s.x0_ + (i + 0.5) * spacing, y = s.y0_ + (j + 0.5) * spacing;
        const double u = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / det;
        const double v = ((bb.x() - a.x()) * (y - a.y()) - (x - a.x()) * (bb.y() - a.y())) / det;
        if (u < -kEdge || v < -kEdge || u + v > 1.0 + kEdge) continue;
        hits[s.index(i, j)].push_back(
            {a.z() + u * (bb.z() - a.z()) + v * (c.z() - a.z()), det > 0.0});
      }
  }
  for (std::size_t k = 0; k < hits.size(); ++k) {
    auto& hz = hits[k];
    std::sort(hz.begin(), hz.end(),
              [](const Hit& p, const Hit& q) { return p.z != q.z ? p.z < q.z : p.up < q.up; });
    std::vector<double> z;
    for (std::size_t m = 0; m < hz.size(); ++m)
      if (m == 0 || std::abs(hz[m].z - hz[m - 1].z) > 1e-9 || hz[m].up != hz[m - 1].up)
        z.push_back(hz[m].z);
    for (std::size_t m = 0; m + 1 < z.size(); m += 2)
      if (z[m + 1] > z[m]) s.rays_[k].push_back({z[m], z[m + 1], 1.0});
    s.weight_[k] = s.rays_[k].empty() ? 0.0 : 1.0;
  }
  return s;
}

double DexelStock::volume() const {
  double v = 0.0;
  for (std::size_t k = 0; k < rays_.size(); ++k) {
    double length = 0.0;
    for (const Interval& x : rays_[k])
      length += (x.z1 - x.z0) * x.f;
    v += length * weight_[k];
  }
  return v * h_ * h_;
}

Box3 DexelStock::bounds() const {
  Box3 b;
  b.min = Eigen::Vector3d::Constant(1e300);
  b.max = Eigen::Vector3d::Constant(-1e300);
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) {
      const auto& r = rays_[index(i, j)];
      if (r.empty()) continue;
      b.min = b.min.cwiseMin(Eigen::Vector3d(x0_ + i * h_, y0_ + j * h_, r.front().z0));
      b.max = b.max.cwiseMax(Eigen::Vector3d(x0_ + (i + 1) * h_, y0_ + (j + 1) * h_, r.back().z1));
    }
  if (b.min.x() > b.max.x()) b.min = b.max = Eigen::Vector3d::Zero();
  return b;
}

std::size_t DexelStock::segments() const {
  std::size_t n = 0;
  for (const auto& r : rays_)
    n += r.size();
  return n;
}

std::size_t DexelStock::memoryBytes() const {
  std::size_t bytes = weight_.size() * sizeof(double) + rays_.size() * sizeof(Intervals);
  for (const auto& r : rays_)
    bytes += r.capacity() * sizeof(Interval);
  return bytes;
}

DexelStock::ColumnBox DexelStock::insideBox(const Sweep& sweep) const {
  const Box3 sb = sweep.bounds();
  return {std::max(0, static_cast<int>(std::floor((sb.min.x() - x0_) / h_))),
          std::min(nx_ - 1, static_cast<int>(std::floor((sb.max.x() - x0_) / h_))),
          std::max(0, static_cast<int>(std::floor((sb.min.y() - y0_) / h_))),
          std::min(ny_ - 1, static_cast<int>(std::floor((sb.max.y() - y0_) / h_)))};
}

void DexelStock::addInside(const Sweep& sweep, double top, int i, int j, double& sum) const {
  const Box3 sb = sweep.bounds();
  forPieces(i, j, sb.min.z(), std::min(top, sb.max.z()), [&](const Eigen::Vector3d& p, double v) {
    if (sweep.signedDistance(p) < 0.0) sum += v;
  });
}

void DexelStock::addInside(const PartSweep& part, int i, int j, double& slim, double& full) const {
  const Box3 fb = part.full->bounds(), sb = part.slim->bounds();
  if (fb.min.z() != sb.min.z() || fb.max.z() != sb.max.z()) {  // (not a part and its slim one)
    addInside(*part.slim, part.top, i, j, slim);
    addInside(*part.full, part.top, i, j, full);
    return;
  }
  // The same pieces as addInside takes for either; the slim part, which lies within the full
  // one, asked only inside it: where nothing is met the check costs what the slim part's alone
  // did (asking it within half a cell of the full one too: a 1 mm ball's shank active on every
  // step of the finishing raster, one core, 6 % longer than the slim part alone).
  forPieces(i, j, fb.min.z(), std::min(part.top, fb.max.z()),
            [&](const Eigen::Vector3d& p, double v) {
              if (!(part.full->signedDistance(p) < 0.0)) return;
              full += v;
              if (part.slim->signedDistance(p) < 0.0) slim += v;
            });
}

double DexelStock::materialInside(const Sweep& sweep, double top) const {
  const ColumnBox b = insideBox(sweep);
  double sum = 0.0;
  for (int j = b.j0; j <= b.j1; ++j)
    for (int i = b.i0; i <= b.i1; ++i)
      addInside(sweep, top, i, j, sum);
  return sum * h_ * h_;
}

std::vector<double> DexelStock::materialAt(const std::vector<Eigen::Vector3d>& points) const {
  std::vector<double> out;
  out.reserve(points.size());
  // The share of ray (i, j) at height z: its interval's share there, times the column's.
  auto at = [&](int i, int j, double z) {
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return 0.0;
    for (const Interval& piece : rays_[index(i, j)])
      if (z >= piece.z0 && z < piece.z1) return piece.f * weight_[index(i, j)];
    return 0.0;
  };
  for (const Eigen::Vector3d& p : points) {
    // Ray (i, j) stands at x0 + (i + 1/2) h.
    const double gx = (p.x() - x0_) / h_ - 0.5, gy = (p.y() - y0_) / h_ - 0.5;
    const int i = static_cast<int>(std::floor(gx)), j = static_cast<int>(std::floor(gy));
    const double tx = gx - i, ty = gy - j;
    out.push_back((1 - tx) * (1 - ty) * at(i, j, p.z()) + tx * (1 - ty) * at(i + 1, j, p.z()) +
                  (1 - tx) * ty * at(i, j + 1, p.z()) + tx * ty * at(i + 1, j + 1, p.z()));
  }
  return out;
}

Removal DexelStock::remove(const Sweep& sweep, int step, double dtSeconds) {
  return removeSteps({StepCut{&sweep, step, dtSeconds, {}}}).front();
}

/// Consecutive steps overlap (each starts where the last ended), so steps cannot run side by
/// side; columns can, each taking the steps that reach it in their order. A batch of steps is
/// taken in tiles of 16 x 16 columns, the tiles side by side. Before, one step's rows ran side
/// by side when its box held 40 columns (256 for a level step): programs of small steps
/// (CAMotics' tiger, 22 columns a step) never did. Loops on 2 cores against one, CAMotics'
/// projects at their grids: tiger 1.33x, flower_mold 1.6x, cameo 1.7x, bear 1.8x (one core
/// unchanged). Tried: tiles of 8 and 32 columns (tiger 0.265 / 0.281 / 0.319 s for 8 / 16 /
/// 32, the others within 3 %); batches of 32, 64, 128 and 512 steps (tiger's loop 0.41, 0.35,
/// 0.29, 0.25 s; bear's at 64 and more the same, its peak 100 -> 102 MiB from 64 to 128: the
/// simulation ends a batch at 128 steps or 8192 columns).
std::vector<Removal> DexelStock::removeSteps(const std::vector<StepCut>& steps) {
  // What each step does to every column, read only while the tiles run.
  struct Plan {
    Box3 sb;
    bool flat = false;
    std::vector<StepPath> pieces;
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
    Eigen::Vector2d u, n;  // feed direction at the step's end (as the voxel stock takes it), left
    std::vector<ColumnBox> parts;  // the columns each of the step's parts asks (insideBox)
  };
  std::vector<Plan> plans(steps.size());
  double work = 0.0;  // columns that change height; a height-keeping one counts less (below)
  for (std::size_t s = 0; s < steps.size(); ++s) {
    Plan& g = plans[s];
    if (!steps[s].sweep) continue;  // (its parts alone: below)
    const Sweep& sweep = *steps[s].sweep;
    const StepPath& path = sweep.path();
    const AptCutter& cutter = sweep.cutter();
    g.sb = sweep.bounds();
    // Closed form: steps that keep their height, and plunges and retracts (the cutter from its
    // lowest to its highest position), of cutters that widen upwards.
    const bool vertical = path.kind == StepPath::Kind::Line &&
                          (path.end.head<2>() - path.start.head<2>()).norm() < 1e-12;
    g.flat = (vertical || (std::abs(path.end.z() - path.start.z()) < 1e-12 &&
                           path.kind != StepPath::Kind::Polyline)) &&
             widensUpwards(cutter);
    // Steps that change height, of such cutters: lines, helix pieces of less than a quarter
    // turn, and the line pieces of polylines (arcs in the XZ and YZ planes, splines), each
    // seen from every ray by rampSolid. Others (inward-leaning sides, longer turns): the march.
    if (!g.flat && widensUpwards(cutter)) {
      if (path.kind == StepPath::Kind::Line ||
          (path.kind == StepPath::Kind::ArcXY && std::abs(path.sweepRad) < 0.5 * kPi)) {
        g.pieces.push_back(path);
      } else if (path.kind == StepPath::Kind::Polyline) {
        for (std::size_t k = 1; k < path.points.size(); ++k) {
          StepPath line;
          line.start = path.points[k - 1];
          line.end = path.points[k];
          g.pieces.push_back(line);
        }
      }
    }
    g.i0 = std::max(0, static_cast<int>(std::floor((g.sb.min.x() - x0_) / h_ - 0.5)));
    g.i1 = std::min(nx_ - 1, static_cast<int>(std::ceil((g.sb.max.x() - x0_) / h_ - 0.5)));
    g.j0 = std::max(0, static_cast<int>(std::floor((g.sb.min.y() - y0_) / h_ - 0.5)));
    g.j1 = std::min(ny_ - 1, static_cast<int>(std::ceil((g.sb.max.y() - y0_) / h_ - 0.5)));
    g.u = path.feedDirectionAtEnd();
    g.n = Eigen::Vector2d(-g.u.y(), g.u.x());
    if (g.i1 >= g.i0 && g.j1 >= g.j0)
      work += static_cast<double>(g.i1 - g.i0 + 1) * (g.j1 - g.j0 + 1) *
              (g.flat ? static_cast<double>(kParallelColumns) / kParallelFlatColumns : 1.0);
  }

  // The columns in tiles; each tile applies the steps that reach it in their order, with its
  // own sums per step (a Part) and the loss columns it starts; the steps' sums are then taken
  // tile by tile in the tiles' order: the same sums whatever the thread count and however
  // the steps come in batches.
  struct Cut {
    Eigen::Vector2d xy;
    double z0, z1;
  };
  struct Part {
    double volume = 0.0, lateral = 0.0, sMin = 1e300, sMax = -1e300;
    long changed = 0, visited = 0;
    std::size_t cutsEnd = 0;  // its cuts: the tile's from the last part's end to this
    std::vector<std::pair<double, double>> met;  // the step's tool parts: slim, full (mm)
  };
  struct Started {
    std::size_t step;  // in this batch
    std::size_t ray;
    LostColumn column;
  };
  struct Tile {
    int index = 0;
    std::vector<std::size_t> steps;  // in order
    std::vector<Part> parts;         // one for each of steps
    std::vector<Cut> cuts;           // the parts' cuts, one part after another
    std::vector<Started> started;    // in the order started
  };
  const int tilesX = (nx_ + kTile - 1) / kTile;
  std::vector<std::pair<int, std::size_t>> reach;  // (tile, step), by tile then step
  for (std::size_t s = 0; s < plans.size(); ++s) {
    Plan& g = plans[s];
    auto reaches = [&](int i0, int i1, int j0, int j1) {
      if (i1 < i0 || j1 < j0) return;
      for (int tj = j0 / kTile; tj <= j1 / kTile; ++tj)
        for (int ti = i0 / kTile; ti <= i1 / kTile; ++ti)
          reach.emplace_back(tj * tilesX + ti, s);
    };
    reaches(g.i0, g.i1, g.j0, g.j1);
    // The tool's parts ask the columns under them too (a holder reaches wider than its cutter).
    for (const PartSweep& part : steps[s].parts) {
      const ColumnBox b = insideBox(*part.full);
      g.parts.push_back(b);
      reaches(b.i0, b.i1, b.j0, b.j1);
    }
  }
  std::sort(reach.begin(), reach.end());
  reach.erase(std::unique(reach.begin(), reach.end()), reach.end());
  std::vector<Tile> tiles;
  for (const auto& [t, s] : reach) {
    if (tiles.empty() || tiles.back().index != t) {
      tiles.emplace_back();
      tiles.back().index = t;
    }
    tiles.back().steps.push_back(s);
  }

  // One column (i, j) of the tile under step s.
  auto removeColumn = [&](std::size_t s, int i, int j, Part& part, Tile& tile, std::int32_t* local,
                          std::vector<Interval>& solid) {
    Intervals& ray = rays_[index(i, j)];
    if (ray.empty()) return;
    const Plan& g = plans[s];
    const Sweep& sweep = *steps[s].sweep;
    const StepPath& path = sweep.path();
    const AptCutter& cutter = sweep.cutter();
    const Eigen::Vector2d q(x0_ + (i + 0.5) * h_, y0_ + (j + 0.5) * h_);
    // The swept solid along this ray: intervals with the share of the column it covers.
    solid.clear();
    if (g.flat) {
      if (!steadySolid(path, cutter, q, h_, ray.back().z1, solid)) return;
    } else if (!g.pieces.empty()) {
      ++part.visited;
      for (const StepPath& piece : g.pieces)
        rampSolid(piece, cutter, q, h_, ray.back().z1, solid);
      if (solid.empty()) return;
    } else {
      ++part.visited;
      const double lo = std::max(g.sb.min.z(), ray.front().z0) - kZTolerance;
      const double hi = std::min(g.sb.max.z(), ray.back().z1) + kZTolerance;
      if (!(hi > lo)) return;
      auto d = [&](double z) { return sweep.signedDistance({q.x(), q.y(), z}); };
      double z = lo, dz = d(z);
      bool inside = dz < 0.0;
      double entry = lo;
      while (z < hi) {
        // At least h/8 a step: the distance only shrinks towards the surface (a bound),
        // and a sliver thinner than that is below the model's resolution anyway.
        const double advance = std::max(std::abs(dz), 0.125 * h_);
        double z2 = std::min(z + advance, hi);
        const double d2 = d(z2);
        if ((d2 < 0.0) != inside) {
          double a = z, b = z2;  // a sign change within [a, b]: bisect it
          while (b - a > kZTolerance) {
            const double m = 0.5 * (a + b);
            ((d(m) < 0.0) == inside ? a : b) = m;
          }
          const double crossing = 0.5 * (a + b);
          if (inside)
            solid.push_back({entry, crossing, 1.0});
          else
            entry = crossing;
          inside = !inside;
        }
        z = z2;
        dz = d2;
      }
      if (inside) solid.push_back({entry, hi, 1.0});
    }
    double removed = 0.0;
    LostColumn* column = nullptr;  // this ray's losses, found or started on its first loss
    for (const Interval& sx : solid) {
      // What of the ray in [z0, z1] loses material; remember where, for the engagement.
      for (const Interval& x : ray)
        if (x.z1 > sx.z0 && x.z0 < sx.z1 && x.f > 1.0 - sx.f + kSameShare)
          tile.cuts.push_back({q, std::max(x.z0, sx.z0), std::min(x.z1, sx.z1)});
      // The capture: what each of the ray's intervals the piece cuts loses, as cut() takes
      // it, summed into the column's cells of voxel height, with the first step to take some
      // (so that removed.vdb holds the removed volume, and in its place). A log of one entry
      // per column, step and span at the span's mean share had put a wall column's rest and
      // the material below it at one share: up to 1.6 voxels of material in some voxels of
      // CAMotics' heart, and removed.vdb (its voxels held to 1) 2.7 % short of the removed
      // volume (bear 0.8 %, tiger 0.4 %); now exact to float rounding. The cells take less
      // memory than that log (bear 246 -> 200 MB, cameo 435 -> 398 MB) and the loop 5-7 %
      // longer (cameo 3.24 -> 3.45 s, bear 2.26 -> 2.39 s, medians of three alternating
      // runs, one core). Entries per ray interval (exact, but bear 734 MB), or merged within
      // 0.1 of share (heart -0.14 %, bear 452 MB), were tried first.
      const double keep = 1.0 - sx.f;
      if (capture_) {
        for (const Interval& x : ray)
          if (x.z1 > sx.z0 && x.z0 < sx.z1 && x.f > keep + kSameShare) {
            if (!column) {
              // Found in lost_, or among those this tile started in this batch, or started.
              const std::uint32_t at = lostIndex_[index(i, j)];
              const std::size_t k = static_cast<std::size_t>((j % kTile) * kTile + i % kTile);
              if (at != kNoColumn) {
                column = &lost_[at];
              } else if (local[k] >= 0) {
                column = &tile.started[static_cast<std::size_t>(local[k])].column;
              } else {
                local[k] = static_cast<std::int32_t>(tile.started.size());
                tile.started.push_back({s, index(i, j), LostColumn{}});
                column = &tile.started.back().column;
              }
            }
            const double share = (x.f - keep) * weight_[index(i, j)];
            voxelHeights(h_, std::max(x.z0, sx.z0), std::min(x.z1, sx.z1), [&](int k, double z) {
              Lost& cell = lostCell(*column, k);
              cell.share += static_cast<float>(z * share);
              if (cell.step < 0) cell.step = steps[s].step;
            });
          }
      }
      removed += cut(ray, sx.z0, sx.z1, keep);
    }
    if (removed <= 0.0) return;
    const double w = weight_[index(i, j)];
    const double volume = removed * w * h_ * h_;
    part.volume += volume;
    ++part.changed;
    const double side = (q - path.end.head<2>()).dot(g.n);
    part.lateral += volume * side;
    part.sMin = std::min(part.sMin, side - 0.5 * h_);
    part.sMax = std::max(part.sMax, side + 0.5 * h_);
  };
  // A tile: the steps that reach it in order, each over its columns row by row. Its loss
  // columns are started in its own list (lost_ must not grow, and move, under another
  // tile's writes), found there again by `local` until the batch is taken.
  auto runTile = [&](Tile& tile) {
    tile.parts.resize(tile.steps.size());
    std::int32_t local[kTile * kTile];
    std::fill(local, local + kTile * kTile, -1);
    static thread_local std::vector<Interval> solid;  // (scratch, no allocation once grown)
    const int ti0 = (tile.index % tilesX) * kTile, tj0 = (tile.index / tilesX) * kTile;
    for (std::size_t a = 0; a < tile.steps.size(); ++a) {
      const std::size_t s = tile.steps[a];
      const Plan& g = plans[s];
      for (int j = std::max(g.j0, tj0); j <= std::min(g.j1, tj0 + kTile - 1); ++j)
        for (int i = std::max(g.i0, ti0); i <= std::min(g.i1, ti0 + kTile - 1); ++i)
          removeColumn(s, i, j, tile.parts[a], tile, local, solid);
      tile.parts[a].cutsEnd = tile.cuts.size();
      // The tool's parts, after the step's removal: the slim one and the full one (whether the
      // full one is needed depends on all tiles' slim sums: it is asked in every tile, the
      // slim one near it).
      if (g.parts.empty()) continue;
      auto& met = tile.parts[a].met;
      met.assign(g.parts.size(), {0.0, 0.0});
      for (std::size_t k = 0; k < g.parts.size(); ++k) {
        const ColumnBox& b = g.parts[k];
        const PartSweep& part = steps[s].parts[k];
        for (int j = std::max(b.j0, tj0); j <= std::min(b.j1, tj0 + kTile - 1); ++j)
          for (int i = std::max(b.i0, ti0); i <= std::min(b.i1, ti0 + kTile - 1); ++i)
            addInside(part, i, j, met[k].first, met[k].second);
      }
    }
  };
  if (tiles.size() > 1 && work >= kParallelColumns && tbb::this_task_arena::max_concurrency() > 1) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t t = r.begin(); t != r.end(); ++t)
                          runTile(tiles[t]);
                      });
  } else {
    for (Tile& tile : tiles)
      runTile(tile);
  }

  // Each step's sums, tile by tile; the loss columns its tiles started join lost_.
  std::vector<Removal> outs(steps.size());
  std::vector<std::size_t> nextPart(tiles.size(), 0), nextStarted(tiles.size(), 0);
  std::vector<Cut> cuts;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const Plan& g = plans[s];
    Removal& out = outs[s];
    double zMin = 1e300, zMax = -1e300, sMin = 1e300, sMax = -1e300;
    cuts.clear();
    out.partsMet.assign(steps[s].parts.size(), {0.0, 0.0});
    for (std::size_t t = 0; t < tiles.size(); ++t) {
      Tile& tile = tiles[t];
      if (nextPart[t] < tile.steps.size() && tile.steps[nextPart[t]] == s) {
        const std::size_t from = nextPart[t] == 0 ? 0 : tile.parts[nextPart[t] - 1].cutsEnd;
        const Part& part = tile.parts[nextPart[t]++];
        out.volume += part.volume;
        out.lateral += part.lateral;
        out.voxelsChanged += part.changed;
        out.voxelsVisited += part.visited;
        sMin = std::min(sMin, part.sMin);
        sMax = std::max(sMax, part.sMax);
        cuts.insert(cuts.end(), tile.cuts.begin() + static_cast<std::ptrdiff_t>(from),
                    tile.cuts.begin() + static_cast<std::ptrdiff_t>(part.cutsEnd));
        for (std::size_t k = 0; k < part.met.size(); ++k) {
          out.partsMet[k].first += part.met[k].first;
          out.partsMet[k].second += part.met[k].second;
        }
      }
      for (; nextStarted[t] < tile.started.size() && tile.started[nextStarted[t]].step == s;
           ++nextStarted[t]) {
        Started& st = tile.started[nextStarted[t]];
        lostIndex_[st.ray] = static_cast<std::uint32_t>(lost_.size());
        lost_.push_back(std::move(st.column));
      }
    }
    for (std::size_t k = 0; k < out.partsMet.size(); ++k) {
      auto& [slim, full] = out.partsMet[k];
      slim *= h_ * h_;
      full = slim > steps[s].parts[k].threshold ? full * h_ * h_ : 0.0;
    }
    if (out.voxelsChanged > 0) {  // (then the step has its sweep)
      const AptCutter& cutter = steps[s].sweep->cutter();
      const Eigen::Vector3d end = steps[s].sweep->path().end;
      for (const Cut& c : cuts) {
        zMin = std::min(zMin, c.z0 - end.z());
        zMax = std::max(zMax, c.z1 - end.z());
      }
      out.lateral /= out.volume;
      out.axialDepth = std::min(zMax - std::max(zMin, 0.0), cutter.height());
      out.top = std::min(zMax, cutter.height());
      out.radialWidth = sMax - sMin;
      // Engagement angle: the arc of the periphery, at mid depth, where this step removed
      // material (rays within a column of the cutter's edge there).
      const double zMid = std::clamp(0.5 * out.axialDepth, 0.0, cutter.height());
      const double edge = cutter.radiusAt(zMid);
      std::vector<bool> bin(kAngleBins, false);
      for (const Cut& c : cuts) {
        if (c.z0 > end.z() + zMid || c.z1 < end.z() + zMid) continue;
        const Eigen::Vector2d rel = c.xy - end.head<2>();
        if (std::abs(rel.norm() - edge) > h_) continue;
        double theta = std::atan2(rel.dot(g.n), rel.dot(g.u));
        if (theta < 0) theta += 2.0 * kPi;
        bin[static_cast<std::size_t>(
            std::min(kAngleBins - 1.0, theta / (2.0 * kPi) * kAngleBins))] = true;
      }
      out.engagementRad =
          2.0 * kPi * static_cast<double>(std::count(bin.begin(), bin.end(), true)) / kAngleBins;
    }
    const int step = steps[s].step;
    if (capture_ && step >= 0) {
      if (stepMrr_.size() <= static_cast<std::size_t>(step))
        stepMrr_.resize(static_cast<std::size_t>(step) + 1, 0.0);
      const double dt = steps[s].dtSeconds;
      stepMrr_[static_cast<std::size_t>(step)] = dt > 0.0 ? out.volume / (dt / 60.0) : 0.0;
    }
  }
  return outs;
}

}  // namespace engage
