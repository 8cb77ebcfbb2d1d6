#include "stock/Part.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

namespace engage {
namespace {

// Plain doubles: the queries sit on the part's faces (a sample, a walk from it), where filtered
// exact predicates fall back to exact arithmetic at every step.
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
using Side = CGAL::Side_of_triangle_mesh<SurfaceMesh, Kernel>;

Point cgal(const Eigen::Vector3d& p) {
  return {p.x(), p.y(), p.z()};
}

Eigen::Vector3d corner(const TriangleMesh& m, unsigned v) {
  const auto& p = m.points[v];
  return {p[0], p[1], p[2]};
}

/// Calls fn(a, b, c) for the pieces of triangle abc split at the midpoint of the longest edge
/// until no edge is longer than `spacing`.
template <typename Fn>
void splitTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   double spacing2, Fn& fn) {
  const double ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(), ca = (a - c).squaredNorm();
  const double longest = std::max({ab, bc, ca});
  if (longest <= spacing2) {
    fn(a, b, c);
    return;
  }
  // Rotate so that the longest edge is ab, then halve it.
  if (ab < longest) {
    if (longest == bc) return splitTriangle(b, c, a, spacing2, fn);
    return splitTriangle(c, a, b, spacing2, fn);
  }
  const Eigen::Vector3d m = 0.5 * (a + b);
  splitTriangle(a, m, c, spacing2, fn);
  splitTriangle(m, b, c, spacing2, fn);
}

/// The sample of triangle pqr.
PartSample piece(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r,
                 const Eigen::Vector3f& normal) {
  return {((p + q + r) / 3.0).cast<float>(),
          normal,
          static_cast<float>(0.5 * (q - p).cross(r - p).norm()),
          {p.cast<float>(), q.cast<float>(), r.cast<float>()}};
}

/// How far from q along the unit direction d the box's boundary is (0 when q is outside it).
double exitDistance(const Eigen::Vector3d& q, const Eigen::Vector3d& d, const Box3& box) {
  double t = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (q[k] < box.min[k] || q[k] > box.max[k]) return 0.0;
    if (d[k] > 0.0) t = std::min(t, (box.max[k] - q[k]) / d[k]);
    if (d[k] < 0.0) t = std::min(t, (box.min[k] - q[k]) / d[k]);
  }
  return std::isfinite(t) ? t : 0.0;
}

Box3 grown(Box3 b, double by) {
  b.min.array() -= by;
  b.max.array() += by;
  return b;
}

/// Where the share of the sample q ends along the unit direction dir, knowing it ends before
/// `beyond`: where the distance to the part, d(s) = s up to there, falls below s. Newton's
/// step on the nearest point's tangent plane from the far end of the bracket (exact in one
/// where the nearer face is a plane), bisection where it leaves the bracket; to `precision`.
double shareEnd(const Part& part, const Eigen::Vector3d& q, const Eigen::Vector3d& dir,
                double beyond, double precision) {
  auto isBeyond = [&](double s) { return part.distance(q + s * dir, q) < s - precision; };
  double a = 0.0, b = beyond;
  while (b - a > precision) {
    const Eigen::Vector3d x = q + b * dir, p = part.closestPoint(x, q);
    const Eigen::Vector3d m = (x - p).normalized();
    const double denominator = 1.0 - dir.dot(m);
    double s = denominator > 1e-12 ? (q - p).dot(m) / denominator : 0.5 * (a + b);
    if (!(s > a && s < b)) s = 0.5 * (a + b);
    if (isBeyond(s)) {
      b = s;
    } else {
      a = s;
      if (isBeyond(std::min(s + precision, b))) b = std::min(s + precision, b);
    }
  }
  return 0.5 * (a + b);
}

}  // namespace

struct Part::Impl {
  TriangleMesh mesh;
  SurfaceMesh surface;
  Tree tree;
  std::unique_ptr<Side> side;
  Box3 bounds;
  double area = 0.0;
  double volume = 0.0;
};

Part Part::fromFile(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw Error("part file not found: " + path);
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return Part(ext == ".vdb" ? levelSetMesh(path) : readMesh(path), path);
}

