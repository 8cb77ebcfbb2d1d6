#include "engine/cam/Pocket.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/gcode/GcodeError.h"

#include <polyclipping/clipper.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <sstream>

namespace engage {
namespace {

namespace cl = ClipperLib;

/// Clipper works on integers: 1e4 units per mm (0.1 um), far below any tolerance here and
/// far inside Clipper's fast 62-bit range for parts up to kilometres.
constexpr double kScale = 1e4;

cl::IntPoint toInt(const Eigen::Vector2d& p) {
  return {static_cast<cl::cInt>(std::llround(p.x() * kScale)),
          static_cast<cl::cInt>(std::llround(p.y() * kScale))};
}
Eigen::Vector2d toMm(const cl::IntPoint& p) {
  return {static_cast<double>(p.X) / kScale, static_cast<double>(p.Y) / kScale};
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

std::string where(const Toolpath& path, const Move& m) {
  return path.files.at(static_cast<std::size_t>(m.file)) + ":" + std::to_string(m.line);
}

/// The raw inward offset of one oriented loop (the region on its left): every edge moved
/// left by `delta`, joined at their intersection where neighbouring edges overlap (a left
/// turn up to 90 degrees; sharper ones straight across) and by an arc of radius `delta`
/// about the vertex where they open (a right turn). The offset region
/// is where the raw loops' winding number is positive (Chen & McMains, "Polygon offsetting
/// by computing winding numbers", 2005). Clipper's own ClipperOffset joins overlapping edges
/// through the source vertex, a spike `delta` long at every vertex of a finely flattened
/// curve; their crossings make its cost grow with the square of the vertex count.
cl::Path rawOffset(const cl::Path& loop, double delta, double tolerance) {
  const std::size_t n = loop.size();
  std::vector<Eigen::Vector2d> p(n);
  for (std::size_t i = 0; i < n; ++i)
    p[i] = {static_cast<double>(loop[i].X), static_cast<double>(loop[i].Y)};
  const double d = delta * kScale, tol = std::max(1.0, tolerance * kScale);
  auto leftNormal = [&](std::size_t i) {  // of the edge from vertex i to vertex i + 1
    const Eigen::Vector2d e = p[(i + 1) % n] - p[i];
    const double len = e.norm();
    return len > 0 ? Eigen::Vector2d(-e.y() / len, e.x() / len) : Eigen::Vector2d(0, 0);
  };
  cl::Path out;
  auto push = [&](const Eigen::Vector2d& q) {
    out.push_back(
        {static_cast<cl::cInt>(std::llround(q.x())), static_cast<cl::cInt>(std::llround(q.y()))});
  };
  const double maxStep = 2.0 * std::acos(std::max(-1.0, 1.0 - tol / d));
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t prev = (i + n - 1) % n;
    const Eigen::Vector2d n0 = leftNormal(prev), n1 = leftNormal(i);
    const Eigen::Vector2d a = p[i] + d * n0, b = p[i] + d * n1;
    const double turn = std::atan2(cross(n0, n1), n0.dot(n1));  // + left turn
    if (turn >= 0.0 && turn <= kPi / 2) {
      // The offset edges overlap: meet at their intersection (the miter point).
      push(p[i] + d * (n0 + n1) / (1.0 + n0.dot(n1)));
      continue;
    }
    push(a);
    if (turn < 0.0) {
      // The offset edges open: round the gap about the vertex, clockwise.
      const int pieces = static_cast<int>(std::ceil(-turn / maxStep));
      const double a0 = std::atan2(n0.y(), n0.x());
      for (int k = 1; k < pieces; ++k) {
        const double t = a0 + turn * k / pieces;
        push(p[i] + d * Eigen::Vector2d(std::cos(t), std::sin(t)));
      }
    }
    push(b);
  }
  return out;
}

/// Offset the (oriented: outer loops counter-clockwise, islands clockwise) boundary inward
/// by `delta` mm.
void offsetInward(const cl::Paths& base, double delta, double tolerance, cl::PolyTree& out) {
  cl::Paths raw;
  for (const cl::Path& loop : base)
    raw.push_back(rawOffset(loop, delta, 0.5 * tolerance));
  cl::Clipper c;
  c.AddPaths(raw, cl::ptSubject, true);
  c.Execute(cl::ctUnion, out, cl::pftPositive, cl::pftPositive);
}

/// A region of one offset: an outer ring and the rings around islands inside it.
struct Region {
  cl::Path outer;
  cl::Paths holes;
  double offset = 0.0;
  std::vector<std::size_t> children;  ///< regions of the next offset inside this one
};

bool tooSmall(const cl::Path& p, double tolerance) {
  const double minArea = tolerance * tolerance * kScale * kScale;
  return p.size() < 3 || std::abs(cl::Area(p)) < minArea;
}

/// Distance from a point to the boundary's edges, in Clipper units.
double distanceToBoundary(const cl::IntPoint& q, const cl::Paths& base) {
  const Eigen::Vector2d p(static_cast<double>(q.X), static_cast<double>(q.Y));
  double best = std::numeric_limits<double>::infinity();
  for (const cl::Path& loop : base)
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const cl::IntPoint& a = loop[i];
      const cl::IntPoint& b = loop[(i + 1) % loop.size()];
      const Eigen::Vector2d u(static_cast<double>(a.X), static_cast<double>(a.Y));
      const Eigen::Vector2d d =
          Eigen::Vector2d(static_cast<double>(b.X), static_cast<double>(b.Y)) - u;
      const double l2 = d.squaredNorm();
      const double t = l2 > 0 ? std::clamp((p - u).dot(d) / l2, 0.0, 1.0) : 0.0;
      best = std::min(best, (u + t * d - p).norm());
    }
  return best;
}

/// A region of the raw offset's positive winding is a real offset region only if its
/// corners are `delta` from the boundary; where a convex stretch tighter than `delta`
/// collapses, the raw offset turns inside out into a spurious loop whose points are nearer.
bool spurious(const cl::Path& p, const cl::Paths& base, double delta, double tolerance) {
  const std::size_t samples = std::min<std::size_t>(p.size(), 8);
  for (std::size_t k = 0; k < samples; ++k)
    if (distanceToBoundary(p[k * p.size() / samples], base) < (delta - tolerance) * kScale)
      return true;
  return false;
}

void collectRegions(const cl::PolyNode& node, const cl::Paths& base, double offset,
                    double tolerance, std::vector<Region>& out) {
  for (const cl::PolyNode* child : node.Childs) {
    if (child->IsHole()) continue;
    if (!tooSmall(child->Contour, tolerance) &&
        !spurious(child->Contour, base, offset, tolerance)) {
      Region r;
      r.outer = child->Contour;
      r.offset = offset;
      for (const cl::PolyNode* hole : child->Childs)
        if (!tooSmall(hole->Contour, tolerance)) r.holes.push_back(hole->Contour);
      out.push_back(std::move(r));
    }
    for (const cl::PolyNode* hole : child->Childs)
      collectRegions(*hole, base, offset, tolerance, out);
  }
}

std::vector<Region> regionsAt(const cl::Paths& base, double delta, double tolerance) {
  cl::PolyTree tree;
  offsetInward(base, delta, tolerance, tree);
  std::vector<Region> out;
  collectRegions(tree, base, delta, tolerance, out);
  return out;
}

/// Inside a region: inside its outer ring and not inside an island's ring.
bool insideRegion(const cl::IntPoint& p, const Region& r) {
  if (cl::PointInPolygon(p, r.outer) == 0) return false;
  for (const cl::Path& h : r.holes)
    if (cl::PointInPolygon(p, h) == 1) return false;
  return true;
}

// --- arc fitting ------------------------------------------------------------------------

/// The circle through three points; false when they are (nearly) collinear.
bool circumcircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                  Eigen::Vector2d& center) {
  const Eigen::Vector2d ab = b - a, ac = c - a;
  const double d = 2.0 * cross(ab, ac);
  if (std::abs(d) < 1e-12 * ab.squaredNorm() * ac.norm() + 1e-300) return false;
  const double ab2 = ab.squaredNorm(), ac2 = ac.squaredNorm();
  center = a + Eigen::Vector2d(ac.y() * ab2 - ab.y() * ac2, ab.x() * ac2 - ac.x() * ab2) / d;
  return true;
}

