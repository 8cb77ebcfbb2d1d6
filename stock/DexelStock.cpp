#include "stock/DexelStock.h"

#include "cutters/Error.h"
#include "cutters/Geometry.h"
#include "cutters/Numbers.h"
#include "stock/DexelSolid.h"
#include "stock/TriangleMesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace engage {
using namespace dexel;
namespace {

/// Precision of a ray's entry into and exit from a swept solid, mm.
constexpr double kZTolerance = 1e-4;
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
/// A column share within this of 0 or 1 is all air or all material for inMaterial.
constexpr double kShareNoise = 1e-9;
/// A line across a column that leaves its 3 x 3 neighbours their shares to this (sum of
/// squares) holds them all: no other is tried; to kGoodLine (a hundredth of a share in
/// each), no one-sided one.
constexpr double kExactLine = 1e-12, kGoodLine = 1e-3;

/// The share of the unit square [-1/2, 1/2]^2 on the side m . u <= offset of a line (m of
/// unit length), in closed form (Scardovelli & Zaleski 2000).
double squareShare(const Eigen::Vector2d& m, double offset) {
  const double m1 = std::min(std::abs(m.x()), std::abs(m.y()));
  const double m2 = std::max(std::abs(m.x()), std::abs(m.y()));
  const double alpha = offset + 0.5 * (m1 + m2);  // from the square's lowest corner
  if (alpha <= 0.0) return 0.0;
  if (alpha >= m1 + m2) return 1.0;
  if (m1 < 1e-12) return std::clamp(alpha / m2, 0.0, 1.0);
  if (alpha < m1) return alpha * alpha / (2.0 * m1 * m2);
  if (alpha <= m2) return (2.0 * alpha - m1) / (2.0 * m2);
  const double rest = m1 + m2 - alpha;
  return 1.0 - rest * rest / (2.0 * m1 * m2);
}

/// The offset of the line with normal m (unit length) that leaves `share` of the unit square
/// on the side m . u <= offset: squareShare's inverse.
double squareOffset(const Eigen::Vector2d& m, double share) {
  const double m1 = std::min(std::abs(m.x()), std::abs(m.y()));
  const double m2 = std::max(std::abs(m.x()), std::abs(m.y()));
  double alpha;
  if (m1 < 1e-12) {
    alpha = m2 * share;
  } else {
    const double corner = m1 / (2.0 * m2);  // the share cut off below alpha = m1
    if (share <= corner)
      alpha = std::sqrt(2.0 * m1 * m2 * share);
    else if (share <= 1.0 - corner)
      alpha = m2 * share + 0.5 * m1;
    else
      alpha = m1 + m2 - std::sqrt(2.0 * m1 * m2 * (1.0 - share));
  }
  return alpha - 0.5 * (m1 + m2);
}

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

constexpr double kParallelLines = 0.9659258262890683;  // cos 15 deg

/// The part of the unit square [-1/2, 1/2]^2 inside two half-planes m . u <= a and n . u <= b:
/// its area (the square clipped by each in turn, Sutherland-Hodgman).
double clippedArea(const Eigen::Vector2d& m, double a, const Eigen::Vector2d& n, double b) {
  // (At most 6 vertices: a square cut by two lines.)
  Eigen::Vector2d poly[8] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
  int count = 4;
  auto clip = [&](const Eigen::Vector2d& k, double c) {
    Eigen::Vector2d out[8];
    int n2 = 0;
    for (int v = 0; v < count; ++v) {
      const Eigen::Vector2d& p = poly[v];
      const Eigen::Vector2d& q = poly[(v + 1) % count];
      const double dp = k.dot(p) - c, dq = k.dot(q) - c;
      if (dp <= 0.0) out[n2++] = p;
      if ((dp < 0.0) != (dq < 0.0) && dp != dq && n2 < 8)
        out[n2++] = p + (q - p) * (dp / (dp - dq));
    }
    count = n2;
    std::copy(out, out + n2, poly);
  };
  clip(m, a);
  if (count >= 3) clip(n, b);
  double twice = 0.0;
  for (int v = 0; count >= 3 && v < count; ++v) {
    const Eigen::Vector2d& p = poly[v];
    const Eigen::Vector2d& q = poly[(v + 1) % count];
    twice += p.x() * q.y() - p.y() * q.x();
  }
  return std::clamp(0.5 * twice, 0.0, 1.0);
}

/// What a column's material interval `x` keeps where a piece `sx` of a step's swept solid
/// covers the share sx.f of the column: the share of the column inside x's line and outside
/// the cutter's, with the cutter's line (the newest surface, which the next step of the same
/// cutter meets nearly parallel) at the offset that leaves that share. Lines within 15 deg of
/// parallel, or where either is not known, are taken as one curve cut again: min(f, 1 - cover)
/// (a circle's outline turns by h / r across a column, so its straight pieces in a column
/// cross a wall it runs along). A box's face across its last columns and a wall left by an
/// earlier pass are lines too, so a cutter that passes outside the face takes nothing from it,
/// and one whose front crosses a wall's column at an angle takes the area it covers of the
/// material, not its share of the column (which made a steady arc's steps vary by 0.55 %).
DexelStock::Interval rest(const DexelStock::Interval& x, const DexelStock::Interval& sx) {
  DexelStock::Interval r = x;
  const double keep = 1.0 - sx.f;
  if (sx.f <= 0.0) return r;
  r.mx = -sx.mx;
  r.my = -sx.my;
  if (keep <= 0.0) {
    r.f = 0.0;
    return r;
  }
  const Eigen::Vector2d n(sx.mx, sx.my), m(x.mx, x.my);
  const bool lines = x.f < 1.0 && m.squaredNorm() > 0.0 && n.squaredNorm() > 0.0;
  if (!lines || -m.normalized().dot(n.normalized()) >= kParallelLines) {
    if (x.f <= keep) return x;
    r.f = keep;
    return r;
  }
  // Material: m . u <= squareOffset(m, f); the cutter's side: n . u <= squareOffset(n, cover),
  // so what stays outside it: -n . u <= -that.
  const Eigen::Vector2d mu = m.normalized(), nu = n.normalized();
  r.f = std::min(clippedArea(mu, squareOffset(mu, x.f), -nu, -squareOffset(nu, sx.f)),
                 std::min(x.f, keep));
  return r;
}

/// What piece `sx` takes from the ray's material in [sx.z0, sx.z1], leaving each interval
/// there its rest() (`rests`, one per interval of `iv`, computed once by the caller); returns
/// the material removed, mm (length x share).
double cut(Intervals& iv, const DexelStock::Interval& sx, const Intervals& rests) {
  const double a = sx.z0, b = sx.z1;
  if (!(b > a)) return 0.0;
  double removed = 0.0;
  // Scratch buffers reused from call to call (a removal calls this for every band piece of
  // every ray it reaches): no allocation once they have grown.
  static thread_local Intervals out, merged;
  out.clear();
  for (std::size_t k = 0; k < iv.size(); ++k) {
    const Interval& x = iv[k];
    const Interval& r = rests[k];
    if (r.f >= x.f - kSameShare) {
      out.push_back(x);
      continue;
    }
    const double lo = std::max(x.z0, a), hi = std::min(x.z1, b);
    removed += (hi - lo) * (x.f - r.f);
    if (x.z0 < lo) out.push_back({x.z0, lo, x.f, x.mx, x.my});
    if (r.f > 1e-9) out.push_back({lo, hi, r.f, r.mx, r.my});
    if (hi < x.z1) out.push_back({hi, x.z1, x.f, x.mx, x.my});
  }
  // Neighbours with one share and one line become one interval.
  merged.clear();
  for (const Interval& x : out) {
    if (!merged.empty() && merged.back().z1 >= x.z0 - 1e-12 && merged.back().f == x.f &&
        merged.back().mx == x.mx && merged.back().my == x.my)
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
  // column, covered by their share of the box: an interval of that share whose line is the
  // box's face (at the corner column, the line of the two faces' shares' weights), so that a
  // cutter passing outside the face takes nothing from it.
  for (int j = 0; j < s.ny_; ++j)
    for (int i = 0; i < s.nx_; ++i) {
      const double x = s.x0_ + i * spacing, y = s.y0_ + j * spacing;
      const double sx = overlap(x, x + spacing, b.min.x(), b.max.x());
      const double sy = overlap(y, y + spacing, b.min.y(), b.max.y());
      if (sx * sy <= 0.0) continue;
      s.weight_[s.index(i, j)] = 1.0;
      Eigen::Vector2d m(1.0 - sx, 1.0 - sy);
      if (m.squaredNorm() > 0.0) m.normalize();
      s.rays_[s.index(i, j)] = {
          {b.min.z(), b.max.z(), sx * sy, static_cast<float>(m.x()), static_cast<float>(m.y())}};
    }
  return s;
}

DexelStock DexelStock::fromColumns(double x0, double y0, double spacing, int nx, int ny,
                                   std::vector<std::vector<Interval>> rays,
                                   std::vector<double> weights) {
  if (nx <= 0 || ny <= 0 ||
      rays.size() != static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) ||
      (!weights.empty() && weights.size() != rays.size()))
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
  if (weights.empty())
    s.weight_.assign(rays.size(), 1.0);
  else
    s.weight_ = std::move(weights);
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
  // Columns and heights first, positions at the end (one pass over every ray).
  int i0 = nx_, i1 = -1, j0 = ny_, j1 = -1;
  double z0 = 1e300, z1 = -1e300;
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) {
      const auto& r = rays_[index(i, j)];
      if (r.empty()) continue;
      i0 = std::min(i0, i);
      i1 = std::max(i1, i);
      j0 = std::min(j0, j);
      j1 = std::max(j1, j);
      z0 = std::min(z0, r.front().z0);
      z1 = std::max(z1, r.back().z1);
    }
  Box3 b;
  if (i1 < 0) {
    b.min = b.max = Eigen::Vector3d::Zero();
    return b;
  }
  b.min = Eigen::Vector3d(x0_ + i0 * h_, y0_ + j0 * h_, z0);
  b.max = Eigen::Vector3d(x0_ + (i1 + 1) * h_, y0_ + (j1 + 1) * h_, z1);
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
  // does.
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

/// A dexel stock's MaterialReader. A column crossed by a surface holds it as a line that
/// leaves the column's share (ELVIRA: of the lines whose slopes the 3 x 3 neighbours' shares
/// summed across them give, by central, backward and forward differences along either axis,
/// the one that best leaves the neighbours their shares). Exact for a straight surface across
/// the nine columns, and for one across six of them where the other three hold another (a cut
/// beside a wall). A column has two shares, each with its own surface: its own (field 0: the
/// stock's faces, the same at every height) and its interval's (field 1: the cuts). Lines are
/// kept for the heights where the nine shares stay the same: one measurement reads the same
/// columns again and again, slice above slice.
class DexelReader final : public MaterialReader {
  /// The column (floor) of grid coordinate g, -1 for any left of the grid: truncation where
  /// std::floor is a call of its own (this build targets x86-64 without SSE4.1's roundsd).
  static int column(double g) {
    g = std::clamp(g, -1.0, 1e9);
    const int i = static_cast<int>(g);
    return i - (g < static_cast<double>(i) ? 1 : 0);
  }