Part::Part(TriangleMesh mesh, const std::string& name) : impl_(std::make_unique<Impl>()) {
  if (mesh.triangles.empty()) throw ParameterError(name + ": the part has no triangles");
  const std::size_t open = boundaryEdgeCount(mesh);
  if (open > 0)
    throw ParameterError(name + ": the part is not closed (" + std::to_string(open) +
                         " edges belong to one triangle only): its inside is not defined");
  // Outward normals: a closed mesh wound the other way (a negative volume) is turned over.
  Impl& m = *impl_;
  for (const auto& t : mesh.triangles)
    m.volume += corner(mesh, t[0]).dot(corner(mesh, t[1]).cross(corner(mesh, t[2]))) / 6.0;
  if (m.volume < 0.0)
    for (auto& t : mesh.triangles)
      std::swap(t[1], t[2]);
  m.volume = std::abs(m.volume);
  std::vector<SurfaceMesh::Vertex_index> vertex;
  vertex.reserve(mesh.points.size());
  m.bounds.min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  m.bounds.max = -m.bounds.min;
  for (const auto& p : mesh.points) {
    vertex.push_back(m.surface.add_vertex(Point(p[0], p[1], p[2])));
    for (int k = 0; k < 3; ++k) {
      m.bounds.min[k] = std::min<double>(m.bounds.min[k], p[static_cast<std::size_t>(k)]);
      m.bounds.max[k] = std::max<double>(m.bounds.max[k], p[static_cast<std::size_t>(k)]);
    }
  }
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = corner(mesh, t[0]), b = corner(mesh, t[1]), c = corner(mesh, t[2]);
    m.area += 0.5 * (b - a).cross(c - a).norm();
    if (m.surface.add_face(vertex[t[0]], vertex[t[1]], vertex[t[2]]) == SurfaceMesh::null_face())
      throw ParameterError(name +
                           ": the part's triangles do not form one surface (an edge is shared "
                           "by more than two triangles, or two triangles face opposite ways)");
  }
  m.tree.insert(faces(m.surface).first, faces(m.surface).second, m.surface);
  m.tree.build();
  m.tree.accelerate_distance_queries();
  m.side = std::make_unique<Side>(m.tree);
  m.mesh = std::move(mesh);
}

Part::Part(Part&&) noexcept = default;
Part& Part::operator=(Part&&) noexcept = default;
Part::~Part() = default;

const TriangleMesh& Part::mesh() const {
  return impl_->mesh;
}
Box3 Part::bounds() const {
  return impl_->bounds;
}
double Part::area() const {
  return impl_->area;
}
double Part::volume() const {
  return impl_->volume;
}

double Part::distance(const Eigen::Vector3d& p) const {
  return std::sqrt(impl_->tree.squared_distance(cgal(p)));
}

double Part::distance(const Eigen::Vector3d& p, const Eigen::Vector3d& onPart) const {
  return std::sqrt(impl_->tree.squared_distance(cgal(p), cgal(onPart)));
}

Eigen::Vector3d Part::closestPoint(const Eigen::Vector3d& p, const Eigen::Vector3d& onPart) const {
  const Point c = impl_->tree.closest_point(cgal(p), cgal(onPart));
  return {c.x(), c.y(), c.z()};
}

double Part::signedDistance(const Eigen::Vector3d& p) const {
  const double d = distance(p);
  return (*impl_->side)(cgal(p)) == CGAL::ON_BOUNDED_SIDE ? -d : d;
}

std::vector<PartSample> Part::samples(double spacing) const {
  std::vector<PartSample> out;
  out.reserve(sampleCount(spacing));
  const TriangleMesh& mesh = impl_->mesh;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = corner(mesh, t[0]), b = corner(mesh, t[1]), c = corner(mesh, t[2]);
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double norm = cross.norm();
    if (!(norm > 0.0)) continue;  // a degenerate triangle bounds nothing
    const Eigen::Vector3f normal = (cross / norm).cast<float>();
    auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
      out.push_back(piece(p, q, r, normal));
    };
    splitTriangle(a, b, c, spacing * spacing, add);
  }
  return out;
}