/// Do points q[i..j] lie on one arc within `tol`, turning one way, sweeping at most about a
/// half turn? Fills the element when they do.
bool fitArc(const std::vector<Eigen::Vector2d>& q, std::size_t i, std::size_t j, double tol,
            Element& e) {
  if (j < i + 3) return false;
  Eigen::Vector2d c;
  if (!circumcircle(q[i], q[(i + j) / 2], q[j], c)) return false;
  const double r = (q[i] - c).norm();
  if (r > 1e4 || r < tol) return false;
  double sweep = 0.0;
  int turn = 0;
  for (std::size_t k = i; k <= j; ++k) {
    if (std::abs((q[k] - c).norm() - r) > tol) return false;
    if (k < j) {
      const double a = std::atan2(cross(q[k] - c, q[k + 1] - c), (q[k] - c).dot(q[k + 1] - c));
      // Clipper's 0.1 um grid puts tiny jogs into offsets: chords shorter than the
      // tolerance do not vote on the direction.
      if ((q[k + 1] - q[k]).norm() > tol) {
        const int s = a > 0 ? 1 : -1;
        if (turn != 0 && s != turn) return false;
        turn = s;
      }
      sweep += a;
      // A chord may not cut more than 45 degrees: a polygon corner is not an arc.
      if (std::abs(a) > kPi / 4) return false;
    }
  }
  // At most a half turn (plus a little): a full circle becomes two arcs, not one arc and a
  // short chord.
  if (turn == 0 || std::abs(sweep) > kPi + 0.1) return false;
  e.arc = true;
  e.start = q[i];
  e.end = q[j];
  e.center = c;
  e.ccw = turn > 0;
  return true;
}

bool fitLine(const std::vector<Eigen::Vector2d>& q, std::size_t i, std::size_t j, double tol) {
  const Eigen::Vector2d d = q[j] - q[i];
  const double len = d.norm();
  if (len <= 0.0) return false;
  for (std::size_t k = i + 1; k < j; ++k) {
    if (std::abs(cross(d, q[k] - q[i])) / len > tol) return false;
    const double t = d.dot(q[k] - q[i]) / (len * len);
    if (t < 0.0 || t > 1.0) return false;
  }
  return true;
}