 public:
  DexelReader(const DexelStock& stock, std::size_t afterStep) : s_(stock), after_(afterStep) {}

  const std::vector<std::uint8_t>& read(const std::vector<Eigen::Vector3d>& points) override {
    out_.clear();
    for (const Eigen::Vector3d& p : points) {
      // Column (i, j) spans [x0 + i h, x0 + (i + 1) h] in x.
      const double gx = (p.x() - s_.x0_) / s_.h_, gy = (p.y() - s_.y0_) / s_.h_;
      const int i = column(gx), j = column(gy);
      out_.push_back(inside(0, i, j, p.z(), gx, gy) && inside(1, i, j, p.z(), gx, gy));
    }
    return out_;
  }

 private:
  struct Line {
    double lo, hi;      // the heights it holds for
    Eigen::Vector2d m;  // outward normal (zero: the share alone decides)
    double offset;
    std::uint32_t next;  // the column's next line in pool_ (kNone: the last)
  };
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

  /// The share of column (i, j) in `field` at height z; narrows [lo, hi) to the heights about z
  /// where it stays the same.
  double share(int field, int i, int j, double z, double& lo, double& hi) const {
    if (i < 0 || j < 0 || i >= s_.nx_ || j >= s_.ny_) return 0.0;
    if (field == 0) return s_.weight_[s_.index(i, j)];
    double below = -std::numeric_limits<double>::infinity();
    const auto [begin, end] = ray(s_.index(i, j));
    for (const DexelStock::Interval* it = begin; it != end; ++it) {
      const DexelStock::Interval& piece = *it;
      if (z < piece.z0) {
        lo = std::max(lo, below);
        hi = std::min(hi, piece.z0);
        return 0.0;
      }
      if (z < piece.z1) {
        lo = std::max(lo, piece.z0);
        hi = std::min(hi, piece.z1);
        return piece.f;
      }
      below = piece.z1;
    }
    lo = std::max(lo, below);
    return 0.0;
  }