std::vector<PartSample> splitSample(const PartSample& sample, double spacing) {
  std::vector<PartSample> out;
  auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
    out.push_back(piece(p, q, r, sample.normal));
  };
  splitTriangle(sample.corners[0].cast<double>(), sample.corners[1].cast<double>(),
                sample.corners[2].cast<double>(), spacing * spacing, add);
  return out;
}

std::size_t Part::sampleCount(double spacing) const {
  std::size_t n = 0;
  const TriangleMesh& mesh = impl_->mesh;
  auto count = [&](const Eigen::Vector3d&, const Eigen::Vector3d&, const Eigen::Vector3d&) { ++n; };
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = corner(mesh, t[0]), b = corner(mesh, t[1]), c = corner(mesh, t[2]);
    if ((b - a).cross(c - a).norm() > 0.0) splitTriangle(a, b, c, spacing * spacing, count);
  }
  return n;
}

std::vector<SampleDeviation> measureDeviation(const Part& part,
                                              const std::vector<PartSample>& samples,
                                              const Stock& stock, const Box3* holds,
                                              const std::function<bool()>& stop) {
  const double h = stock.resolution();
  const double stepLength = 0.5 * h, precision = 1e-4 * h;
  // Outside the stock's bounds is air; the inward walk ends at the part's bounds at the latest
  // (the medial axis comes first for a closed part).
  const Box3 stockBox = holds ? *holds : grown(stock.bounds(), h),
             partBox = grown(part.bounds(), h);
  std::vector<SampleDeviation> out(samples.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      if (stop && stop()) return;
                      const std::unique_ptr<MaterialReader> reader = stock.materialReader();
                      std::vector<Eigen::Vector3d> one(1);
                      auto material = [&](const Eigen::Vector3d& p) {
                        one[0] = p;
                        return reader->read(one)[0] != 0;
                      };
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3d q = samples[i].point.cast<double>();
                        const bool inMaterial = material(q);
                        const Eigen::Vector3d dir =
                            (inMaterial ? 1.0 : -1.0) * samples[i].normal.cast<double>();
                        const double cap = exitDistance(q, dir, inMaterial ? stockBox : partBox);
                        // The share ends where another point of the part is nearer: once past
                        // there, it stays past (a point's nearest point is the nearest of every
                        // point between them). Checked at distances doubling from two cells: a walk
                        // goes at most twice as far as its share.
                        auto beyondShare = [&](double s) {
                          return part.distance(q + s * dir, q) < s - precision;
                        };
                        double lo = 0.0, hi = -1.0, check = 2.0 * h;
                        bool pastShare = false;
                        while (lo < cap) {
                          const double s = std::min(lo + stepLength, cap);
                          if (material(q + s * dir) != inMaterial) {
                            hi = s;
                            break;
                          }
                          lo = s;
                          if (lo >= check) {
                            if ((pastShare = beyondShare(lo))) break;
                            check *= 2.0;
                          }
                        }
                        double t = lo;
                        // The stock's surface: a change met, or a box stock's face where the
                        // material reaches it (not air up to the part's bounds: no surface).
                        const bool met = hi > 0.0 || (!pastShare && inMaterial);
                        if (hi > 0.0) {
                          while (hi - lo > precision) {
                            const double mid = 0.5 * (lo + hi);
                            (material(q + mid * dir) == inMaterial ? lo : hi) = mid;
                          }
                          t = 0.5 * (lo + hi);
                        }
                        // A hundredth of a cell is as good as none, whatever the share (a query
                        // saved at every sample of a surface cut where the part has it).
                        if (!pastShare) pastShare = t > 0.01 * h && beyondShare(t);
                        SampleDeviation& d = out[i];
                        d.surfaceMet = met && !pastShare;
                        d.stockPoint = (q + t * dir).cast<float>();
                        if (pastShare) t = shareEnd(part, q, dir, t, precision);
                        d.deviation = static_cast<float>(inMaterial ? t : -t);
                      }
                    });
  return out;
}

}  // namespace engage
