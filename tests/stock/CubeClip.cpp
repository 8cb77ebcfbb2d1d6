// Tests of stock/CubeClip.h: the volume of the unit cube cut by planes, against closed forms
// and against counting the points of a fine lattice.

#include "stock/CubeClip.h"

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

using namespace engage;

namespace {

HalfSpace plane(double x, double y, double z, double a) {
  const Eigen::Vector3d n(x, y, z);
  return {n.normalized(), a};
}

/// Share of the midpoints of an N^3 lattice of the cube inside all planes.
double latticeFraction(const HalfSpace* planes, int count, int n) {
  long inside = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d u((i + 0.5) / n - 0.5, (j + 0.5) / n - 0.5, (k + 0.5) / n - 0.5);
        bool in = true;
        for (int p = 0; p < count && in; ++p)
          in = planes[p].n.dot(u) <= planes[p].a;
        inside += in;
      }
  return static_cast<double>(inside) / (static_cast<double>(n) * n * n);
}

}  // namespace

TEST_CASE("one plane: slabs, the diagonal and a corner", "[stock]") {
  // Rounding only: 1e-12.
  CHECK(cubeFraction(plane(1, 0, 0, 0.2)) == Approx(0.7).margin(1e-12));
  CHECK(cubeFraction(plane(0, -1, 0, 0.2)) == Approx(0.7).margin(1e-12));
  CHECK(cubeFraction(plane(0, 0, 1, 0.6)) == 1.0);
  CHECK(cubeFraction(plane(0, 0, 1, -0.6)) == 0.0);
  // Through the centre, by symmetry half, in any direction.
  CHECK(cubeFraction(plane(1, 1, 1, 0.0)) == Approx(0.5).margin(1e-12));
  CHECK(cubeFraction(plane(0.3, -0.7, 0.2, 0.0)) == Approx(0.5).margin(1e-12));
  // x + y + z <= -3/2 + t cuts off the corner tetrahedron t^3 / 6 (t <= 1).
  const double t = 0.8;
  CHECK(cubeFraction(plane(1, 1, 1, (-1.5 + t) / std::sqrt(3.0))) ==
        Approx(t * t * t / 6.0).margin(1e-12));
  // x + y <= -1 + t: a prism of triangle t^2 / 2 and height 1.
  CHECK(cubeFraction(plane(1, 1, 0, (-1.0 + t) / std::sqrt(2.0))) ==
        Approx(t * t / 2.0).margin(1e-12));
  // The keep-all half-space.
  CHECK(cubeFraction(HalfSpace{}) == 1.0);
}

TEST_CASE("two planes: quadrants, a slab, a wedge", "[stock]") {
  const HalfSpace x0 = plane(1, 0, 0, 0.0), y0 = plane(0, 1, 0, 0.0);
  const HalfSpace quadrant[] = {x0, y0};
  CHECK(cubeFraction(quadrant, 2) == Approx(0.25).margin(1e-12));
  const HalfSpace slab[] = {plane(1, 0, 0, 0.1), plane(1, 0, 0, -0.2).complement()};
  CHECK(cubeFraction(slab, 2) == Approx(0.3).margin(1e-12));
  // |y| <= x: a quarter of the cube about the x axis.
  const HalfSpace wedge[] = {plane(-1, 1, 0, 0.0), plane(-1, -1, 0, 0.0)};
  CHECK(cubeFraction(wedge, 2) == Approx(0.25).margin(1e-12));
  // Disjoint half-spaces keep nothing.
  const HalfSpace none[] = {plane(1, 0, 0, -0.1), plane(-1, 0, 0, -0.1)};
  CHECK(cubeFraction(none, 2) == 0.0);
}

TEST_CASE("random planes: complements add up, and a lattice count agrees", "[stock]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const HalfSpace p = plane(U(rng), U(rng), U(rng), 0.6 * U(rng));
    const HalfSpace q = plane(U(rng), U(rng), U(rng), 0.6 * U(rng));
    const HalfSpace pq[] = {p, q}, pnq[] = {p, q.complement()};
    // Splitting by a plane loses nothing: rounding only.
    CHECK(cubeFraction(p) + cubeFraction(p.complement()) == Approx(1.0).margin(1e-12));
    CHECK(cubeFraction(pq, 2) + cubeFraction(pnq, 2) == Approx(cubeFraction(p)).margin(1e-12));
    if (trial % 20 == 0) {
      // A 100^3 lattice: each plane's cells on the boundary (up to 3 x 100^2 of 100^3) count
      // half in or out on average; 0.5 % bounds the lattice's error.
      const HalfSpace three[] = {p, q, plane(U(rng), U(rng), U(rng), 0.3)};
      CHECK(cubeFraction(three, 3) == Approx(latticeFraction(three, 3, 100)).margin(0.005));
    }
  }
}