  bool inside(int field, int i, int j, double z, double gx, double gy) {
    double lo = 0.0, hi = 0.0;
    const double at = share(field, i, j, z, lo, hi);
    if (at >= 1.0 - kShareNoise || at <= kShareNoise) return at > 0.5;
    const Line& l = line(field, i, j, z, at);
    if (l.m.squaredNorm() == 0.0) return at > 0.5;
    return l.m.x() * (gx - i - 0.5) + l.m.y() * (gy - j - 0.5) <= l.offset;
  }

  /// Ray k's intervals after step after_ of the last batch: what it held before the first
  /// later step changed it, else what it holds.
  std::pair<const DexelStock::Interval*, const DexelStock::Interval*> ray(std::size_t k) const {
    if (after_ != Stock::kLatest) {
      const auto found = s_.beforeOf_.find(k);
      if (found != s_.beforeOf_.end())
        for (std::size_t q = found->second; q < s_.before_.size() && s_.before_[q].ray == k; ++q)
          if (s_.before_[q].step > after_) {
            const DexelStock::Interval* a = s_.beforeIntervals_.data() + s_.before_[q].from;
            return {a, a + s_.before_[q].count};
          }
    }
    const std::vector<DexelStock::Interval>& now = s_.rays_[k];
    return {now.data(), now.data() + now.size()};
  }

