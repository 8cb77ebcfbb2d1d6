#include "engine/run/ProbeContact.h"

#include <algorithm>
#include <cmath>

namespace engage {
namespace {

/// Distance in XY from p to the box's outline (0 inside it).
double outlineDistance(const Box3& box, const Eigen::Vector3d& p) {
  const double dx = std::max({box.min.x() - p.x(), 0.0, p.x() - box.max.x()});
  const double dy = std::max({box.min.y() - p.y(), 0.0, p.y() - box.max.y()});
  return std::hypot(dx, dy);
}

}  // namespace

double probeContact(const Box3& box, double radius, const Eigen::Vector3d& from,
                    const Eigen::Vector3d& to) {
  constexpr double kNone = 2.0;
  // Below the top: t from zIn on (the tip descending) or up to zOut (rising).
  double zIn = 0.0, zOut = 1.0;
  const double dz = to.z() - from.z();
  if (dz == 0.0) {
    if (from.z() > box.max.z()) return kNone;
  } else {
    const double t = (box.max.z() - from.z()) / dz;
    if (dz < 0.0)
      zIn = std::max(0.0, t);
    else
      zOut = std::min(1.0, t);
  }
  if (zIn > zOut) return kNone;
  // Within a radius of the outline: the distance is convex along the move; its least value
  // by golden-section search, then where it first comes within the radius by bisection.
  auto at = [&](double t) { return outlineDistance(box, from + t * (to - from)); };
  double lo = zIn, hi = zOut;
  if (at(lo) <= radius) return lo;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
  for (int i = 0; i < 200 && hi - lo > 1e-13; ++i) {
    if (at(a) < at(b)) {
      hi = b;
      b = a;
      a = hi - g * (hi - lo);
    } else {
      lo = a;
      a = b;
      b = lo + g * (hi - lo);
    }
  }
  const double nearest = (lo + hi) / 2.0;
  if (at(nearest) > radius) return kNone;
  double outside = zIn, inside = nearest;
  for (int i = 0; i < 200 && inside - outside > 1e-13; ++i) {
    const double mid = (outside + inside) / 2.0;
    (at(mid) <= radius ? inside : outside) = mid;
  }
  return inside;
}

}  // namespace engage