/// A closed polygon as lines and arcs: greedy, each element as long as it can be.
std::vector<Element> fitElements(std::vector<Eigen::Vector2d> p, double tol) {
  const std::size_t n = p.size();
  // Start at the sharpest corner, so that no arc is cut in two at the start.
  std::size_t best = 0;
  double sharpest = -1.0;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d a = p[k] - p[(k + n - 1) % n], b = p[(k + 1) % n] - p[k];
    const double turn = std::abs(std::atan2(cross(a, b), a.dot(b)));
    if (turn > sharpest + 1e-9) {
      sharpest = turn;
      best = k;
    }
  }
  std::rotate(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(best), p.end());
  p.push_back(p.front());
  std::vector<Element> out;
  std::size_t i = 0;
  while (i < n) {
    std::size_t lineEnd = i + 1;
    while (lineEnd + 1 <= n && fitLine(p, i, lineEnd + 1, tol))
      ++lineEnd;
    Element arc, e;
    std::size_t arcEnd = 0;
    for (std::size_t j = i + 3; j <= n && fitArc(p, i, j, tol, e); ++j) {
      arc = e;
      arcEnd = j;
    }
    if (arcEnd > lineEnd) {
      out.push_back(arc);
      i = arcEnd;
    } else {
      Element l;
      l.start = p[i];
      l.end = p[lineEnd];
      out.push_back(l);
      i = lineEnd;
    }
  }
  return out;
}

// --- exact offsets of the boundary's elements ---------------------------------------------

/// Signed sweep of an arc element, radians, in (-2pi, 2pi).
double sweepOf(const Element& e) {
  const Eigen::Vector2d a = e.start - e.center, b = e.end - e.center;
  double s = std::atan2(cross(a, b), a.dot(b));
  if (e.ccw && s <= 0.0) s += 2.0 * kPi;
  if (!e.ccw && s >= 0.0) s -= 2.0 * kPi;
  return s;
}

/// The nearest point of an element to p: its distance, and whether it is an end
/// (-1 interior, 0 start, 1 end).
std::pair<double, int> nearestOn(const Element& e, const Eigen::Vector2d& p) {
  if (!e.arc) {
    const Eigen::Vector2d d = e.end - e.start;
    const double t = (p - e.start).dot(d) / d.squaredNorm();
    if (t <= 0.0) return {(p - e.start).norm(), 0};
    if (t >= 1.0) return {(p - e.end).norm(), 1};
    return {std::abs(cross(d, p - e.start)) / d.norm(), -1};
  }
  const Eigen::Vector2d a = e.start - e.center, q = p - e.center;
  double t = std::atan2(cross(a, q), a.dot(q));  // angle from the start, signed
  const double sweep = sweepOf(e);
  if (sweep < 0) t = -t;
  if (t < 0) t += 2.0 * kPi;
  if (t <= std::abs(sweep)) return {std::abs(q.norm() - a.norm()), -1};
  const double ds = (p - e.start).norm(), de = (p - e.end).norm();
  return ds < de ? std::make_pair(ds, 0) : std::make_pair(de, 1);
}

/// Where a ring point comes from: an element of a boundary loop, or a corner of it (the
/// start of element `index`), whose offset by the ring's distance the point lies on.
struct Source {
  int loop = -1, index = -1;
  bool corner = false;
  bool operator==(const Source& o) const {
    return loop == o.loop && index == o.index && corner == o.corner;
  }
  bool operator!=(const Source& o) const { return !(*this == o); }
};

/// An offset curve: a line (point, unit direction) or a circle (centre, radius).
struct Curve {
  bool circle = false;
  Eigen::Vector2d p{0.0, 0.0}, dir{1.0, 0.0};
  double radius = 0.0;
};

/// The crossing of two offset curves nearest to `near`; `near` itself when they do not
/// meet (tangent curves, within rounding).
Eigen::Vector2d meet(const Curve& a, const Curve& b, const Eigen::Vector2d& near) {
  auto nearest = [&](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return (u - near).squaredNorm() < (v - near).squaredNorm() ? u : v;
  };
  if (!a.circle && !b.circle) {
    const double den = cross(a.dir, b.dir);
    if (std::abs(den) < 1e-12) return near;
    return a.p + a.dir * (cross(b.p - a.p, b.dir) / den);
  }
  if (a.circle != b.circle) {
    const Curve& l = a.circle ? b : a;
    const Curve& c = a.circle ? a : b;
    const Eigen::Vector2d f = l.p - c.p;
    const double bb = f.dot(l.dir), cc = f.squaredNorm() - c.radius * c.radius;
    const double disc = bb * bb - cc;
    if (disc < 0.0) return l.p + l.dir * (-bb);  // tangent: the foot of the centre
    const double r = std::sqrt(disc);
    return nearest(l.p + l.dir * (-bb + r), l.p + l.dir * (-bb - r));
  }
  const Eigen::Vector2d d = b.p - a.p;
  const double dist = d.norm();
  if (dist < 1e-9) return a.p + (near - a.p).normalized() * a.radius;  // one circle
  const double x = (dist * dist + a.radius * a.radius - b.radius * b.radius) / (2.0 * dist);
  const double h2 = a.radius * a.radius - x * x;
  const Eigen::Vector2d mid = a.p + d * (x / dist);
  if (h2 <= 0.0) return mid;  // tangent
  const Eigen::Vector2d perp(-d.y() / dist, d.x() / dist);
  return nearest(mid + perp * std::sqrt(h2), mid - perp * std::sqrt(h2));
}