  const Line& line(int field, int i, int j, double z, double at) {
    const std::uint64_t key =
        static_cast<std::uint64_t>(s_.index(i, j)) * 2u + static_cast<std::uint64_t>(field);
    std::uint32_t& head = slot(key);
    for (std::uint32_t k = head; k != kNone; k = pool_[k].next)
      if (z >= pool_[k].lo && z < pool_[k].hi) return pool_[k];
    Line l{-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           Eigen::Vector2d::Zero(), 0.0, head};
    double n[3][3];
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        n[a + 1][b + 1] = share(field, i + a, j + b, z, l.lo, l.hi);
    const double gxs = (n[2][0] + 2.0 * n[2][1] + n[2][2]) - (n[0][0] + 2.0 * n[0][1] + n[0][2]);
    const double gys = (n[0][2] + 2.0 * n[1][2] + n[2][2]) - (n[0][0] + 2.0 * n[1][0] + n[2][0]);
    double bestError = std::numeric_limits<double>::infinity();
    auto consider = [&](const Eigen::Vector2d& normal) {
      if (!(normal.norm() > 0.0)) return;
      const Eigen::Vector2d m = normal.normalized();
      const double offset = squareOffset(m, at);
      double error = 0.0;
      for (int a = -1; a <= 1; ++a)
        for (int b = -1; b <= 1; ++b) {
          const double d = squareShare(m, offset - m.x() * a - m.y() * b) - n[a + 1][b + 1];
          error += d * d;
        }
      if (error < bestError) {
        bestError = error;
        l.m = m;
        l.offset = offset;
      }
    };
    const double rows[3] = {n[0][0] + n[1][0] + n[2][0], n[0][1] + n[1][1] + n[2][1],
                            n[0][2] + n[1][2] + n[2][2]};  // material along x, per row
    const double cols[3] = {n[0][0] + n[0][1] + n[0][2], n[1][0] + n[1][1] + n[1][2],
                            n[2][0] + n[2][1] + n[2][2]};  // along y, per column
    const bool alongX = std::abs(gxs) >= std::abs(gys);
    // The central differences first, along the axis the material grows along most, then the
    // other: a straight surface across the nine columns the first reproduces exactly, and a
    // gently curved one nearly (kGoodLine); only where neither does (another surface among
    // the nine) are the one-sided differences tried.
    auto candidates = [&](int from, int to) {
      for (int pass = 0; pass < 2 && !(bestError < kExactLine); ++pass) {
        const bool x = (pass == 0) == alongX;
        const double* sums = x ? rows : cols;
        const double g = x ? gxs : gys;
        if (g == 0.0) continue;
        const double sign = g > 0.0 ? -1.0 : 1.0;
        const double slopes[3] = {0.5 * (sums[2] - sums[0]), sums[1] - sums[0], sums[2] - sums[1]};
        for (int c = from; c < to && !(bestError < kExactLine); ++c)
          consider(x ? Eigen::Vector2d(sign, -slopes[c]) : Eigen::Vector2d(-slopes[c], sign));
      }
    };
    candidates(0, 1);
    if (!(bestError < kGoodLine)) candidates(1, 3);
    pool_.push_back(l);
    head = static_cast<std::uint32_t>(pool_.size() - 1);
    return pool_.back();
  }

