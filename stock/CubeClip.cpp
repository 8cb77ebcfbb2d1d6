#include "stock/CubeClip.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include <Eigen/Geometry>

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
  if (count == 1 && !(moment && nin == 2)) {
    // The last plane: the share of the tetrahedron below it in closed form (the distribution
    // of a linear function over a tetrahedron), with x = -s at the inside vertices and
    // C, D, E = s at the outside ones: one inside, x^3 / ((C + x)(D + x)(E + x)); three
    // inside, one less the outside corner's share; two inside,
    // (C D (x^2 + x y + y^2) + (C + D) x y (x + y) + x^2 y^2) / ((C + x)(D + x)(C + y)(D + y)).
    auto at = [&](int i) { return s[static_cast<std::size_t>(i)]; };
    auto v = [&](int i) { return t[static_cast<std::size_t>(i)]; };
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
  auto v = [&](int i) { return t[static_cast<std::size_t>(i)]; };
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

}  // namespace

double cubeFraction(const HalfSpace* planes, int count, Eigen::Vector3d* centroid) {
  // Planes that keep the whole cube are dropped, one that keeps none ends the search: most
  // calls then clip against one plane or none.
  std::array<HalfSpace, 8> active;
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
  // The section's corners are where the plane crosses the cube's edges (n . u - a changes
  // sign along them), taken in the plane's coordinates (x, y) along t1, t2 from the foot
  // f = a n and ordered by angle about their mean; then the polygon's area and second
  // moments in closed form (Green's theorem).
  const Eigen::Vector3d f = plane.a * n;
  // Most planes cross only the four faces around the axis k of n's largest component: the
  // section is the unit square of the other two coordinates (x, y) lifted onto the plane,
  // uniform in (x, y), so the mean is that of a quadratic over the square: at its centre
  // u0, plus (g_x^T K g_x + g_y^T K g_y) / 12 with g the lift's derivatives.
  int top = 0;
  n.cwiseAbs().maxCoeff(&top);
  const int x = (top + 1) % 3, y = (top + 2) % 3;
  if (std::abs(plane.a) + 0.5 * (std::abs(n[x]) + std::abs(n[y])) <= 0.5 * std::abs(n[top])) {
    Eigen::Vector3d u0 = Eigen::Vector3d::Zero(), gx = Eigen::Vector3d::Zero(), gy = gx;
    u0[top] = plane.a / n[top];
    gx[x] = 1.0;
    gx[top] = -n[x] / n[top];
    gy[y] = 1.0;
    gy[top] = -n[y] / n[top];
    const Eigen::Vector3d r = u0 - f;
    return r.dot(K * r) + (gx.dot(K * gx) + gy.dot(K * gy)) / 12.0;
  }
  const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  std::array<Eigen::Vector2d, 12> corner;  // six, or more where the plane meets a vertex
  int size = 0;
  for (int axis = 0; axis < 3; ++axis) {
    // The four edges along `axis`: the other two coordinates at +-1/2.
    const int j = (axis + 1) % 3, k = (axis + 2) % 3;
    for (const double uj : {-0.5, 0.5})
      for (const double uk : {-0.5, 0.5}) {
        const double rest = n[j] * uj + n[k] * uk - plane.a;  // n . u - a at u_axis = 0
        const double s0 = rest - 0.5 * n[axis], s1 = rest + 0.5 * n[axis];
        if ((s0 <= 0.0) == (s1 <= 0.0)) continue;
        Eigen::Vector3d u;
        u[axis] = -0.5 + s0 / (s0 - s1);
        u[j] = uj;
        u[k] = uk;
        corner[static_cast<std::size_t>(size++)] = {(u - f).dot(t1), (u - f).dot(t2)};
      }
  }
  if (size < 3) return 0.0;
  Eigen::Vector2d mid = Eigen::Vector2d::Zero();
  for (int i = 0; i < size; ++i)
    mid += corner[static_cast<std::size_t>(i)];
  mid /= size;
  // Pseudo-angle about the mean, in [0, 4): monotone in the angle, without atan2.
  std::array<double, 12> key;
  for (int i = 0; i < size; ++i) {
    const Eigen::Vector2d d = corner[static_cast<std::size_t>(i)] - mid;
    const double r = d.y() / (std::abs(d.x()) + std::abs(d.y()) + 1e-300);
    key[static_cast<std::size_t>(i)] = d.x() >= 0.0 ? 1.0 - r : 3.0 + r;
  }
  for (int i = 1; i < size; ++i)  // insertion sort of a few
    for (int m = i;
         m > 0 && key[static_cast<std::size_t>(m - 1)] > key[static_cast<std::size_t>(m)]; --m) {
      std::swap(key[static_cast<std::size_t>(m - 1)], key[static_cast<std::size_t>(m)]);
      std::swap(corner[static_cast<std::size_t>(m - 1)], corner[static_cast<std::size_t>(m)]);
    }
  double area = 0.0, xx = 0.0, yy = 0.0, xy = 0.0;
  for (int i = 0; i < size; ++i) {
    const Eigen::Vector2d& p = corner[static_cast<std::size_t>(i)];
    const Eigen::Vector2d& q = corner[static_cast<std::size_t>(i + 1 == size ? 0 : i + 1)];
    const double c = p.x() * q.y() - q.x() * p.y();
    area += c;
    xx += c * (p.x() * p.x() + p.x() * q.x() + q.x() * q.x());
    yy += c * (p.y() * p.y() + p.y() * q.y() + q.y() * q.y());
    xy += c * (2.0 * p.x() * p.y() + p.x() * q.y() + q.x() * p.y() + 2.0 * q.x() * q.y());
  }
  if (!(std::abs(area) > 0.0)) return 0.0;
  // area / 2, xx / 12, yy / 12, xy / 24 are the area and the integrals of x^2, y^2, x y.
  const double k11 = t1.dot(K * t1), k22 = t2.dot(K * t2), k12 = t1.dot(K * t2);
  return (k11 * xx / 12.0 + k22 * yy / 12.0 + 2.0 * k12 * xy / 24.0) / (area / 2.0);
}

}  // namespace engage