/// The source of each edge of the polygon `q` (from its midpoint: a vertex may sit on a
/// joint): the boundary element or corner it is the offset of. False where an edge does not
/// lie `delta` from the boundary.
bool edgeSources(const std::vector<Eigen::Vector2d>& q, const std::vector<Loop>& boundary,
                 double delta, double tol, std::vector<Source>& src) {
  const std::size_t n = q.size();
  src.assign(n, Source{});
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d mid = 0.5 * (q[i] + q[(i + 1) % n]);
    double best = std::numeric_limits<double>::infinity(), bestScore = best;
    for (std::size_t l = 0; l < boundary.size(); ++l)
      for (std::size_t k = 0; k < boundary[l].size(); ++k) {
        const auto [d, end] = nearestOn(boundary[l][k], mid);
        // On a tie an element beats a corner (a corner is the end of two elements).
        const double score = d + (end >= 0 ? 1e-6 : 0.0);
        if (score < bestScore) {
          bestScore = score;
          best = d;
          const std::size_t m = boundary[l].size();
          src[i] = {static_cast<int>(l), static_cast<int>(end == 1 ? (k + 1) % m : k), end >= 0};
        }
      }
    if (std::abs(best - delta) > 5.0 * tol) return false;
  }
  return true;
}

/// Appends to `out` the element of curve c from a to b through the points `via` (a line, or
/// an arc turning the way the points do, split in two where it sweeps more than half a turn);
/// nothing for a line of no length.
void appendCurve(std::vector<Element>& out, const Curve& c, const Eigen::Vector2d& a,
                 const Eigen::Vector2d& b, const std::vector<Eigen::Vector2d>& via) {
  if ((b - a).norm() < 1e-6 && !(c.circle && via.size() > 2)) return;
  Element el;
  el.start = a;
  el.end = b;
  if (!c.circle) {
    out.push_back(el);
    return;
  }
  el.arc = true;
  el.center = c.p;
  // The turn direction and sweep from the points the run passes through.
  double sweep = 0.0;
  Eigen::Vector2d prev = a;
  auto step = [&](const Eigen::Vector2d& x) {
    sweep += std::atan2(cross(prev - c.p, x - c.p), (prev - c.p).dot(x - c.p));
    prev = x;
  };
  for (const Eigen::Vector2d& x : via)
    step(x);
  step(b);
  el.ccw = sweep > 0.0;
  if (std::abs(sweep) <= kPi + 1e-9) {
    out.push_back(el);
    return;
  }
  // More than half a turn: two arcs, split halfway.
  const Eigen::Vector2d u = a - c.p;
  const double h = 0.5 * sweep;
  const Eigen::Vector2d mid = c.p + Eigen::Vector2d(u.x() * std::cos(h) - u.y() * std::sin(h),
                                                    u.x() * std::sin(h) + u.y() * std::cos(h));
  Element e1 = el, e2 = el;
  e1.end = mid;
  e2.start = mid;
  out.push_back(e1);
  out.push_back(e2);
}

