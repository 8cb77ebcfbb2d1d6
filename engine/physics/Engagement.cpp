#include "engine/physics/Engagement.h"
#include "cutters/Numbers.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace engage {
namespace {

constexpr int kAngleSamples = 90;  ///< intervals over the front half: 2 degrees
constexpr int kMaxSlices = 64;
constexpr int kRefinements = 8;  ///< halvings of a 2 degree interval: 0.008 degrees
/// Contact is read this many cells outside the surface (the material share there above 1/2),
/// and again twice as far to take the boundary's offset out (see measureEngagement).
constexpr double kOutside = 0.25;
constexpr double kReach = 10.0 * kPi / 180.0;  ///< how far the second boundary is looked for

}  // namespace

// One function: it runs for every cutting step with --material, and its slices, angular
// samples and boundary refinements share one sampling of the stock.
EdgeEngagement measureEngagement(const Stock& stock, const AptCutter& cutter,
                                 const Eigen::Vector3d& tip, const Eigen::Vector2d& feedDir,
                                 bool clockwise, double zTop) {
  EdgeEngagement out;
  out.entry = out.exit = std::numeric_limits<double>::quiet_NaN();
  const double h = stock.resolution();
  zTop = std::min(zTop, cutter.height());
  if (!(zTop > 0.0) || !(feedDir.norm() > 0.0)) return out;
  const Eigen::Vector2d u = feedDir.normalized();
  const Eigen::Vector2d left(-u.y(), u.x());
  const Eigen::Vector2d v = clockwise ? left : Eigen::Vector2d(-left);
  out.feed = u;
  out.side = v;
  const int n = std::clamp(static_cast<int>(std::ceil(zTop / (0.5 * h))), 1, kMaxSlices);
  const double dz = zTop / n;
  const double eps = kOutside * h;

  std::vector<EdgeSlice> slices;
  for (int k = 0; k < n; ++k) {
    EdgeSlice s;
    s.z = (k + 0.5) * dz;
    s.dz = dz;
    s.radius = cutter.radiusAt(s.z);
    if (!(s.radius > 1e-9)) continue;
    const double d = 1e-4;  // the profile is analytic: a central difference to 1e-8
    const double slope = (cutter.radiusAt(s.z + d) - cutter.radiusAt(std::max(0.0, s.z - d))) /
                         (s.z + d - std::max(0.0, s.z - d));
    s.kappa = std::atan2(1.0, slope);
    slices.push_back(s);
  }
  // The point `out` outside the surface at slice s, angle phi.
  auto point = [&](const EdgeSlice& s, double phi, double offset) {
    const Eigen::Vector2d e = std::sin(phi) * u + std::cos(phi) * v;
    const double reach = s.radius + offset * std::sin(s.kappa);
    return Eigen::Vector3d(tip.x() + reach * e.x(), tip.y() + reach * e.y(),
                           tip.z() + s.z - offset * std::cos(s.kappa));
  };
  std::vector<Eigen::Vector3d> points;
  points.reserve(slices.size() * (kAngleSamples + 1));
  for (const EdgeSlice& s : slices)
    for (int i = 0; i <= kAngleSamples; ++i)
      points.push_back(point(s, kPi * i / kAngleSamples, eps));
  const std::vector<double> share = stock.materialAt(points);

  // Boundaries between samples, refined by halving: (slice, low angle, high angle, low side
  // in contact).
  struct Edge {
    std::size_t slice;
    double lo, hi;
    bool loIn;
  };
  std::vector<Edge> edges;
  for (std::size_t k = 0; k < slices.size(); ++k)
    for (int i = 0; i < kAngleSamples; ++i) {
      const bool a = share[k * (kAngleSamples + 1) + i] > 0.5;
      const bool b = share[k * (kAngleSamples + 1) + i + 1] > 0.5;
      if (a != b) edges.push_back({k, kPi * i / kAngleSamples, kPi * (i + 1) / kAngleSamples, a});
    }
  auto refine = [&](std::vector<Edge>& list, double offset, int rounds) {
    for (int round = 0; round < rounds && !list.empty(); ++round) {
      points.clear();
      for (const Edge& e : list)
        points.push_back(point(slices[e.slice], 0.5 * (e.lo + e.hi), offset));
      const std::vector<double> mid = stock.materialAt(points);
      for (std::size_t i = 0; i < list.size(); ++i) {
        Edge& e = list[i];
        ((mid[i] > 0.5) == e.loIn ? e.lo : e.hi) = 0.5 * (e.lo + e.hi);
      }
    }
  };
  refine(edges, eps, kRefinements);
  // The boundary read at eps outside lies where the gap between cutter and material reaches
  // eps, beyond the contact's true end (gap 0) by eps / (d gap / d phi). Read at 2 eps, the
  // boundary lies about as far again: the true one is 2 phi(eps) - phi(2 eps). The second is
  // looked for up to 10 degrees on the air side; where it is not there (a wall met at a steep
  // angle, where both coincide, or a grazing contact) the first stays.
  std::vector<double> boundary(edges.size());
  std::vector<Edge> far;  // far[i]: where edges[i] is looked for again, 2 eps out
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const Edge& e = edges[i];
    const double at = boundary[i] = 0.5 * (e.lo + e.hi);
    // In contact on the low side: the air lies at higher angles.
    if (e.loIn)
      far.push_back({e.slice, at, std::min(kPi, at + kReach), true});
    else
      far.push_back({e.slice, std::max(0.0, at - kReach), at, false});
  }
  // Keep only those whose bracket holds the change (contact at the near end, air at the far).
  points.clear();
  for (const Edge& f : far) {
    points.push_back(point(slices[f.slice], f.lo, 2.0 * eps));
    points.push_back(point(slices[f.slice], f.hi, 2.0 * eps));
  }
  const std::vector<double> ends = stock.materialAt(points);
  std::vector<Edge> bracketed;
  std::vector<std::size_t> bracketOf;  // the index in edges
  for (std::size_t i = 0; i < far.size(); ++i)
    if ((ends[2 * i] > 0.5) == far[i].loIn && (ends[2 * i + 1] > 0.5) != far[i].loIn) {
      bracketed.push_back(far[i]);
      bracketOf.push_back(i);
    }
  refine(bracketed, 2.0 * eps, kRefinements + 2);
  for (std::size_t i = 0; i < bracketed.size(); ++i) {
    const double near = boundary[bracketOf[i]];
    const double second = 0.5 * (bracketed[i].lo + bracketed[i].hi);
    boundary[bracketOf[i]] = std::clamp(2.0 * near - second, 0.0, kPi);
  }
  // Arcs: runs of samples in contact, their ends at the refined boundaries.
  std::size_t next = 0;  // edges are in slice, angle order
  for (std::size_t k = 0; k < slices.size(); ++k) {
    EdgeSlice& s = slices[k];
    double start = -1.0;
    for (int i = 0; i <= kAngleSamples; ++i) {
      const bool in = share[k * (kAngleSamples + 1) + i] > 0.5;
      if (i == 0 && in) start = 0.0;
      if (i > 0) {
        const bool was = share[k * (kAngleSamples + 1) + i - 1] > 0.5;
        if (was != in) {
          const double at = boundary[next++];
          if (in)
            start = at;
          else
            s.arcs.push_back({start, at});
        }
      }
      if (i == kAngleSamples && in) s.arcs.push_back({start, kPi});
    }
    if (s.arcs.empty()) continue;
    out.entry = std::isnan(out.entry) ? s.arcs.front()[0] : std::min(out.entry, s.arcs.front()[0]);
    out.exit = std::isnan(out.exit) ? s.arcs.back()[1] : std::max(out.exit, s.arcs.back()[1]);
    out.slices.push_back(std::move(s));
  }
  return out;
}

}  // namespace engage
