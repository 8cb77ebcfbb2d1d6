#pragma once
// Helpers shared by the stock tests (tests/stock/VoxelStock.cpp, tests/stock/DexelStock.cpp,
// the thin-cut reference) and the stock benchmarks: a box of either model, straight passes cut
// at 30 degrees to the grid, and the per-step errors against a closed form.

#include "cutters/Numbers.h"
#include "cutters/Sweep.h"
#include "stock/DexelStock.h"
#include "stock/Stock.h"
#include "stock/TriangleMesh.h"
#include "stock/VoxelStock.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace engage::test {

/// A box stock of the named model ("voxel", else dexels) at cell size h.
inline std::unique_ptr<Stock> boxStock(const std::string& model, const Box3& box, double h) {
  if (model == "voxel") return std::make_unique<VoxelStock>(VoxelStock::box(box, h));
  return std::make_unique<DexelStock>(DexelStock::box(box, h));
}

const Eigen::Vector3d kDir(std::cos(kPi / 6), std::sin(kPi / 6), 0.0);  // 30 deg to the grid
const Eigen::Vector3d kSide(-std::sin(kPi / 6), std::cos(kPi / 6), 0.0);

/// The volume a closed mesh encloses (mm^3), from its triangles' signed tetrahedra with the
/// origin: positive where they face outwards.
inline double meshVolume(const TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles) {
    const auto& p = m.points[t[0]];
    const auto& q = m.points[t[1]];
    const auto& r = m.points[t[2]];
    v += (double{p[0]} * (double{q[1]} * r[2] - double{q[2]} * r[1]) -
          double{p[1]} * (double{q[0]} * r[2] - double{q[2]} * r[0]) +
          double{p[2]} * (double{q[0]} * r[1] - double{q[1]} * r[0])) /
         6.0;
  }
  return v;
}

inline StepPath line(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  StepPath p;
  p.start = a;
  p.end = b;
  return p;
}

/// A counter-clockwise XY arc piece of radius r about `centre` (its x, y) from angle a0 to
/// a1 (radians), the tip at height z.
inline StepPath arc(const Eigen::Vector3d& centre, double r, double a0, double a1, double z) {
  StepPath p;
  p.kind = StepPath::Kind::ArcXY;
  p.center = centre;
  p.start = Eigen::Vector3d(centre.x() + r * std::cos(a0), centre.y() + r * std::sin(a0), z);
  p.end = Eigen::Vector3d(centre.x() + r * std::cos(a1), centre.y() + r * std::sin(a1), z);
  p.sweepRad = a1 - a0;
  return p;
}

/// Volumes of the steps of a helical bore: the tip on a helix of radius `helixRadius` about
/// the vertical line through `centre` (from `centre` + helixRadius x, at its height), `pitch`
/// lower per counter-clockwise turn, `turns` turns in arc pieces of `L` (mm of XY arc).
inline std::vector<double> helix(Stock& stock, const AptCutter& c, const Eigen::Vector3d& centre,
                                 double helixRadius, double pitch, double turns, double L) {
  const double h = stock.resolution();
  const double step = L / helixRadius;  // radians
  const int n = static_cast<int>(std::round(turns * 2.0 * kPi / step));
  auto at = [&](int k) {
    const double a = k * step;
    return Eigen::Vector3d(centre.x() + helixRadius * std::cos(a),
                           centre.y() + helixRadius * std::sin(a),
                           centre.z() - pitch * a / (2.0 * kPi));
  };
  stock.remove(Sweep(c, line(at(0), at(0)), h));
  std::vector<double> v;
  for (int k = 0; k < n; ++k) {
    StepPath p;
    p.kind = StepPath::Kind::ArcXY;
    p.start = at(k);
    p.end = at(k + 1);
    p.center = centre;
    p.sweepRad = step;
    v.push_back(stock.remove(Sweep(c, p, h)).volume);
  }
  return v;
}

/// The volume every steady step of helix() removes for a cutter of radius r with vertical
/// sides (flat, ball, bull) when helixRadius < r: the bore has no island, and by helical
/// symmetry each step takes the bore's area x pitch x its share of a turn,
/// (helixRadius + r)^2 pitch (L / helixRadius) / 2.
inline double helixSteadyStep(double helixRadius, double r, double pitch, double L) {
  return (helixRadius + r) * (helixRadius + r) * pitch * (L / helixRadius) / 2.0;
}

