#pragma once
// Cuts whose contact with a flat end mill is known in closed form, made in a real stock and
// measured with engine/physics/Engagement.h: shared by tests/engine/physics (the assertions)
// and tests/bench/bench_contact.cpp (the figures docs/accuracy.md quotes).

#include "cutters/Numbers.h"
#include "cutters/Sweep.h"
#include "engine/physics/Engagement.h"
#include "engine/physics/Material.h"
#include "tests/stock/StockTestSupport.h"

#include <cmath>
#include <memory>
#include <string>

namespace engage::test {

/// A straight side cut along +X of a flat end mill of radius R, axial depth ap, radial depth
/// ae (2 R: a slot), the stock on the cutter's left (+Y: up milling under M3) or right (down
/// milling), in a block whose top lies `top` cells above a grid line and whose side face (the
/// wall the contact ends at) lies `across` cells off one. The contact at the pass's end.
inline EdgeEngagement straightContact(const std::string& model, double h, double R, double ap,
                                      double ae, bool left, double top, double across) {
  Box3 b;
  b.min = {-30, -20, -20};
  b.max = {30, 20, top * h};
  const double yc = across * h;
  if (ae < 2 * R) {
    if (left)
      b.min.y() = yc + R - ae;
    else
      b.max.y() = yc - R + ae;
  }
  std::unique_ptr<Stock> s = boxStock(model, b, h);
  const AptCutter flat = AptCutter::flat(2 * R, 20.0);
  const Eigen::Vector3d end(0.0, yc, b.max.z() - ap);
  s->remove(Sweep(flat, line(end - Eigen::Vector3d(40.0, 0, 0), end), h));
  return measureEngagement(*s, flat, end, {1.0, 0.0}, true, ap + h);
}

/// The immersion angles (Engagement.h) of straightContact's cut: [0, acos(1 - ae/R)] up
/// milling, [pi - acos(1 - ae/R), pi] down milling.
inline std::array<double, 2> straightAngles(double R, double ae, bool left) {
  const double arc = std::acos(std::max(-1.0, 1.0 - ae / R));
  return left ? std::array<double, 2>{0.0, arc} : std::array<double, 2>{kPi - arc, kPi};
}

/// A full circle of tool-centre radius rho1 about `centre`, then three quarters of a turn at
/// radius rho (both clockwise or both counter-clockwise, from angle 0, in arc pieces 2.5
/// cells long), a flat end mill of radius R at depth ap in a block; the contact at the second
/// arc's end (M3).
inline EdgeEngagement arcContact(const std::string& model, double h, double R, double ap,
                                 double rho, double rho1, bool clockwise,
                                 const Eigen::Vector3d& centre) {
  Box3 b;
  b.min = {-50, -50, -10};
  b.max = {50, 50, 0};
  std::unique_ptr<Stock> s = boxStock(model, b, h);
  const AptCutter flat = AptCutter::flat(2 * R, 20.0);
  const double L = 2.5 * h;
  const Eigen::Vector3d c(centre.x(), centre.y(), -ap);
  auto circle = [&](double radius, double turn) {
    const int n = static_cast<int>(std::ceil(turn * radius / L));
    for (int k = 0; k < n; ++k) {
      const double a0 = turn * k / n, a1 = turn * (k + 1) / n;
      s->remove(
          Sweep(flat, clockwise ? arc(c, radius, -a0, -a1, -ap) : arc(c, radius, a0, a1, -ap), h));
    }
    const double a = clockwise ? -turn : turn;
    return Eigen::Vector3d(c.x() + radius * std::cos(a), c.y() + radius * std::sin(a), -ap);
  };
  circle(rho1, 2 * kPi);
  const Eigen::Vector3d tip = circle(rho, 1.5 * kPi);
  const Eigen::Vector2d radial = (tip - c).head<2>().normalized();
  const Eigen::Vector2d feed = clockwise ? Eigen::Vector2d(radial.y(), -radial.x())
                                         : Eigen::Vector2d(-radial.y(), radial.x());
  return measureEngagement(*s, flat, tip, feed, true, ap + h, (clockwise ? -1.0 : 1.0) / rho);
}

/// The immersion angles of arcContact's cut with stepover ae (concave: the stock outside,
/// rho1 = rho - ae; convex: inside, rho1 = rho + ae). The previous wall is the circle of
/// radius Rw = rho1 + R (concave) or rho1 - R (convex); the edge meets it at theta from the
/// outward radial, cos(theta) = (Rw^2 - rho^2 - R^2) / (2 rho R). Under M3 phi runs from the
/// left of the feed through its front: the left is outward for clockwise travel (the wall at
/// phi = theta), inward for counter-clockwise (pi - theta); the contact runs from the stock's
/// side (phi = 0 on the left, pi on the right) to the wall.
inline std::array<double, 2> arcAngles(double R, double rho, double ae, bool concave,
                                       bool clockwise) {
  const double rho1 = concave ? rho - ae : rho + ae;
  const double wall = concave ? rho1 + R : rho1 - R;
  const double theta = std::acos((wall * wall - rho * rho - R * R) / (2.0 * rho * R));
  const bool leftIsOut = clockwise;
  const double boundary = leftIsOut ? theta : kPi - theta;
  return concave == leftIsOut ? std::array<double, 2>{0.0, boundary}
                              : std::array<double, 2>{boundary, kPi};
}

/// Mean forces (N) and torque (N m) per revolution of a straight-toothed flat end mill (N
/// teeth, radius R) at axial depth a and feed per tooth c, immersion [st, ex], under the
/// linear edge-force model: the textbook integrals (Altintas, Manufacturing Automation, 2nd
/// ed., Eq 2.40), x along the feed, y to the side phi = 0:
///   Fx = N a c / (8 pi) [Ktc cos 2phi - Krc (2phi - sin 2phi)] + N a / (2 pi) [-Kte sin phi
///        + Kre cos phi]
///   Fy = N a c / (8 pi) [Ktc (2phi - sin 2phi) + Krc cos 2phi] - N a / (2 pi) [Kte cos phi
///        + Kre sin phi]
///   Fz = N a / (2 pi) [-Kac c cos phi + Kae phi],  T = N a R / (2 pi) [-Ktc c cos phi + Kte phi]
/// each evaluated from st to ex.
struct MeanLoad {
  double fx, fy, fz, torque;
};

inline MeanLoad linearMeanLoad(const LinearCoefficients& k, int N, double a, double c, double R,
                               double st, double ex) {
  auto fx = [&](double p) {
    return N * a * c / (8 * kPi) * (k.Ktc * std::cos(2 * p) - k.Krc * (2 * p - std::sin(2 * p))) +
           N * a / (2 * kPi) * (-k.Kte * std::sin(p) + k.Kre * std::cos(p));
  };
  auto fy = [&](double p) {
    return N * a * c / (8 * kPi) * (k.Ktc * (2 * p - std::sin(2 * p)) + k.Krc * std::cos(2 * p)) -
           N * a / (2 * kPi) * (k.Kte * std::cos(p) + k.Kre * std::sin(p));
  };
  auto fz = [&](double p) { return N * a / (2 * kPi) * (-k.Kac * c * std::cos(p) + k.Kae * p); };
  auto t = [&](double p) { return N * a * R / (2 * kPi) * (-k.Ktc * c * std::cos(p) + k.Kte * p); };
  return {fx(ex) - fx(st), fy(ex) - fy(st), fz(ex) - fz(st), (t(ex) - t(st)) / 1000.0};
}

}  // namespace engage::test