/// The ring through points `q` (in cutting order) as the exact offsets of the boundary's
/// elements: each point is put on the element or corner it is the offset of, runs of
/// points with one source become one line or arc, and neighbouring runs meet where their
/// curves cross. Empty when the points do not lie `delta` from the boundary (then the
/// caller fits arcs to the points instead).
std::vector<Element> exactElements(const std::vector<Eigen::Vector2d>& q,
                                   const std::vector<Loop>& boundary, double delta, double tol) {
  const std::size_t n = q.size();
  std::vector<Source> src;
  if (!edgeSources(q, boundary, delta, tol, src)) return {};
  // A lone edge between two of one source is that source.
  for (std::size_t i = 0; i < n; ++i) {
    const Source& before = src[(i + n - 1) % n];
    if (src[i] != before && before == src[(i + 1) % n]) src[i] = before;
  }
  // Runs of edges of one source, starting at a change of source; a run's points are the
  // vertices of its edges.
  std::size_t first = 0;
  while (first < n && src[first] == src[(first + n - 1) % n])
    ++first;
  struct Run {
    Source source;
    std::vector<Eigen::Vector2d> points;
    Curve curve;
  };
  std::vector<Run> runs;
  if (first == n) {
    runs.push_back({src[0], q, {}});
  } else {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = (first + k) % n;
      if (runs.empty() || src[i] != runs.back().source) runs.push_back({src[i], {q[i]}, {}});
      runs.back().points.push_back(q[(i + 1) % n]);
    }
  }
  for (Run& r : runs) {
    const Loop& loop = boundary[static_cast<std::size_t>(r.source.loop)];
    const Element& e = loop[static_cast<std::size_t>(r.source.index)];
    if (r.source.corner) {
      r.curve = {true, e.start, {1.0, 0.0}, delta};
    } else if (!e.arc) {
      Eigen::Vector2d dir = (e.end - e.start).normalized();
      Eigen::Vector2d normal(-dir.y(), dir.x());
      if (normal.dot(r.points.front() - e.start) < 0.0) normal = -normal;
      r.curve = {false, e.start + delta * normal, dir, 0.0};
    } else {
      const double R = (e.start - e.center).norm();
      const double seen = (r.points.front() - e.center).norm();
      r.curve = {
          true,
          e.center,
          {1.0, 0.0},
          std::abs(seen - (R + delta)) < std::abs(seen - (R - delta)) ? R + delta : R - delta};
    }
  }
  // Neighbouring runs on one curve (a circle split into halves, collinear lines) are one.
  auto same = [](const Curve& a, const Curve& b) {
    if (a.circle != b.circle) return false;
    if (a.circle) return (a.p - b.p).norm() < 1e-7 && std::abs(a.radius - b.radius) < 1e-7;
    return std::abs(cross(a.dir, b.dir)) < 1e-9 && std::abs(cross(a.dir, b.p - a.p)) < 1e-7;
  };
  for (std::size_t k = 1; k < runs.size();) {
    if (same(runs[k - 1].curve, runs[k].curve)) {
      runs[k - 1].points.insert(runs[k - 1].points.end(), runs[k].points.begin() + 1,
                                runs[k].points.end());
      runs.erase(runs.begin() + static_cast<std::ptrdiff_t>(k));
    } else {
      ++k;
    }
  }
  if (runs.size() > 1 && same(runs.back().curve, runs.front().curve)) {
    runs.back().points.insert(runs.back().points.end(), runs.front().points.begin() + 1,
                              runs.front().points.end());
    runs.front() = std::move(runs.back());
    runs.pop_back();
  }
  // The joints, then the elements between them.
  std::vector<Element> out;
  auto emit = [&](const Curve& c, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                  const std::vector<Eigen::Vector2d>& via) { appendCurve(out, c, a, b, via); };
  if (runs.size() == 1) {
    const Curve& c = runs[0].curve;
    const Eigen::Vector2d a =
        c.circle ? meet(c, c, runs[0].points.front()) : runs[0].points.front();
    emit(c, a, a, runs[0].points);
    return out;
  }
  std::vector<Eigen::Vector2d> joint(runs.size());  // joint[k]: where run k starts
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Run& before = runs[(k + runs.size() - 1) % runs.size()];
    const Eigen::Vector2d near = runs[k].points.front();  // the vertex between the runs
    joint[k] = meet(before.curve, runs[k].curve, near);
    // The joint lies within the polygon edges on either side of the vertex (farther along
    // them where the curves are tangent); a crossing beyond is the wrong one.
    const double reach = std::max((near - before.points[before.points.size() - 2]).norm(),
                                  (runs[k].points[1] - near).norm());
    if ((joint[k] - near).norm() > 2.0 * reach + 10.0 * tol) joint[k] = near;
  }
  for (std::size_t k = 0; k < runs.size(); ++k)
    emit(runs[k].curve, joint[k], joint[(k + 1) % runs.size()], runs[k].points);
  return out;
}

/// The ring of one Clipper path, in the cutting direction. With an M3 (clockwise from above)
/// spindle the tooth on the tool's right moves backwards, with the part's motion relative to
/// the tool: climb milling keeps the material on the right (G41 side). Clipper's outer rings
/// run counter-clockwise (the wall outside, on the right) and its island rings clockwise (the
/// island inside, on the right): climb keeps them, conventional reverses them.
Ring makeRing(const cl::Path& path, double offset, bool island, const std::vector<Loop>& boundary,
              const PocketOptions& o) {
  // Drop Clipper's grid jogs: vertices nearer than a quarter of the tolerance.
  cl::Path clean;
  cl::CleanPolygon(path, clean, 0.25 * o.tolerance * kScale);
  if (clean.size() < 3) clean = path;
  std::vector<Eigen::Vector2d> pts;
  pts.reserve(clean.size());
  for (const cl::IntPoint& q : clean)
    pts.push_back(toMm(q));
  if (!o.climb) std::reverse(pts.begin(), pts.end());
  Ring r;
  r.elements = exactElements(pts, boundary, offset, o.tolerance);
  if (r.elements.empty()) r.elements = fitElements(pts, o.tolerance);
  r.offset = offset;
  r.island = island;
  return r;
}

/// Start the ring at the element start nearest to `from`.
void startNearest(Ring& r, const Eigen::Vector2d& from) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < r.elements.size(); ++k)
    if ((r.elements[k].start - from).squaredNorm() < (r.elements[best].start - from).squaredNorm())
      best = k;
  std::rotate(r.elements.begin(), r.elements.begin() + static_cast<std::ptrdiff_t>(best),
              r.elements.end());
}

/// A loop as a polygon: arcs flattened within `chordTolerance` mm.
std::vector<Eigen::Vector2d> flatten(const Loop& loop, double chordTolerance) {
  std::vector<Eigen::Vector2d> out;
  for (const Element& e : loop) {
    out.push_back(e.start);
    if (!e.arc) continue;
    const double r = (e.start - e.center).norm(), sweep = sweepOf(e);
    const double maxStep = 2.0 * std::acos(std::max(-1.0, 1.0 - chordTolerance / r));
    const int pieces = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / maxStep)));
    const Eigen::Vector2d u = e.start - e.center;
    for (int k = 1; k < pieces; ++k) {
      const double t = sweep * k / pieces;
      out.push_back(e.center + Eigen::Vector2d(u.x() * std::cos(t) - u.y() * std::sin(t),
                                               u.x() * std::sin(t) + u.y() * std::cos(t)));
    }
  }
  return out;
}