/// Volumes of the steps of a straight pass from `a` over `length` along `dir` in steps of L,
/// after placing the tool at `a` (its own removal not counted).
inline std::vector<double> pass(Stock& stock, const AptCutter& c, const Eigen::Vector3d& a,
                                const Eigen::Vector3d& dir, double length, double L) {
  const double h = stock.resolution();
  stock.remove(Sweep(c, line(a, a), h));
  std::vector<double> v;
  for (double s = 0.0; s + L <= length + 1e-9; s += L)
    v.push_back(stock.remove(Sweep(c, line(a + s * dir, a + (s + L) * dir), h)).volume);
  return v;
}

/// Volume a convex cutter removes from the half-space z < 0 ramping down into it at angle
/// `alpha` below the horizontal, tip on the surface at the start, over a horizontal travel x.
/// New material enters through the tool's front surface only (a convex solid in straight
/// motion), at the rate of v . n per unit area: over the profile (arc length sigma, radius
/// rho, outward normal (n_rho, n_z)) and the angle phi about the axis, measured from the
/// horizontal direction of travel, v . n = n_rho cos(phi) cos(alpha) - n_z sin(alpha), and a
/// profile point at height z(sigma) above the tip is below the surface once the tip has
/// travelled z / sin(alpha). So
///   V = int rho(sigma) Phi(sigma) (s - z(sigma) / sin(alpha))^+ dsigma,  s = x / cos(alpha),
/// Phi = int_0^2pi (n_rho cos(phi) cos(alpha) - n_z sin(alpha))^+ dphi in closed form, and
/// the profile integral by the midpoint rule on 20000 pieces per profile segment (the
/// kink where z(sigma) = s sin(alpha) costs below 1e-7 relative). For a flat end mill it is
/// tan(alpha) (r x^2 + pi r^2 x).
inline double rampVolume(const AptCutter& c, double alpha, double x) {
  const double s = x / std::cos(alpha);
  auto phi = [&](double nRho, double nZ) {
    const double a = nRho * std::cos(alpha), b = -nZ * std::sin(alpha);
    if (b >= a) return 2.0 * kPi * b;
    if (b <= -a) return 0.0;
    const double p0 = std::acos(-b / a);
    return 2.0 * (a * std::sin(p0) + b * p0);
  };
  double v = 0.0;
  for (const ProfileSegment& seg : c.profile()) {
    const int n = 20000;
    double a0 = 0.0, sweep = 0.0, length = (seg.end - seg.start).norm();
    if (seg.kind == ProfileSegment::Kind::Arc) {
      a0 = std::atan2(seg.start.y() - seg.center.y(), seg.start.x() - seg.center.x());
      sweep = std::atan2(seg.end.y() - seg.center.y(), seg.end.x() - seg.center.x()) - a0;
      if (sweep < 0.0) sweep += 2.0 * kPi;  // counter-clockwise from start to end
      length = seg.radius * sweep;
    }
    for (int i = 0; i < n; ++i) {
      const double u = (i + 0.5) / n;
      Eigen::Vector2d at, normal;
      if (seg.kind == ProfileSegment::Kind::Arc) {
        normal = {std::cos(a0 + u * sweep), std::sin(a0 + u * sweep)};
        at = seg.center + seg.radius * normal;
      } else {
        const Eigen::Vector2d d = (seg.end - seg.start) / length;
        at = seg.start + u * (seg.end - seg.start);
        normal = {d.y(), -d.x()};  // the solid is on the left going up the profile
      }
      const double travel = s - at.y() / std::sin(alpha);
      if (travel > 0.0) v += at.x() * phi(normal.x(), normal.y()) * travel * length / n;
    }
  }
  return v;
}

inline double worstRelative(const std::vector<double>& got, double expected, std::size_t skip = 1) {
  double worst = 0.0;
  for (std::size_t i = skip; i < got.size(); ++i)
    worst = std::max(worst, std::abs(got[i] / expected - 1.0));
  return worst;
}

inline double meanRelative(const std::vector<double>& got, double expected, std::size_t skip = 1) {
  double sum = 0.0;
  for (std::size_t i = skip; i < got.size(); ++i)
    sum += got[i];
  return sum / static_cast<double>(got.size() - skip) / expected - 1.0;
}

/// The steps' standard deviation about their own mean, relative to the mean (issue 44's
/// per-step steadiness).
inline double spreadRelative(const std::vector<double>& got, std::size_t skip = 1) {
  double sum = 0.0, squares = 0.0;
  const double n = static_cast<double>(got.size() - skip);
  for (std::size_t i = skip; i < got.size(); ++i)
    sum += got[i];
  const double mean = sum / n;
  for (std::size_t i = skip; i < got.size(); ++i)
    squares += (got[i] - mean) * (got[i] - mean);
  return std::sqrt(squares / n) / mean;
}

}  // namespace engage::test