TEST_CASE("one plane: the closed form agrees with clipping", "[stock]") {
  // cubeFraction takes the closed form for one plane; two planes with the second keeping all
  // of the cube also go that way, so clip instead with the plane split into two halves of
  // the cube (x <= 0 and x >= 0), each clipped by tetrahedra.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    // Some normals along axes and diagonals, where the closed form has its special cases.
    Eigen::Vector3d n(U(rng), U(rng), U(rng));
    if (trial % 5 == 1) n.x() = 0.0;
    if (trial % 5 == 2) n.y() = n.z() = 0.0;
    if (trial % 5 == 3) n.y() = n.x();
    const HalfSpace p = plane(n.x(), n.y(), n.z(), 0.9 * U(rng));
    const HalfSpace left[] = {p, plane(1, 0, 0, 0.0)}, right[] = {p, plane(-1, 0, 0, 0.0)};
    // Rounding only.
    CHECK(cubeFraction(p) == Approx(cubeFraction(left, 2) + cubeFraction(right, 2)).margin(1e-9));
  }
}

TEST_CASE("three planes and more: boxes, the same plane twice, and splits that add up", "[stock]") {
  // x <= a, y <= b, z <= c: a box (a + 1/2)(b + 1/2)(c + 1/2) centred at ((a - 1/2) / 2, ...).
  // Rounding only: 1e-12.
  const double a = 0.1, b = -0.2, c = 0.35;
  const HalfSpace box[] = {plane(1, 0, 0, a), plane(0, 1, 0, b), plane(0, 0, 1, c)};
  Eigen::Vector3d centroid;
  CHECK(cubeFraction(box, 3, &centroid) == Approx((a + 0.5) * (b + 0.5) * (c + 0.5)).margin(1e-12));
  CHECK((centroid - Eigen::Vector3d((a - 0.5) / 2, (b - 0.5) / 2, (c - 0.5) / 2)).norm() < 1e-12);
  // The same plane three times, and planes through the cube's corners and edges: as once.
  const HalfSpace diagonal = plane(1, 1, 1, (-1.5 + 0.8) / std::sqrt(3.0));
  const HalfSpace thrice[] = {diagonal, diagonal, diagonal};
  CHECK(cubeFraction(thrice, 3) == Approx(0.8 * 0.8 * 0.8 / 6.0).margin(1e-12));
  const HalfSpace throughEdges[] = {plane(1, 1, 0, 0.0), plane(1, -1, 0, 0.0), plane(0, 0, 1, 0.5)};
  CHECK(cubeFraction(throughEdges, 3) == Approx(0.25).margin(1e-12));  // x <= -|y|
  // A slab of no width keeps nothing.
  const HalfSpace flat[] = {plane(2, 1, 0, 0.1), plane(2, 1, 0, 0.1).complement(),
                            plane(0, 0, 1, 0.2)};
  CHECK(cubeFraction(flat, 3) == Approx(0.0).margin(1e-12));
  // Random sets of 3 to 8 planes: split by one more plane and its complement, the parts add up
  // to the whole, with centroids that add up as moments (each part clipped on its own).
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 3 + trial % 6;
    HalfSpace with[9], without[9];
    for (int k = 0; k < n - 1; ++k)
      with[k] = without[k] = plane(U(rng), U(rng), U(rng), 0.45 * U(rng));
    const HalfSpace split = plane(U(rng), U(rng), U(rng), 0.3 * U(rng));
    with[n - 1] = split;
    without[n - 1] = split.complement();
    Eigen::Vector3d c0, c1, c2;
    const double whole = cubeFraction(with, n - 1, &c0);
    const double in = cubeFraction(with, n, &c1), out = cubeFraction(without, n, &c2);
    CHECK(in + out == Approx(whole).margin(1e-12));
    CHECK((in * c1 + out * c2 - whole * c0).norm() < 1e-12);
  }
}

