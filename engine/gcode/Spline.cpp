#include "engine/gcode/Spline.h"

#include "cutters/Error.h"
#include "cutters/Geometry.h"

#include <algorithm>
#include <cmath>
#include <functional>

namespace engage::gcode {
namespace {

using Curve = std::function<Eigen::Vector2d(double)>;
/// Work limit of one curve: huge coordinates could never meet the tolerance in doubles.
constexpr std::size_t kMaxPieces = 100000;

void subdivide(const Curve& f, double t0, double t1, const Eigen::Vector2d& a,
               const Eigen::Vector2d& b, double tolerance, int depth,
               std::vector<Eigen::Vector2d>& out) {
  const double dt = t1 - t0;
  const Eigen::Vector2d q1 = f(t0 + 0.25 * dt);
  const Eigen::Vector2d q2 = f(t0 + 0.5 * dt);
  const Eigen::Vector2d q3 = f(t0 + 0.75 * dt);
  const double error = std::max(
      {distanceToSegment(q1, a, b), distanceToSegment(q2, a, b), distanceToSegment(q3, a, b)});
  if (error <= tolerance || depth >= 24) {
    out.push_back(b);
    if (out.size() > kMaxPieces)
      throw Error("expected a curve that flattens within " + std::to_string(tolerance) +
                  " mm in at most " + std::to_string(kMaxPieces) + " line pieces, found more");
    return;
  }
  subdivide(f, t0, t0 + 0.5 * dt, a, q2, tolerance, depth + 1, out);
  subdivide(f, t0 + 0.5 * dt, t1, q2, b, tolerance, depth + 1, out);
}

/// Flatten f over [0, 1]. `breaks` are parameters where f may have a corner (NURBS knots):
/// each smooth piece between them is split into 8 spans first, so that an S-shaped span
/// cannot hide behind a straight chord, then bisected to the tolerance.
std::vector<Eigen::Vector2d> flatten(const Curve& f, double tolerance,
                                     std::vector<double> breaks = {}) {
  breaks.push_back(0.0);
  breaks.push_back(1.0);
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
  std::vector<Eigen::Vector2d> out;
  constexpr int kSpans = 8;
  Eigen::Vector2d a = f(0.0);
  for (std::size_t k = 0; k + 1 < breaks.size(); ++k) {
    const double lo = breaks[k];
    const double hi = breaks[k + 1];
    for (int i = 0; i < kSpans; ++i) {
      const double t0 = lo + (hi - lo) * i / kSpans;
      const double t1 = i + 1 == kSpans ? hi : lo + (hi - lo) * (i + 1) / kSpans;
      const Eigen::Vector2d b = f(t1);
      subdivide(f, t0, t1, a, b, tolerance, 0, out);
      a = b;
    }
  }
  return out;
}

}  // namespace

std::vector<Eigen::Vector2d> flattenCubic(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                          const Eigen::Vector2d& p2, const Eigen::Vector2d& p3,
                                          double tolerance) {
  return flatten(
      [&](double t) -> Eigen::Vector2d {
        const double u = 1.0 - t;
        return u * u * u * p0 + 3.0 * u * u * t * p1 + 3.0 * u * t * t * p2 + t * t * t * p3;
      },
      tolerance);
}

std::vector<Eigen::Vector2d> flattenQuadratic(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                              const Eigen::Vector2d& p2, double tolerance) {
  return flatten(
      [&](double t) -> Eigen::Vector2d {
        const double u = 1.0 - t;
        return u * u * p0 + 2.0 * u * t * p1 + t * t * p2;
      },
      tolerance);
}

std::vector<Eigen::Vector2d> flattenNurbs(const std::vector<Eigen::Vector2d>& cp,
                                          const std::vector<double>& w, int order,
                                          double tolerance) {
  const int n = static_cast<int>(cp.size());
  const int k = order;
  // Clamped uniform knots on [0, 1]: k zeros, n - k interior knots, k ones.
  std::vector<double> knots(static_cast<std::size_t>(n + k));
  const int spans = n - k + 1;
  for (int i = 0; i < n + k; ++i) {
    if (i < k)
      knots[static_cast<std::size_t>(i)] = 0.0;
    else if (i >= n)
      knots[static_cast<std::size_t>(i)] = 1.0;
    else
      knots[static_cast<std::size_t>(i)] = static_cast<double>(i - k + 1) / spans;
  }
  auto eval = [&](double t) -> Eigen::Vector2d {
    // De Boor on homogeneous points (w x, w y, w).
    int span = k - 1;
    while (span < n - 1 && t >= knots[static_cast<std::size_t>(span + 1)])
      ++span;
    std::vector<Eigen::Vector3d> d(static_cast<std::size_t>(k));
    for (int j = 0; j < k; ++j) {
      const std::size_t i = static_cast<std::size_t>(span - k + 1 + j);
      d[static_cast<std::size_t>(j)] = Eigen::Vector3d(w[i] * cp[i].x(), w[i] * cp[i].y(), w[i]);
    }
    for (int r = 1; r < k; ++r) {
      for (int j = k - 1; j >= r; --j) {
        const int i = span - k + 1 + j;
        const double left = knots[static_cast<std::size_t>(i)];
        const double right = knots[static_cast<std::size_t>(i + k - r)];
        const double a = right > left ? (t - left) / (right - left) : 0.0;
        d[static_cast<std::size_t>(j)] =
            (1.0 - a) * d[static_cast<std::size_t>(j - 1)] + a * d[static_cast<std::size_t>(j)];
      }
    }
    const Eigen::Vector3d& h = d[static_cast<std::size_t>(k - 1)];
    return Eigen::Vector2d(h.x() / h.z(), h.y() / h.z());
  };
  // Knot values are where a NURBS may have corners (degree 1) or curvature jumps.
  std::vector<Eigen::Vector2d> out = flatten(eval, tolerance, knots);
  out.back() = cp.back();  // clamped: the curve ends exactly on the last control point
  return out;
}

}  // namespace engage::gcode
