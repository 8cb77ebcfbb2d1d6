#include "stock/CubeClip.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

namespace engage {
namespace {

using Tet = std::array<Eigen::Vector3d, 4>;

double tetVolume(const Tet& t) {
  const Eigen::Vector3d a = t[1] - t[0], b = t[2] - t[0], c = t[3] - t[0];
  return std::abs(a.x() * (b.y() * c.z() - b.z() * c.y()) -
                  a.y() * (b.x() * c.z() - b.z() * c.x()) +
                  a.z() * (b.x() * c.y() - b.y() * c.x())) /
         6.0;
}

/// Volume of tetrahedron t inside planes[0 .. count): clip by the first plane into at most
/// three tetrahedra, recurse with the rest. With `moment`, adds volume x centroid there.
double clipped(const Tet& t, const HalfSpace* planes, int count, Eigen::Vector3d* moment) {
  if (count == 0) {
    const double v = tetVolume(t);
    if (moment) *moment += v * (t[0] + t[1] + t[2] + t[3]) / 4.0;
    return v;
  }
  const HalfSpace& p = *planes;
  std::array<double, 4> s{};
  std::array<int, 4> in{}, out{};
  int nin = 0, nout = 0;
  for (int i = 0; i < 4; ++i) {
    s[static_cast<std::size_t>(i)] = p.n.dot(t[static_cast<std::size_t>(i)]) - p.a;
    if (s[static_cast<std::size_t>(i)] <= 0.0)
      in[static_cast<std::size_t>(nin++)] = i;
    else
      out[static_cast<std::size_t>(nout++)] = i;
  }
  if (nout == 0) return clipped(t, planes + 1, count - 1, moment);
  if (nin == 0) return 0.0;
  auto v = [&](int i) { return t[static_cast<std::size_t>(i)]; };
  if (count == 1 && !(moment && nin == 2)) {
    // The last plane: the share of the tetrahedron below it in closed form (the distribution
    // of a linear function over a tetrahedron), with x = -s at the inside vertices and
    // C, D, E = s at the outside ones: one inside, x^3 / ((C + x)(D + x)(E + x)); three
    // inside, one less the outside corner's share; two inside,
    // (C D (x^2 + x y + y^2) + (C + D) x y (x + y) + x^2 y^2) / ((C + x)(D + x)(C + y)(D + y)).
    auto at = [&](int i) { return s[static_cast<std::size_t>(i)]; };
    const double whole = tetVolume(t);
    auto corner = [&](int k, int o0, int o1, int o2, Eigen::Vector3d& centroid) {
      // The share of the corner at vertex k cut off by the plane, and its centroid.
      const double x = std::abs(at(k));
      const double r0 = x / (x + std::abs(at(o0))), r1 = x / (x + std::abs(at(o1))),
                   r2 = x / (x + std::abs(at(o2)));
      if (moment)
        centroid = v(k) + (r0 * (v(o0) - v(k)) + r1 * (v(o1) - v(k)) + r2 * (v(o2) - v(k))) / 4.0;
      return r0 * r1 * r2;
    };
    Eigen::Vector3d centroid;
    if (nin == 1) {
      const double share = corner(in[0], out[0], out[1], out[2], centroid);
      if (moment) *moment += whole * share * centroid;
      return whole * share;
    }
    if (nin == 3) {
      const double share = corner(out[0], in[0], in[1], in[2], centroid);
      if (moment) *moment += whole * (v(0) + v(1) + v(2) + v(3)) / 4.0 - whole * share * centroid;
      return whole * (1.0 - share);
    }
    const double x = -at(in[0]), y = -at(in[1]), C = at(out[0]), D = at(out[1]);
    return whole * (C * D * (x * x + x * y + y * y) + (C + D) * x * y * (x + y) + x * x * y * y) /
           ((C + x) * (D + x) * (C + y) * (D + y));
  }
  // Where the plane crosses the edge from inside vertex i to outside vertex o.
  auto cross = [&](int i, int o) {
    const auto si = static_cast<std::size_t>(i), so = static_cast<std::size_t>(o);
    return Eigen::Vector3d(t[si] + (t[so] - t[si]) * (s[si] / (s[si] - s[so])));
  };
  // A prism with bottom a0 a1 a2 and top b0 b1 b2 (edges ai-bi) as three tetrahedra.
  auto prism = [&](const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& a2,
                   const Eigen::Vector3d& b0, const Eigen::Vector3d& b1,
                   const Eigen::Vector3d& b2) {
    return clipped(Tet{a0, a1, a2, b2}, planes + 1, count - 1, moment) +
           clipped(Tet{a0, a1, b1, b2}, planes + 1, count - 1, moment) +
           clipped(Tet{a0, b0, b1, b2}, planes + 1, count - 1, moment);
  };
  if (nin == 1) {
    const int i = in[0];
    return clipped(Tet{v(i), cross(i, out[0]), cross(i, out[1]), cross(i, out[2])}, planes + 1,
                   count - 1, moment);
  }
  if (nin == 3) {  // the tetrahedron less the corner at the outside vertex: a prism
    const int o = out[0];
    return prism(v(in[0]), v(in[1]), v(in[2]), cross(in[0], o), cross(in[1], o), cross(in[2], o));
  }
  // Two inside (i0, i1), two outside (o0, o1): a wedge between the triangles at i0 and i1.
  const int i0 = in[0], i1 = in[1], o0 = out[0], o1 = out[1];
  return prism(v(i0), cross(i0, o0), cross(i0, o1), v(i1), cross(i1, o0), cross(i1, o1));
}

/// The six tetrahedra of the unit cube about the diagonal from (-1/2)^3 to (1/2)^3.
std::array<Tet, 6> kuhnTetrahedra() {
  std::array<Tet, 6> tets;
  const std::array<std::array<int, 3>, 6> orders = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (std::size_t k = 0; k < 6; ++k) {
    Eigen::Vector3d p = Eigen::Vector3d::Constant(-0.5);
    tets[k][0] = p;
    for (std::size_t j = 0; j < 3; ++j) {
      p[orders[k][j]] += 1.0;
      tets[k][j + 1] = p;
    }
  }
  return tets;
}

/// Share of the unit cube below one plane, in closed form (Scardovelli and Zaleski,
/// J. Comput. Phys. 164 (2000), for the cube [0, 1]^3 and normal components m1 <= m2 <= m3
/// summing to 1), for the hot path of fresh cuts: a tenth of the cost of clipping.
double onePlane(const HalfSpace& p) {
  std::array<double, 3> m = {std::abs(p.n.x()), std::abs(p.n.y()), std::abs(p.n.z())};
  const double sum = m[0] + m[1] + m[2];
  // About the cube's corner where n . u is least: n . u <= a there reads m . x <= alpha.
  double alpha = (p.a + 0.5 * sum) / sum;
  for (double& v : m)
    v /= sum;
  std::sort(m.begin(), m.end());
  if (m[0] < 1e-9) m[0] = 0.0;  // a component this small changes the share by less
  if (m[1] < 1e-9) m[1] = 0.0;
  const bool upper = alpha > 0.5;  // by symmetry, the share above 1 - alpha
  if (upper) alpha = 1.0 - alpha;
  const double m1 = m[0], m2 = m[1], m3 = m[2], m12 = m1 + m2;
  double v = 0.0;
  if (alpha <= 0.0)
    v = 0.0;
  else if (alpha < m1)
    v = alpha * alpha * alpha / (6.0 * m1 * m2 * m3);
  else if (alpha < m2)
    v = alpha * (alpha - m1) / (2.0 * m2 * m3) + m1 * m1 / (6.0 * m2 * m3);
  else if (alpha < std::min(m12, m3))
    v = (alpha * alpha * (3.0 * m12 - alpha) + m1 * m1 * (m1 - 3.0 * alpha) +
         m2 * m2 * (m2 - 3.0 * alpha)) /
        (6.0 * m1 * m2 * m3);
  else if (m3 < m12)
    v = (alpha * alpha * (3.0 - 2.0 * alpha) + m1 * m1 * (m1 - 3.0 * alpha) +
         m2 * m2 * (m2 - 3.0 * alpha) + m3 * m3 * (m3 - 3.0 * alpha)) /
        (6.0 * m1 * m2 * m3);
  else
    v = (2.0 * alpha - m12) / (2.0 * m3);
  v = std::clamp(v, 0.0, 1.0);
  return upper ? 1.0 - v : v;
}

/// The unit cube clipped by three planes or more, as a convex polyhedron: each face a polygon
/// (counter-clockwise seen from outside) clipped by each plane in turn, the cap on the plane
/// from the new edges, and the volume (and with `moment` its first moment) from the
/// tetrahedra between the cube's centre and the faces' triangles. The six tetrahedra clipped
/// plane by plane split into up to three each per plane, which is slow with six to eight
/// planes (a flat end mill's rim on a 3D path, where up to eight corner planes bound the cut).
class Polyhedron {
 public:
  Polyhedron() {
    // The cube's faces, counter-clockwise seen from outside.
    static const int corners[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                      {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    auto corner = [](int c) {
      return Eigen::Vector3d((c & 1) ? 0.5 : -0.5, (c & 2) ? 0.5 : -0.5, (c & 4) ? 0.5 : -0.5);
    };
    faces_ = 6;
    for (int f = 0; f < 6; ++f) {
      size_[f] = 4;
      for (int k = 0; k < 4; ++k)
        v_[f][k] = corner(corners[f][k]);
    }
  }

  /// Keep {u : n . u <= a}. Points within 1e-12 of the plane count as kept, so that a plane
  /// that only touches the polyhedron (the same plane again, a face of the cube) changes
  /// nothing.
  void clip(const HalfSpace& p) {
    constexpr double kOn = 1e-12;
    bool cuts = false;
    for (int f = 0; f < faces_ && !cuts; ++f)
      for (int k = 0; k < size_[f] && !cuts; ++k)
        cuts = p.n.dot(v_[f][k]) - p.a > kOn;
    if (!cuts) return;
    Eigen::Vector3d cap[kMaxVertices * 2];
    int capSize = 0;
    int kept = 0;
    for (int f = 0; f < faces_; ++f) {
      Eigen::Vector3d out[kMaxVertices];
      int n = 0;
      const int m = size_[f];
      for (int k = 0; k < m; ++k) {
        const Eigen::Vector3d& P = v_[f][k];
        const Eigen::Vector3d& Q = v_[f][(k + 1) % m];
        const double sp = p.n.dot(P) - p.a, sq = p.n.dot(Q) - p.a;
        const bool pIn = sp <= kOn, qIn = sq <= kOn;
        if (pIn && n < kMaxVertices) out[n++] = P;
        if (pIn != qIn) {
          const Eigen::Vector3d x = P + (Q - P) * (sp / (sp - sq));
          if (n < kMaxVertices) out[n++] = x;
          if (capSize < kMaxVertices * 2) cap[capSize++] = x;
        }
      }
      if (n < 3) continue;
      size_[kept] = n;
      for (int k = 0; k < n; ++k)
        v_[kept][k] = out[k];
      ++kept;
    }
    faces_ = kept;
    if (kept == 0 || capSize < 3 || faces_ >= kMaxFaces) return;
    // The cap: its points (where the faces' edges cross the plane, a corner on it from each of
    // its edges) in order of angle about their mean, counter-clockwise about n (outward). A
    // pseudo-angle (monotonic in the angle) instead of atan2, which took 6 % of the loop.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int k = 0; k < capSize; ++k)
      mean += cap[k];
    mean /= capSize;
    const Eigen::Vector3d e1 = p.n.unitOrthogonal(), e2 = p.n.normalized().cross(e1);
    double angle[kMaxVertices * 2];
    int order[kMaxVertices * 2];
    for (int k = 0; k < capSize; ++k) {
      const Eigen::Vector3d d = cap[k] - mean;
      const double x = d.dot(e1), y = d.dot(e2), r = std::abs(x) + std::abs(y);
      const double t = r > 0.0 ? y / r : 0.0;  // in [-1, 1], rising with the angle in a half
      angle[k] = x >= 0.0 ? t : (y >= 0.0 ? 2.0 - t : -2.0 - t);
      order[k] = k;
    }
    std::sort(order, order + capSize, [&](int a, int b) { return angle[a] < angle[b]; });
    int n = 0;
    for (int k = 0; k < capSize && n < kMaxVertices; ++k) {
      const Eigen::Vector3d& x = cap[order[k]];
      if (n > 0 && (x - v_[faces_][n - 1]).squaredNorm() < 1e-24) continue;  // (a corner twice)
      v_[faces_][n++] = x;
    }
    if (n > 1 && (v_[faces_][n - 1] - v_[faces_][0]).squaredNorm() < 1e-24) --n;
    if (n >= 3) size_[faces_++] = n;
  }

  /// Volume, and with `moment` the first moment added to it.
  double volume(Eigen::Vector3d* moment) const {
    double sum = 0.0;
    for (int f = 0; f < faces_; ++f)
      for (int k = 1; k + 1 < size_[f]; ++k) {
        const Eigen::Vector3d &a = v_[f][0], &b = v_[f][k], &c = v_[f][k + 1];
        const double v = a.dot(b.cross(c)) / 6.0;
        sum += v;
        if (moment) *moment += v * (a + b + c) / 4.0;
      }
    return sum;
  }

 private:
  static constexpr int kMaxFaces = 6 + 9, kMaxVertices = 4 + 9 + 2;
  int faces_ = 0;
  int size_[kMaxFaces] = {};
  Eigen::Vector3d v_[kMaxFaces][kMaxVertices];
};

}  // namespace

double cubeFraction(const HalfSpace* planes, int count, Eigen::Vector3d* centroid) {
  // Planes that keep the whole cube are dropped, one that keeps none ends the search: most
  // calls then clip against one plane or none.
  std::array<HalfSpace, 9> active;
  int n = 0;
  for (int k = 0; k < count; ++k) {
    const HalfSpace& p = planes[k];
    const double reach = 0.5 * p.n.lpNorm<1>();  // max of n . u over the cube
    if (p.a >= reach) continue;
    if (p.a <= -reach) {
      if (centroid) centroid->setZero();
      return 0.0;
    }
    assert(n < static_cast<int>(active.size()));
    active[static_cast<std::size_t>(n++)] = p;
  }
  if (centroid) centroid->setZero();
  if (n == 0) return 1.0;
  if (n == 1 && !centroid) return onePlane(active[0]);
  // Three planes or more: the cube clipped as a polyhedron (for two, the tetrahedra and the
  // last plane's closed form are faster).
  if (n >= 3) {
    Polyhedron cut;
    for (int k = 0; k < n; ++k)
      cut.clip(active[static_cast<std::size_t>(k)]);
    const double sum = std::max(0.0, cut.volume(centroid));
    if (centroid && sum > 0.0) *centroid /= sum;
    if (centroid && !(sum > 0.0)) centroid->setZero();
    return sum;
  }
  static const std::array<Tet, 6> tets = kuhnTetrahedra();
  double sum = 0.0;
  for (const Tet& t : tets)
    sum += clipped(t, active.data(), n, centroid);
  if (centroid && sum > 0.0) *centroid /= sum;
  return sum;
}

double sectionMeanSquare(const HalfSpace& plane, const Eigen::Matrix3d& K) {
  const Eigen::Vector3d& n = plane.n;
  if (std::abs(plane.a) >= 0.5 * n.lpNorm<1>()) return 0.0;  // misses the cube
  // With `top` the axis of n's largest component and (x, y) the other two coordinates, the
  // plane is the lift u(x, y) = u0 + x g_x + y g_y of the (x, y) plane, and the section is
  // the lift of the unit square's part where |u_top| <= 1/2 (a strip): the square clipped by
  // two lines, a convex polygon in order. The lift's area element is constant, so the mean is
  // that of the quadratic q(x, y) = (u - f)^T K (u - f), f = a n, over that polygon: from its
  // area and first and second moments (Green's theorem). Most planes cross only the four
  // faces around `top`: the whole square, whose moments are 1, 0 and 1/12.
  int top = 0;
  n.cwiseAbs().maxCoeff(&top);
  const int ix = (top + 1) % 3, iy = (top + 2) % 3;
  Eigen::Vector3d u0 = Eigen::Vector3d::Zero(), gx = Eigen::Vector3d::Zero(), gy = gx;
  u0[top] = plane.a / n[top];
  gx[ix] = 1.0;
  gx[top] = -n[ix] / n[top];
  gy[iy] = 1.0;
  gy[top] = -n[iy] / n[top];
  const Eigen::Vector3d r = u0 - plane.a * n;
  const Eigen::Vector3d Kr = K * r, Kgx = K * gx, Kgy = K * gy;
  // q = c0 + 2 (bx x + by y) + mxx x^2 + 2 mxy x y + myy y^2
  const double c0 = r.dot(Kr), bx = gx.dot(Kr), by = gy.dot(Kr);
  const double mxx = gx.dot(Kgx), mxy = gx.dot(Kgy), myy = gy.dot(Kgy);
  if (std::abs(plane.a) + 0.5 * (std::abs(n[ix]) + std::abs(n[iy])) <= 0.5 * std::abs(n[top]))
    return c0 + (mxx + myy) / 12.0;
  // u_top = u0_top + x gx_top + y gy_top within [-1/2, 1/2]: clip the square by both sides.
  std::array<Eigen::Vector2d, 8> buffer[2];
  buffer[0] = {Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(0.5, -0.5), Eigen::Vector2d(0.5, 0.5),
               Eigen::Vector2d(-0.5, 0.5)};
  int size = 4, from = 0;
  const Eigen::Vector2d g(gx[top], gy[top]);
  for (const double side : {1.0, -1.0}) {  // side * (u0_top + g . (x, y)) <= 1/2
    const auto& in = buffer[from];
    auto& out = buffer[1 - from];
    int m = 0;
    for (int i = 0; i < size; ++i) {
      const Eigen::Vector2d& p = in[static_cast<std::size_t>(i)];
      const Eigen::Vector2d& q = in[static_cast<std::size_t>(i + 1 == size ? 0 : i + 1)];
      const double sp = side * (u0[top] + g.dot(p)) - 0.5, sq = side * (u0[top] + g.dot(q)) - 0.5;
      if (sp <= 0.0) out[static_cast<std::size_t>(m++)] = p;
      if ((sp <= 0.0) != (sq <= 0.0))
        out[static_cast<std::size_t>(m++)] = p + (q - p) * (sp / (sp - sq));
    }
    size = m;
    from = 1 - from;
  }
  // Twice the area; 6 x the first moments; 12 x the second (24 x for x y).
  double area = 0.0, sx = 0.0, sy = 0.0, xx = 0.0, yy = 0.0, xy = 0.0;
  const auto& poly = buffer[from];
  for (int i = 0; i < size; ++i) {
    const Eigen::Vector2d& p = poly[static_cast<std::size_t>(i)];
    const Eigen::Vector2d& q = poly[static_cast<std::size_t>(i + 1 == size ? 0 : i + 1)];
    const double cross = p.x() * q.y() - q.x() * p.y();
    area += cross;
    sx += cross * (p.x() + q.x());
    sy += cross * (p.y() + q.y());
    xx += cross * (p.x() * p.x() + p.x() * q.x() + q.x() * q.x());
    yy += cross * (p.y() * p.y() + p.y() * q.y() + q.y() * q.y());
    xy += cross * (2.0 * p.x() * p.y() + p.x() * q.y() + q.x() * p.y() + 2.0 * q.x() * q.y());
  }
  if (!(area > 0.0)) return 0.0;
  const double A = area / 2.0;
  return c0 + 2.0 * (bx * sx + by * sy) / 6.0 / A +
         (mxx * xx / 12.0 + 2.0 * mxy * xy / 24.0 + myy * yy / 12.0) / A;
}

/// The plane with outward normal n that leaves `share` of the unit cube inside: the share
/// grows with the offset; regula falsi (Illinois) to 1e-9 of the share.
HalfSpace planeLeaving(const Eigen::Vector3d& n, double share) {
  double lo = -0.5 * n.lpNorm<1>(), hi = -lo;
  double flo = -share, fhi = 1.0 - share;
  double a = 0.0;
  int side = 0;
  for (int i = 0; i < 60; ++i) {
    a = (lo * fhi - hi * flo) / (fhi - flo);
    const double f = cubeFraction(HalfSpace{n, a}) - share;
    if (std::abs(f) < 1e-9) break;
    if (f < 0.0) {
      lo = a;
      flo = f;
      if (side == -1) fhi /= 2.0;
      side = -1;
    } else {
      hi = a;
      fhi = f;
      if (side == 1) flo /= 2.0;
      side = 1;
    }
  }
  return HalfSpace{n, a};
}

}  // namespace engage