  /// The head of key's list in the open-addressed table (kNone: a new key), the table grown
  /// to keep it at most half full.
  std::uint32_t& slot(std::uint64_t key) {
    if (2 * (used_ + 1) > keys_.size()) {
      std::vector<std::uint64_t> keys = std::move(keys_);
      std::vector<std::uint32_t> heads = std::move(heads_);
      keys_.assign(std::max<std::size_t>(256, 2 * keys.size()), kEmpty);
      heads_.assign(keys_.size(), kNone);
      used_ = 0;
      for (std::size_t q = 0; q < keys.size(); ++q)
        if (keys[q] != kEmpty) slot(keys[q]) = heads[q];
    }
    const std::size_t mask = keys_.size() - 1;
    for (std::size_t q = (key * 0x9E3779B97F4A7C15ull) >> 20 & mask;; q = (q + 1) & mask) {
      if (keys_[q] == key) return heads_[q];
      if (keys_[q] == kEmpty) {
        keys_[q] = key;
        ++used_;
        return heads_[q];
      }
    }
  }

  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  const DexelStock& s_;
  std::size_t after_;
  std::vector<Line> pool_;
  std::vector<std::uint64_t> keys_;   // per column and field: an open-addressed table
  std::vector<std::uint32_t> heads_;  // of the heads of their lists in pool_
  std::size_t used_ = 0;
  std::vector<std::uint8_t> out_;
};

std::unique_ptr<MaterialReader> DexelStock::materialReader(std::size_t afterStep) const {
  return std::make_unique<DexelReader>(*this, afterStep);
}

Removal DexelStock::remove(const Sweep& sweep, int step, double dtSeconds) {
  return removeSteps({StepCut{&sweep, step, dtSeconds, {}}}).front();
}

/// Consecutive steps overlap (each starts where the last ended), so steps cannot run side by
/// side; columns can, each taking the steps that reach it in their order. A batch of steps is
/// taken in tiles of 16 x 16 columns, the tiles side by side, so that programs of small steps
/// (a few dozen columns each) run in parallel too; the simulation ends a batch at 128 steps
/// or 8192 columns. Speed-ups measured: docs/performance.md. One function: the steps' plans,
/// the tiles and the merge of their sums share the batch's local types, and the per-column
/// removal (removeColumn) is the run's hot loop, kept inline in the tile loop.
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
    double z0, z1;
  };
  struct Part {
    double volume = 0.0, lateral = 0.0;
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
    std::vector<Before> before;      // the rays' intervals before each step changed them
    std::vector<Interval> beforeIntervals;
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
    bool logged = false;
    LostColumn* column = nullptr;         // this ray's losses, found or started on its first loss
    static thread_local Intervals rests;  // (scratch: what each interval keeps of one piece)
    for (const Interval& sx : solid) {
      // What each interval keeps (once: the capture and the cut take the same), what of the
      // ray in [z0, z1] loses material; remember where, for the axial depth. Most pieces change
      // nothing (air, or material already cut as far): no cut, no copy then.
      rests.resize(ray.size());
      bool loses = false;
      for (std::size_t k = 0; k < ray.size(); ++k) {
        const Interval& x = ray[k];
        rests[k] = x.z1 > sx.z0 && x.z0 < sx.z1 ? rest(x, sx) : x;
        if (rests[k].f < x.f - kSameShare) {
          tile.cuts.push_back({std::max(x.z0, sx.z0), std::min(x.z1, sx.z1)});
          loses = true;
        }
      }
      if (!loses) continue;
      // The ray as it was before this step's first change, for readers of the material after
      // an earlier step of the batch.
      if (!logged) {
        tile.before.push_back({index(i, j), s, tile.beforeIntervals.size(), ray.size()});
        tile.beforeIntervals.insert(tile.beforeIntervals.end(), ray.begin(), ray.end());
        logged = true;
      }
      // The capture: what each of the ray's intervals the piece cuts loses, as cut() takes
      // it, summed into the column's cells of voxel height, with the first step to take some
      // (so that removed.vdb holds the removed volume, and in its place, exact to float
      // rounding). A log at a span's mean share would put a wall column's rest and the
      // material below it at one share, more than a voxel's material in some voxels.
      if (capture_) {
        for (std::size_t n = 0; n < ray.size(); ++n) {
          const Interval& x = ray[n];
          const double kept = rests[n].f;
          if (kept < x.f - kSameShare) {
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
            const double share = (x.f - kept) * weight_[index(i, j)];
            voxelHeights(h_, std::max(x.z0, sx.z0), std::min(x.z1, sx.z1), [&](int k, double z) {
              Lost& cell = lostCell(*column, k);
              cell.share += static_cast<float>(z * share);
              if (cell.step < 0) cell.step = steps[s].step;
            });
          }
        }
      }
      removed += cut(ray, sx, rests);
    }
    if (removed <= 0.0) return;
    const double w = weight_[index(i, j)];
    const double volume = removed * w * h_ * h_;
    part.volume += volume;
    ++part.changed;
    const double side = (q - path.end.head<2>()).dot(g.n);
    part.lateral += volume * side;
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

  // The rays' earlier intervals, by ray and step (a tile logs its rays in step order; tiles
  // hold different rays).
  before_.clear();
  beforeIntervals_.clear();
  for (Tile& tile : tiles) {
    for (Before b : tile.before) {
      b.from += beforeIntervals_.size();
      before_.push_back(b);
    }
    beforeIntervals_.insert(beforeIntervals_.end(), tile.beforeIntervals.begin(),
                            tile.beforeIntervals.end());
  }
  std::stable_sort(before_.begin(), before_.end(),
                   [](const Before& a, const Before& b) { return a.ray < b.ray; });
  beforeOf_.clear();
  for (std::size_t q = 0; q < before_.size(); ++q)
    beforeOf_.try_emplace(before_[q].ray, q);

  // Each step's sums, tile by tile; the loss columns its tiles started join lost_.
  std::vector<Removal> outs(steps.size());
  std::vector<std::size_t> nextPart(tiles.size(), 0), nextStarted(tiles.size(), 0);
  std::vector<Cut> cuts;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    Removal& out = outs[s];
    double zMin = 1e300, zMax = -1e300;
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