void positive(double v, const char* name) {
  if (!(v > 0.0 && std::isfinite(v)))
    throw ParameterError(std::string(name) + " must be positive, found " + std::to_string(v));
}

}  // namespace

Loop polygonLoop(const std::vector<Eigen::Vector2d>& corners) {
  Loop l;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    Element e;
    e.start = corners[i];
    e.end = corners[(i + 1) % corners.size()];
    if ((e.end - e.start).norm() > 0.0) l.push_back(e);
  }
  return l;
}

std::vector<Loop> boundaryLoops(const Toolpath& boundary) {
  std::vector<Loop> loops;
  Loop current;
  const Move* first = nullptr;
  const Move* last = nullptr;
  auto close = [&]() {
    if (current.empty()) return;
    const Eigen::Vector2d s = current.front().start, e = current.back().end;
    if ((e - s).norm() > 1e-4)
      throw Error(where(boundary, *last) + ": boundary loop starting at line " +
                  std::to_string(first->line) + " does not close: it ends at (" +
                  std::to_string(e.x()) + ", " + std::to_string(e.y()) + ") mm, it starts at (" +
                  std::to_string(s.x()) + ", " + std::to_string(s.y()) + ") mm");
    current.back().end = s;
    double turn = 0.0;
    for (const Element& el : current)
      turn += el.arc ? std::abs(sweepOf(el)) : 0.0;
    if (current.size() < 3 && turn < kPi)
      throw Error(where(boundary, *first) + ": boundary loop encloses no area");
    loops.push_back(current);
    current.clear();
  };
  auto add = [&](Element e) {
    if ((e.end - e.start).norm() > 1e-9 || e.arc) current.push_back(e);
  };
  for (const Move& m : boundary.moves) {
    if (m.kind == MoveKind::Rapid) {
      close();
      continue;
    }
    if (current.empty()) first = &m;
    last = &m;
    Element e;
    e.start = m.start.head<2>();
    e.end = m.end.head<2>();
    if (m.kind == MoveKind::Arc) {
      if (m.plane != Plane::XY)
        throw Error(where(boundary, m) + ": boundary arcs must be in the XY plane (G17)");
      // Pieces of at most half a turn (a full circle is two).
      const double sweep = arcSweep(m);
      const int pieces = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / kPi - 1e-9)));
      e.arc = true;
      e.center = m.center.head<2>();
      e.ccw = sweep > 0.0;
      for (int k = 1; k <= pieces; ++k) {
        e.end = pointAt(m, static_cast<double>(k) / pieces).head<2>();
        add(e);
        e.start = e.end;
      }
    } else if (m.kind == MoveKind::Spline) {
      for (const Eigen::Vector3d& q : m.points) {
        e.end = q.head<2>();
        add(e);
        e.start = e.end;
      }
    } else {
      add(e);
    }
  }
  close();
  if (loops.empty())
    throw Error((boundary.files.empty() ? std::string("boundary") : boundary.files.front()) +
                ": no closed boundary loop (expected G1/G2/G3 moves that end where they start)");
  return loops;
}