TEST_CASE("centroids of the clipped part", "[stock]") {
  // Half the cube, x <= 0: centroid at x = -1/4. The corner tetrahedron x + y + z <= -3/2 + t:
  // centroid a quarter of the way from the corner to the plane, -1/2 + t/4 on each axis.
  Eigen::Vector3d c;
  const HalfSpace half = plane(1, 0, 0, 0.0);
  CHECK(cubeFraction(&half, 1, &c) == Approx(0.5).margin(1e-12));
  CHECK((c - Eigen::Vector3d(-0.25, 0, 0)).norm() < 1e-12);
  const double t = 0.6;
  const HalfSpace corner = plane(1, 1, 1, (-1.5 + t) / std::sqrt(3.0));
  cubeFraction(&corner, 1, &c);
  CHECK((c - Eigen::Vector3d::Constant(-0.5 + t / 4)).norm() < 1e-12);
  const HalfSpace keepAll;
  CHECK(cubeFraction(&keepAll, 1, &c) == 1.0);
  CHECK(c.norm() == 0.0);
}

TEST_CASE("mean square distance from the foot over a plane's section", "[stock]") {
  // With K = I: the unit square about its centre, 1/12 + 1/12 (any height); the diagonal
  // plane x = y, a sqrt(2) x 1 rectangle through two cube edges, 2/12 + 1/12; the small
  // triangle x + y + z = 3/2 - 3 d cut off a corner, equilateral with side 3 sqrt(2) d and
  // its centroid at the foot, s^2 / 12 = 3 d^2 / 2. With K = e_x e_x^T on the square, 1/12.
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  CHECK(sectionMeanSquare(plane(0, 0, 1, 0.3), I) == Approx(1.0 / 6.0).epsilon(1e-12));
  CHECK(sectionMeanSquare(plane(1, -1, 0, 0.0), I) == Approx(0.25).epsilon(1e-12));
  const double d = 0.05;
  CHECK(sectionMeanSquare(plane(1, 1, 1, (1.5 - 3 * d) / std::sqrt(3.0)), I) ==
        Approx(1.5 * d * d).epsilon(1e-9));
  Eigen::Matrix3d xx = Eigen::Matrix3d::Zero();
  xx(0, 0) = 1.0;
  CHECK(sectionMeanSquare(plane(0, 0, -1, -0.2), xx) == Approx(1.0 / 12.0).epsilon(1e-12));
  CHECK(sectionMeanSquare(plane(0, 0, 1, 0.6), I) == 0.0);  // misses the cube
  // Through the centre normal to a diagonal: the regular hexagon of side sqrt(2)/2, whose
  // polar moment per area about its centre is 5 s^2 / 12.
  CHECK(sectionMeanSquare(plane(1, 1, 1, 0.0), I) == Approx(5.0 / 24.0).epsilon(1e-12));
}

TEST_CASE("mean square over random sections agrees with a fine grid on the plane", "[stock]") {
  // The mean of (u - f)^T K (u - f) over the points of a 600 x 600 grid of the plane's
  // square [-1, 1]^2 (about the foot, larger than any section) that fall in the cube: the
  // grid's error is at the section's boundary, about one grid step (1/300) relative.
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const HalfSpace h = plane(normal(rng), normal(rng), normal(rng), 0.0);
    const HalfSpace p{h.n, unit(rng) * 0.45 * h.n.lpNorm<1>()};
    Eigen::Matrix3d A;
    for (int i = 0; i < 9; ++i)
      A(i / 3, i % 3) = normal(rng);
    const Eigen::Matrix3d K = A + A.transpose();
    const Eigen::Vector3d f = p.a * p.n;
    const Eigen::Vector3d t1 = p.n.unitOrthogonal(), t2 = p.n.cross(t1);
    double sum = 0.0, scale = 0.0;
    double count = 0.0;
    const int n = 600;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const Eigen::Vector3d d =
            (2.0 * (i + 0.5) / n - 1.0) * t1 + (2.0 * (j + 0.5) / n - 1.0) * t2;
        const Eigen::Vector3d u = f + d;
        if (u.cwiseAbs().maxCoeff() > 0.5) continue;
        sum += d.dot(K * d);
        scale += d.squaredNorm();
        count += 1.0;
      }
    INFO("trial " << trial);
    // Relative to the mean of |u - f|^2 times |K| (the quadratic form can pass through 0).
    CHECK(std::abs(sectionMeanSquare(p, K) - sum / count) <= 0.01 * K.norm() * scale / count);
  }
}
