// The exact reference of ExactSweep.h. The stock is a Nef polyhedron (CGAL::Nef_polyhedron_3
// on the exact-constructions kernel): its faces are maximal planar regions, so a cut whose face
// coincides with an earlier one (a peck back to the last depth, a floor continued at one height)
// adds nothing. Surface_mesh corefinement was tried first and dropped for that reason: it keeps
// each hull's own triangulation of a flat cap, and two overlapping caps split each other into
// O(n^2) triangles (a rapid back down a 256-gon peck hole: 924 to 53,544 faces in one move).
// Volumes: the Nef stock converted to a triangle mesh and PMP::volume on the exact kernel,
// converted to double once per move (rounding ~1e-11 mm^3 of a 1e5 mm^3 total).

#include "tests/support/ExactSweep.h"
#include "cutters/Numbers.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/convert_nef_polyhedron_to_polygon_mesh.h>
#include <CGAL/boost/graph/generators.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace engage::test {

namespace {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Nef = CGAL::Nef_polyhedron_3<Kernel>;
namespace PMP = CGAL::Polygon_mesh_processing;

/// The profile's vertices in (rho, z): segment ends, and arcs cut into equal chords of at most
/// `arcDegrees`.
std::vector<Eigen::Vector2d> profilePoints(const AptCutter& cutter, double arcDegrees) {
  std::vector<Eigen::Vector2d> points;
  for (const ProfileSegment& s : cutter.profile()) {
    points.push_back(s.start);
    if (s.kind == ProfileSegment::Kind::Arc) {
      const Eigen::Vector2d a = s.start - s.center, b = s.end - s.center;
      const double a0 = std::atan2(a.y(), a.x());
      double sweep = std::atan2(b.y(), b.x()) - a0;  // counter-clockwise from start to end
      while (sweep <= 0.0)
        sweep += 2.0 * kPi;
      const int n = std::max(1, static_cast<int>(std::ceil(sweep * 180.0 / kPi / arcDegrees)));
      for (int k = 1; k < n; ++k) {
        const double t = a0 + sweep * k / n;
        points.emplace_back(s.center + s.radius * Eigen::Vector2d(std::cos(t), std::sin(t)));
      }
    }
    points.push_back(s.end);
  }
  return points;
}

/// The faceted cutter's vertices with its tip at `tip`.
void addCopy(const std::vector<Eigen::Vector2d>& profile, int ring, const Eigen::Vector3d& tip,
             std::vector<Point>& out) {
  for (const Eigen::Vector2d& p : profile) {
    if (p.x() <= 0.0) {
      out.emplace_back(tip.x(), tip.y(), tip.z() + p.y());
      continue;
    }
    for (int j = 0; j < ring; ++j) {
      const double a = 2.0 * kPi * j / ring;
      out.emplace_back(tip.x() + p.x() * std::cos(a), tip.y() + p.x() * std::sin(a),
                       tip.z() + p.y());
    }
  }
}

}  // namespace

double facetDeviation(const AptCutter& cutter, const Faceting& faceting) {
  double d = cutter.maxRadius() * (1.0 - std::cos(kPi / faceting.ringVertices));
  for (const ProfileSegment& s : cutter.profile())
    if (s.kind == ProfileSegment::Kind::Arc)
      d = std::max(d, s.radius * (1.0 - std::cos(faceting.arcDegrees * kPi / 360.0)));
  return d;
}

std::vector<double> exactRemovals(const Toolpath& path, const std::vector<AptCutter>& cutterOfMove,
                                  const Box3& box, const Faceting& faceting) {
  if (cutterOfMove.size() != path.moves.size())
    throw std::invalid_argument("exactRemovals: one cutter per move");
  Mesh boxMesh;
  const Eigen::Vector3d& lo = box.min;
  const Eigen::Vector3d& hi = box.max;
  CGAL::make_hexahedron(Point(lo.x(), lo.y(), lo.z()), Point(hi.x(), lo.y(), lo.z()),
                        Point(hi.x(), hi.y(), lo.z()), Point(lo.x(), hi.y(), lo.z()),
                        Point(lo.x(), hi.y(), hi.z()), Point(lo.x(), lo.y(), hi.z()),
                        Point(hi.x(), lo.y(), hi.z()), Point(hi.x(), hi.y(), hi.z()), boxMesh);
  PMP::triangulate_faces(boxMesh);
  Nef stock(boxMesh);
  auto volume = [](const Nef& nef) {
    Mesh mesh;
    CGAL::convert_nef_polyhedron_to_polygon_mesh(nef, mesh, true);
    return CGAL::to_double(PMP::volume(mesh));
  };
  double before = volume(stock);
  std::vector<double> removed;
  removed.reserve(path.moves.size());
  for (std::size_t i = 0; i < path.moves.size(); ++i) {
    const Move& m = path.moves[i];
    if (m.kind != MoveKind::Rapid && m.kind != MoveKind::Line)
      throw std::invalid_argument("exactRemovals: move " + std::to_string(i) +
                                  " is not a straight line");
    const std::vector<Eigen::Vector2d> profile =
        profilePoints(cutterOfMove[i], faceting.arcDegrees);
    std::vector<Point> points;
    addCopy(profile, faceting.ringVertices, m.start, points);
    addCopy(profile, faceting.ringVertices, m.end, points);
    Mesh hull;
    CGAL::convex_hull_3(points.begin(), points.end(), hull);
    stock -= Nef(hull);
    const double after = volume(stock);
    removed.push_back(before - after);
    if (std::getenv("ENGAGE_EXACT_TRACE"))
      std::fprintf(stderr, "move %zu line %d: %.6f mm3\n", i, m.line, before - after);
    before = after;
  }
  return removed;
}

}  // namespace engage::test