namespace {

/// The pocket options checked: positive sizes, a stepover that leaves no material between
/// rings, a sane number of levels.
void checkPocketOptions(const PocketOptions& o) {
  positive(o.toolRadius, "tool radius");
  positive(o.stepover, "stepover");
  positive(o.depth, "depth");
  positive(o.tolerance, "tolerance");
  if (o.stepover > 2.0 * o.toolRadius)
    throw ParameterError("stepover " + std::to_string(o.stepover) +
                         " mm is more than the tool diameter " +
                         std::to_string(2.0 * o.toolRadius) +
                         " mm: material would stay between "
                         "the rings");
  if (o.stepDown < 0.0) throw ParameterError("step-down must not be negative");
  if (o.stepDown > 0.0 && o.depth / o.stepDown > 10000.0)
    throw ParameterError("step-down: " + std::to_string(o.stepDown) +
                         " mm makes more than 10000 "
                         "levels of a " +
                         std::to_string(o.depth) + " mm deep pocket");
}

/// The boundary as one set of oriented polygons: outer loops counter-clockwise, islands
/// clockwise (even-odd: a loop inside a loop is an island).
cl::Paths boundaryPolygons(const std::vector<Loop>& boundary, const PocketOptions& o) {
  cl::Paths loops;
  for (const Loop& l : boundary) {
    cl::Path p;
    for (const Eigen::Vector2d& q : flatten(l, 0.25 * o.tolerance))
      p.push_back(toInt(q));
    loops.push_back(p);
  }
  cl::Clipper c;
  c.AddPaths(loops, cl::ptSubject, true);
  cl::Paths base;
  c.Execute(cl::ctUnion, base, cl::pftEvenOdd, cl::pftEvenOdd);

  return base;
}

/// Offsets r, r + s, r + 2s, ... from the boundary, each as regions, every region linked to
/// the region of the previous offset that holds it (`roots`: those no region holds).
std::vector<Region> offsetRegions(const cl::Paths& base, const PocketOptions& o,
                                  std::vector<std::size_t>& roots) {
  std::vector<Region> all;
  std::vector<std::size_t> previous;
  for (int k = 0;; ++k) {
    const double delta = o.toolRadius + k * o.stepover;
    std::vector<Region> regions = regionsAt(base, delta, o.tolerance);
    if (regions.empty()) break;
    std::vector<std::size_t> now;
    for (Region& r : regions) {
      const std::size_t idx = all.size();
      bool held = false;
      for (std::size_t p : previous)
        if (insideRegion(r.outer.front(), all[p])) {
          all[p].children.push_back(idx);
          held = true;
          break;
        }
      if (!held) roots.push_back(idx);
      all.push_back(std::move(r));
      now.push_back(idx);
    }
    previous = std::move(now);
    if (k > 100000) throw Error("pocket: more than 100000 rings; is the stepover right?");
  }
  if (all.empty())
    throw Error("the tool (radius " + std::to_string(o.toolRadius) +
                " mm) does not fit in the pocket");

  return all;
}

/// Where a region (of the first `uniform`) has no inner region but material stays farther
/// than r from its ring, one more ring at the deepest offset that still exists there clears
/// it.
void clearLeftovers(std::vector<Region>& all, std::size_t uniform, const cl::Paths& base,
                    const PocketOptions& o) {
  for (std::size_t li = 0; li < uniform; ++li) {
    if (!all[li].children.empty()) continue;
    const Region leaf = all[li];
    auto insideLeaf = [&](double delta) {
      for (const Region& r : regionsAt(base, delta, o.tolerance))
        if (insideRegion(r.outer.front(), leaf)) return true;
      return false;
    };
    if (!insideLeaf(leaf.offset + o.toolRadius)) continue;
    double lo = leaf.offset + o.toolRadius, hi = leaf.offset + o.stepover;
    while (hi - lo > o.tolerance)
      (insideLeaf(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
    for (Region& r : regionsAt(base, lo, o.tolerance))
      if (insideRegion(r.outer.front(), leaf)) {
        all[li].children.push_back(all.size());
        all.push_back(std::move(r));
      }
  }
}

/// The rings in cut order: children before their parent (inside out), the nearest child
/// first; within a region the nearest ring first, each started where it is nearest.
std::vector<Ring> cutOrder(const std::vector<Region>& all, std::vector<std::size_t> roots,
                           const std::vector<Loop>& boundary, const PocketOptions& o) {
  std::vector<Ring> xy;
  Eigen::Vector2d at(std::numeric_limits<double>::quiet_NaN(), 0.0);
  auto emitRegion = [&](const Region& r) {
    std::vector<Ring> rings;
    rings.push_back(makeRing(r.outer, r.offset, false, boundary, o));
    for (const cl::Path& h : r.holes)
      rings.push_back(makeRing(h, r.offset, true, boundary, o));
    while (!rings.empty()) {
      std::size_t best = 0;
      if (!std::isnan(at.x())) {
        double bestD = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < rings.size(); ++i) {
          startNearest(rings[i], at);
          const double d = (rings[i].elements.front().start - at).norm();
          if (d < bestD) {
            bestD = d;
            best = i;
          }
        }
      }
      xy.push_back(std::move(rings[best]));
      rings.erase(rings.begin() + static_cast<std::ptrdiff_t>(best));
      at = xy.back().elements.front().start;
    }
  };
  auto nearestFirst = [&](std::vector<std::size_t>& ids) {
    if (std::isnan(at.x()) || ids.empty()) return;
    auto d = [&](std::size_t id) {
      double m = std::numeric_limits<double>::infinity();
      for (const cl::IntPoint& q : all[id].outer)
        m = std::min(m, (toMm(q) - at).squaredNorm());
      return m;
    };
    const auto it = std::min_element(ids.begin(), ids.end(),
                                     [&](std::size_t a, std::size_t b) { return d(a) < d(b); });
    std::iter_swap(ids.begin(), it);
  };
  std::function<void(std::size_t)> visit = [&](std::size_t id) {
    std::vector<std::size_t> kids = all[id].children;
    while (!kids.empty()) {
      nearestFirst(kids);
      const std::size_t next = kids.front();
      kids.erase(kids.begin());
      visit(next);
    }
    emitRegion(all[id]);
  };
  while (!roots.empty()) {
    nearestFirst(roots);
    const std::size_t next = roots.front();
    roots.erase(roots.begin());
    visit(next);
  }

  return xy;
}

/// Links: a straight feed move to the next ring when it starts within two stepovers and the
/// move stays where the tool centre may go (inside the first offset of the first `uniform`
/// regions).
void linkRings(std::vector<Ring>& xy, const std::vector<Region>& all, std::size_t uniform,
               const PocketOptions& o) {
  std::vector<Region> wall;
  for (std::size_t i = 0; i < uniform && all[i].offset == o.toolRadius; ++i)
    wall.push_back(all[i]);
  auto inside = [&](const Eigen::Vector2d& p) {
    const cl::IntPoint q = toInt(p);
    return std::any_of(wall.begin(), wall.end(),
                       [&](const Region& r) { return insideRegion(q, r); });
  };
  for (std::size_t i = 1; i < xy.size(); ++i) {
    const Eigen::Vector2d a = xy[i - 1].elements.front().start, b = xy[i].elements.front().start;
    bool ok = (b - a).norm() <= 2.0 * o.stepover + o.tolerance;
    for (int t = 1; ok && t < 16; ++t)
      ok = inside(a + (b - a) * (t / 16.0));
    xy[i].linked = ok;
  }
}

}  // namespace

std::vector<Ring> pocketRings(const std::vector<Loop>& boundary, const PocketOptions& o) {
  checkPocketOptions(o);
  const cl::Paths base = boundaryPolygons(boundary, o);
  std::vector<std::size_t> roots;
  std::vector<Region> all = offsetRegions(base, o, roots);
  const std::size_t uniform = all.size();
  clearLeftovers(all, uniform, base, o);
  std::vector<Ring> xy = cutOrder(all, roots, boundary, o);
  linkRings(xy, all, uniform, o);

  // Levels: the same rings at each depth, the first ring of a level entered from above.
  const int levels =
      o.stepDown > 0.0 ? std::max(1, static_cast<int>(std::ceil(o.depth / o.stepDown - 1e-9))) : 1;
  std::vector<Ring> out;
  for (int level = 0; level < levels; ++level)
    for (std::size_t i = 0; i < xy.size(); ++i) {
      Ring r = xy[i];
      r.level = level;
      if (i == 0) r.linked = false;
      out.push_back(std::move(r));
    }
  return out;
}

double levelZ(const PocketOptions& o, int level) {
  if (o.stepDown <= 0.0) return o.top - o.depth;
  return o.top - std::min((level + 1) * o.stepDown, o.depth);
}

std::string writePocketProgram(const std::vector<Ring>& rings, const PocketOptions& o,
                               const std::vector<std::string>& comments,
                               std::vector<int>* ringLines) {
  if (!(o.safeZ > o.top)) throw ParameterError("safe Z must be above the stock top");
  positive(o.feed, "feed");
  positive(o.plungeFeed, "plunge feed");
  const double unit = o.inch ? 25.4 : 1.0;
  // Coordinates to 0.01 um in mm and to 0.000001 in in inches, trailing zeros dropped.
  auto coordinate = [&](double mm) {
    char buf[64];
    std::snprintf(buf, sizeof buf, o.inch ? "%.6f" : "%.5f", mm / unit);
    std::string s(buf);
    while (!s.empty() && s.back() == '0')
      s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
    if (s == "-0") s = "0";
    return s;
  };
  auto feedNum = [&](double mmPerMin) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", mmPerMin / unit);
    return std::string(buf);
  };
  std::ostringstream g;
  for (const std::string& c : comments) {
    std::string clean = c;
    for (char& ch : clean)
      if (ch == '(' || ch == ')') ch = ' ';
    g << "(" << clean << ")\n";
  }
  g << (o.inch ? "G20" : "G21") << " G90 G17 G94 G91.1\n";
  g << "G0 Z" << coordinate(o.safeZ) << "\n";
  bool retracted = true;
  const double clearance = std::min(o.safeZ - o.top, o.inch ? 0.04 * 25.4 : 1.0);
  double feedNow = -1.0;
  auto feedWord = [&](double f) {
    if (f == feedNow) return std::string();
    feedNow = f;
    return " F" + feedNum(f);
  };
  for (const Ring& r : rings) {
    const double z = levelZ(o, r.level);
    const Eigen::Vector2d s = r.elements.front().start;
    if (!r.linked) {
      // Retract, go over the start, and enter just above the floor of the level above.
      const double levelTop = r.level == 0 ? o.top : levelZ(o, r.level - 1);
      if (!retracted) g << "G0 Z" << coordinate(o.safeZ) << "\n";
      g << "G0 X" << coordinate(s.x()) << " Y" << coordinate(s.y()) << "\n";
      g << "G0 Z" << coordinate(levelTop + clearance) << "\n";
      g << "G1 Z" << coordinate(z) << feedWord(o.plungeFeed) << "\n";
    } else {
      g << "G1 X" << coordinate(s.x()) << " Y" << coordinate(s.y()) << feedWord(o.feed) << "\n";
    }
    retracted = false;
    if (ringLines) {
      const std::string sofar = g.str();
      ringLines->push_back(1 + static_cast<int>(std::count(sofar.begin(), sofar.end(), '\n')));
    }
    for (const Element& e : r.elements) {
      if (e.arc) {
        g << (e.ccw ? "G3" : "G2") << " X" << coordinate(e.end.x()) << " Y" << coordinate(e.end.y())
          << " I" << coordinate(e.center.x() - e.start.x()) << " J"
          << coordinate(e.center.y() - e.start.y()) << feedWord(o.feed) << "\n";
      } else {
        g << "G1 X" << coordinate(e.end.x()) << " Y" << coordinate(e.end.y()) << feedWord(o.feed)
          << "\n";
      }
    }
  }
  g << "G0 Z" << coordinate(o.safeZ) << "\n";
  g << "M2\n";
  return g.str();
}

}  // namespace engage
