// Tests of engine/physics/CuttingForces.h against the textbook integrals of the linear
// edge-force model of a flat end mill (tests/support/ContactCases.h, linearMeanLoad), and of
// Kienzle's model, given the contact and with the contact read in a cut stock.

#include "engine/physics/CuttingForces.h"

#include "cutters/Numbers.h"
#include "cutters/Sweep.h"
#include "stock/DexelStock.h"
#include "tests/support/ContactCases.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>

using namespace engage;

namespace {
constexpr double a = 3.0, c = 0.1, R = 5.0;
constexpr int N = 3;

Material linearMaterial() {
  Material m;
  m.model = ForceModel::Linear;
  // Al 7075-T6 (data/materials/aluminium-7075-t6.json); any positive set would do.
  m.linear = {767.01, 168.8, 222.0, 27.7, 26.6, 0.7};
  return m;
}

/// A cylinder's contact over depth `depth` in `slices` slices, one arc [st, ex].
EdgeEngagement cylinder(double st, double ex, double depth = a, int slices = 12) {
  EdgeEngagement e;
  e.feed = {1.0, 0.0};
  e.side = {0.0, 1.0};
  e.entry = st;
  e.exit = ex;
  for (int k = 0; k < slices; ++k) {
    EdgeSlice s;
    s.dz = depth / slices;
    s.z = (k + 0.5) * s.dz;
    s.radius = R;
    s.kappa = kPi / 2;
    s.arcs.push_back({st, ex});
    e.slices.push_back(s);
  }
  return e;
}

using Closed = test::MeanLoad;

Closed closedForm(const LinearCoefficients& k, double st, double ex) {
  return test::linearMeanLoad(k, N, a, c, R, st, ex);
}

}  // namespace

TEST_CASE("mean forces and torque of a slot and of half immersion up and down milling",
          "[physics]") {
  const Material m = linearMaterial();
  const double rpm = 10000.0;
  struct Case {
    const char* name;
    double st, ex;
  };
  for (const Case& k : {Case{"slot", 0.0, kPi}, Case{"half immersion up milling", 0.0, kPi / 2},
                        Case{"half immersion down milling", kPi / 2, kPi}}) {
    CAPTURE(k.name);
    const StepLoad load = cuttingLoad(cylinder(k.st, k.ex), m, {N, 0.0, R}, c, rpm);
    const Closed want = closedForm(m.linear, k.st, k.ex);
    // Gauss-Legendre on trigonometric integrands: exact to round-off (1e-9 relative).
    CHECK(load.force.x() == Approx(want.fx).epsilon(1e-9).margin(1e-9));
    CHECK(load.force.y() == Approx(want.fy).epsilon(1e-9).margin(1e-9));
    CHECK(load.force.z() == Approx(want.fz).epsilon(1e-9).margin(1e-9));
    CHECK(load.torque == Approx(want.torque).epsilon(1e-9));
    // Power = T omega.
    CHECK(load.power == Approx(want.torque * 2 * kPi * rpm / 60.0).epsilon(1e-9));
    CHECK(load.hMax == Approx(c).epsilon(1e-12));  // every case reaches phi = pi/2
  }
  // The slot's hand values (N = 3, a = 3 mm, c = 0.1 mm): Fx = -N a Krc c / 4 - 0 (edge terms
  // cancel: -Kte (sin pi - sin 0) + Kre (cos pi - cos 0) -> -2 Kre N a / (2 pi)).
  const StepLoad slot = cuttingLoad(cylinder(0.0, kPi), m, {N, 0.0, R}, c, rpm);
  CHECK(slot.force.x() ==
        Approx(-N * a * c * 168.8 / 4.0 - N * a * 26.6 / kPi).epsilon(1e-9));  // -139.75 N
}

TEST_CASE("a slice's own feed, scaled and turned: the chip of arcs turned with it", "[physics]") {
  // A slice whose feed per tooth is s times the step's, turned by beta towards `side`
  // (EdgeSlice::feedShare = s (cos beta, sin beta): a tool whose axis turns), cuts at phi the
  // chip c s sin(phi + beta): the step's own feed at c s over the arcs turned by beta. So its
  // torque, largest and mean chip are theirs, and its mean force theirs turned about the axis
  // (the same across it and along it). Round-off: 1e-9.
  const Material m = linearMaterial();
  for (const double beta : {0.0, 0.3, -0.4, 1.2})
    for (const double s : {1.5, 0.7}) {
      CAPTURE(beta, s);
      EdgeEngagement e = cylinder(0.2, 2.0);
      for (EdgeSlice& slice : e.slices)
        slice.feedShare = s * Eigen::Vector2d(std::cos(beta), std::sin(beta));
      const StepLoad load = cuttingLoad(e, m, {N, 0.0, R}, c, 10000.0);
      const StepLoad want =
          cuttingLoad(cylinder(0.2 + beta, 2.0 + beta), m, {N, 0.0, R}, c * s, 10000.0);
      CHECK(load.torque == Approx(want.torque).epsilon(1e-9));
      CHECK(load.hMax == Approx(want.hMax).epsilon(1e-12));
      CHECK(load.hMean == Approx(want.hMean).epsilon(1e-9));
      CHECK(load.force.z() == Approx(want.force.z()).epsilon(1e-9));
      CHECK(load.force.head<2>().norm() == Approx(want.force.head<2>().norm()).epsilon(1e-9));
    }
  // Turned by 1.2 rad the arcs reach past pi, where the chip is 0: h_max c s (at phi + beta =
  // pi/2, inside [1.4, 3.2]).
  EdgeEngagement e = cylinder(0.2, 2.0);
  for (EdgeSlice& slice : e.slices)
    slice.feedShare = 0.7 * Eigen::Vector2d(std::cos(1.2), std::sin(1.2));
  CHECK(cuttingLoad(e, m, {N, 0.0, R}, c, 10000.0).hMax == Approx(0.7 * c).epsilon(1e-12));
}

TEST_CASE("chip thinning of a 10 % side cut and the mean chip thickness", "[physics]") {
  const Material m = linearMaterial();
  const double D = 2 * R, ae = 0.1 * D;
  const double ex = std::acos(1.0 - 2.0 * ae / D);
  const StepLoad load = cuttingLoad(cylinder(0.0, ex), m, {N, 0.0, R}, c, 10000.0);
  // h_max = f_z 2 sqrt(ae (D - ae)) / D = 0.6 f_z.
  CHECK(load.hMax == Approx(c * 2.0 * std::sqrt(ae * (D - ae)) / D).epsilon(1e-12));
  // h_mean over the arc: c (1 - cos ex) / ex.
  CHECK(load.hMean == Approx(c * (1.0 - std::cos(ex)) / ex).epsilon(1e-9));
}

TEST_CASE("the peak resultant of a straight-toothed slot and the helix's effect", "[physics]") {
  const Material m = linearMaterial();
  const LinearCoefficients& k = m.linear;
  // Two straight teeth in a slot: one tooth in the cut at a time; the force on it is largest
  // at phi = pi/2, where its tangential, radial and axial parts are orthogonal.
  const StepLoad two = cuttingLoad(cylinder(0.0, kPi), m, {2, 0.0, R}, c, 10000.0);
  const double want =
      a * std::sqrt(std::pow(k.Ktc * c + k.Kte, 2) + std::pow(k.Krc * c + k.Kre, 2) +
                    std::pow(k.Kac * c + k.Kae, 2));
  CHECK(two.peak == Approx(want).epsilon(1e-9));  // phi = pi/2 is one of the samples
  // A helix spreads the teeth's contact over the revolution: the same means, a lower peak.
  const StepLoad helix =
      cuttingLoad(cylinder(0.0, kPi, a, 48), m, {2, 30.0 * kPi / 180, R}, c, 1e4);
  const StepLoad straight = cuttingLoad(cylinder(0.0, kPi, a, 48), m, {2, 0.0, R}, c, 1e4);
  CHECK(helix.force.x() == Approx(straight.force.x()).epsilon(1e-12));
  CHECK(helix.torque == Approx(straight.torque).epsilon(1e-12));
  CHECK(helix.peak < straight.peak);
  // The peaks kept for the scheduler grow with the feed and hold the one at scale 1.
  for (std::size_t i = 1; i < kPeakScales.size(); ++i)
    CHECK(two.peakAt[i] > two.peakAt[i - 1]);
  // Torque with the feed: T(s) = s T_cut + T_edge (linear model).
  const double limit = 0.5 * two.torque;
  const double s = scaleForTorque(two, limit);
  CHECK(s * two.torqueCut + two.torqueEdge == Approx(limit).epsilon(1e-12));
  // The peak at the scale found for a force limit between kept scales is within the chord's
  // error (convex: at or below the limit), and at a kept scale it is exact.
  CHECK(scaleForPeak(two, two.peakAt[1]) == Approx(kPeakScales[1]).epsilon(1e-12));
}

TEST_CASE("Kienzle's model: torque of a slot against its closed form", "[physics]") {
  Material m;
  m.model = ForceModel::Kienzle;
  m.kienzle.kc11 = 1500.0;  // a carbon steel (data/materials/steel-c45.json)
  m.kienzle.mc = 0.22;
  const double p = 1.0 - m.kienzle.mc;
  // T = N a R / (2 pi) kc11 c^p Int_0^pi sin^p, Int_0^pi sin^p = sqrt(pi) G((p+1)/2) / G(p/2+1).
  const double integral = std::sqrt(kPi) * std::tgamma((p + 1) / 2) / std::tgamma(p / 2 + 1);
  const double want = N * a * R / (2 * kPi) * 1500.0 * std::pow(c, p) * integral / 1000.0;
  const StepLoad load = cuttingLoad(cylinder(0.0, kPi), m, {N, 0.0, R}, c, 10000.0);
  // 16-point Gauss-Legendre on sin^0.78 (its derivative unbounded at the ends): 1e-4.
  CHECK(load.torque == Approx(want).epsilon(1e-4));
  CHECK(load.torqueEdge == 0.0);
  // Only tangential coefficients: the mean force is the tangential one, no axial part.
  CHECK(load.force.z() == 0.0);
  // T(s) = s^p T_cut.
  CHECK(scaleForTorque(load, 0.5 * load.torque) == Approx(std::pow(0.5, 1.0 / p)).epsilon(1e-12));
}

TEST_CASE("no force in air, and a ball's chip at a shallow depth", "[physics]") {
  const Material m = linearMaterial();
  const StepLoad air = cuttingLoad(EdgeEngagement{}, m, {N, 0.5, R}, c, 10000.0);
  CHECK(air.peak == 0.0);
  CHECK(air.force.norm() == 0.0);
  CHECK(air.torque == 0.0);
  CHECK(air.hMax == 0.0);

  // A 10 mm ball slotting 0.5 mm deep in a dexel block (rays 0.05 mm apart): the thickest
  // chip is cut at the top of the contact, h = f_z sin(kappa) = f_z r(d) / R with
  // r(d) = sqrt(d (2R - d)) = 2.18 mm -> 0.436 f_z. The top slice's middle lies up to half a
  // slice below d (slices 0.025 mm): sin(kappa) there is 1.2 % lower; and the contact's top
  // is found to a ray spacing: 3 %.
  const double d = 0.5, hs = 0.05;
  const AptCutter ball = AptCutter::ball(2 * R, 20.0);
  Box3 b;
  b.min = {-30, -20, -20};
  b.max = {30, 20, 0};
  DexelStock stock = DexelStock::box(b, hs);
  StepPath path;
  path.start = {-40.0, 0.0, -d};
  path.end = {0.0, 0.0, -d};
  stock.remove(Sweep(ball, path, hs));
  const EdgeEngagement e = measureEngagement(stock, ball, {0.0, 0.0, -d}, {1.0, 0.0}, true, d);
  const StepLoad load = cuttingLoad(e, m, {2, 0.0, R}, c, 10000.0);
  CHECK(load.hMax == Approx(c * std::sqrt(d * (2 * R - d)) / R).epsilon(0.03));
}

TEST_CASE("mean forces and torque read from a cut stock against the closed forms", "[physics]") {
  // The same closed forms, the contact now measured in a stock after a straight pass
  // (tests/support/ContactCases.h): the stock's top face on a grid line or 0.37 cells off it,
  // the wall the contact ends at on a grid line or 0.29 cells off it. Tolerance 0.5 %
  // (measured worst 0.16 %: the edge's sampled quadrature and its boundaries to 0.01 deg),
  // tighter than the 3 % at D/20 and 1 % at D/40; Fx of half immersion is a small
  // difference of large terms, held to 0.5 % of the resultant. The angles within 0.5 deg.
  const Material m = linearMaterial();
  struct Case {
    const char* name;
    double ae;
    bool left;  // the stock on the cutter's left: up milling under M3
  };
  for (const char* model : {"dexel", "voxel"})
    for (const double cells : {20.0, 40.0})
      for (const double top : {0.0, 0.37})
        for (const double across : {0.0, 0.29})
          for (const Case& k :
               {Case{"slot", 2 * R, true}, Case{"half immersion up", R, true},
                Case{"half immersion down", R, false}, Case{"10 % radial down", 0.2 * R, false}}) {
            CAPTURE(model, cells, top, across, k.name);
            const EdgeEngagement e =
                test::straightContact(model, 2 * R / cells, R, a, k.ae, k.left, top, across);
            const StepLoad load = cuttingLoad(e, m, {N, 0.0, R}, c, 10000.0);
            const std::array<double, 2> want = test::straightAngles(R, k.ae, k.left);
            const Closed closed = closedForm(m.linear, want[0], want[1]);
            const double tol = 0.005, resultant = std::hypot(closed.fx, closed.fy);
            CHECK(load.force.x() == Approx(closed.fx).margin(tol * resultant));
            CHECK(load.force.y() == Approx(closed.fy).epsilon(tol));
            CHECK(load.force.z() == Approx(closed.fz).epsilon(tol));
            CHECK(load.torque == Approx(closed.torque).epsilon(tol));
            CHECK(e.entry == Approx(want[0]).margin(0.5 * kPi / 180));
            CHECK(e.exit == Approx(want[1]).margin(0.5 * kPi / 180));
          }
}

TEST_CASE("Kienzle's model: a slot's torque read from a cut stock", "[physics]") {
  // The Kienzle slot closed form above, the contact measured in both stocks at D/20 with the
  // top off the grid: within 0.5 % (the quadrature's 1e-4 and the contact's reading).
  Material m;
  m.model = ForceModel::Kienzle;
  m.kienzle.kc11 = 1500.0;
  m.kienzle.mc = 0.22;
  const double p = 1.0 - m.kienzle.mc;
  const double integral = std::sqrt(kPi) * std::tgamma((p + 1) / 2) / std::tgamma(p / 2 + 1);
  const double want = N * a * R / (2 * kPi) * 1500.0 * std::pow(c, p) * integral / 1000.0;
  for (const char* model : {"dexel", "voxel"}) {
    CAPTURE(model);
    const EdgeEngagement e = test::straightContact(model, R / 10, R, a, 2 * R, true, 0.37, 0.29);
    CHECK(cuttingLoad(e, m, {N, 0.0, R}, c, 10000.0).torque == Approx(want).epsilon(0.005));
  }
}

TEST_CASE("a ball end mill's slot: the lead angle tilts the radial and axial forces", "[physics]") {
  // A ball of radius R slotting R deep (its whole hemisphere engaged over [0, pi]), straight
  // teeth, linear model. On the sphere z = R (1 - cos kappa): the chip h = c sin(phi)
  // sin(kappa), the edge's width db = dz / sin(kappa) = R dkappa; the radial force points
  // (-sin k sin p, -sin k cos p, cos k) and the axial (cos k sin p, cos k cos p, sin k) in
  // (feed, side, z). Integrating by hand over phi in [0, pi] and kappa in [0, pi/2]
  // (int sin^2 k = pi/4, int sin k cos k = 1/2, int sin k = int cos k = 1):
  //   Fz = N R / (2 pi) [Krc c + pi Kre + (pi/2) Kac c + pi Kae]
  //   Fx = N R / (2 pi) [-(pi^2/8) Krc c - 2 Kre + (pi/4) Kac c + 2 Kae]
  // The cos(kappa) terms (the radial force's axial part, the axial force's horizontal part)
  // vanish on a flat end mill's side; here they carry most of Fz. The contact in 2000 slices
  // of equal lead angle (each dz = R (cos k0 - cos k1), its middle's kappa): the midpoint rule
  // in kappa on smooth integrands, within 1e-6.
  const Material m = linearMaterial();
  const LinearCoefficients& k = m.linear;
  EdgeEngagement e;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double k0 = 0.5 * kPi * i / n, k1 = 0.5 * kPi * (i + 1) / n;
    EdgeSlice s;
    s.kappa = 0.5 * (k0 + k1);
    s.dz = R * (std::cos(k0) - std::cos(k1));
    s.z = R * (1.0 - std::cos(s.kappa));
    s.radius = R * std::sin(s.kappa);
    s.arcs.push_back({0.0, kPi});
    e.slices.push_back(s);
  }
  e.entry = 0.0;
  e.exit = kPi;
  const StepLoad load = cuttingLoad(e, m, {N, 0.0, R}, c, 10000.0);
  const double fz =
      N * R / (2 * kPi) * (k.Krc * c + kPi * k.Kre + kPi / 2 * k.Kac * c + kPi * k.Kae);
  const double fx = N * R / (2 * kPi) *
                    (-kPi * kPi / 8 * k.Krc * c - 2 * k.Kre + kPi / 4 * k.Kac * c + 2 * k.Kae);
  CHECK(load.force.z() == Approx(fz).epsilon(1e-6));
  CHECK(load.force.x() == Approx(fx).epsilon(1e-6));
}

TEST_CASE("the end face of a flat end mill: a plunge's and a ramp's torque and thrust",
          "[physics]") {
  // The face's lips as radial edges (kappa = 0) cutting the axial feed per tooth f_a, wholly on
  // material: T = N (K_tc f_a + K_te) R^2 / 2, F_z = N (K_rc f_a + K_re) R (the drilling form),
  // no lateral force. The face is read in rings (midpoints: exact for the linear moments) and
  // the tangential parts cancel over the full circle: 1e-9.
  const Material m = linearMaterial();
  const LinearCoefficients& k = m.linear;
  const double fa = 0.004;
  const double torque = N * (k.Ktc * fa + k.Kte) * R * R / 2 / 1000.0;  // N*m
  const double thrust = N * (k.Krc * fa + k.Kre) * R;
  const AptCutter flat = AptCutter::flat(2 * R, 20.0);
  SECTION("given the face on material") {
    FaceContact face;
    face.radius = R;
    face.rings = 8;
    face.angles = 72;
    face.onMaterial.assign(8 * 72, 1);
    const StepLoad l = cuttingLoad(EdgeEngagement{}, m, {N, 0.0, R}, 0.0, 10000.0, {&face, fa});
    CHECK(l.torque == Approx(torque).epsilon(1e-9));
    CHECK(l.force.z() == Approx(thrust).epsilon(1e-9));
    CHECK(std::hypot(l.force.x(), l.force.y()) < 1e-9 * thrust);
    CHECK(l.hMax == fa);
    CHECK(l.endFace);
    // Without a flat end (a ball) there is no face to read.
    CHECK(measureFace(*test::boxStock("dexel", Box3{{-10, -10, -10}, {10, 10, 0}}, 0.5),
                      AptCutter::ball(2 * R, 20.0), {0, 0, -1}, {1, 0}, true)
              .radius == 0.0);
  }
  for (const char* model : {"dexel", "voxel"}) {
    CAPTURE(model);
    const double h = 2 * R / 20;
    SECTION(std::string("read in a stock after a plunge and after a ramp: ") + model) {
      // A plunge 3 mm into a block and a 10 degree ramp from its top: the face rests on
      // material all over at the step's end (nothing below the tool has been cut), so the
      // closed form holds to the reading's rounding: 0.1 %.
      Box3 b{{-30, -20, -20}, {30, 20, 0.37 * h}};
      std::unique_ptr<Stock> s = test::boxStock(model, b, h);
      const Eigen::Vector3d bottom(0.0, 0.0, b.max.z() - 3.0);
      s->remove(Sweep(flat, test::line(bottom + Eigen::Vector3d(0, 0, 5.0), bottom), h));
      FaceContact plunge = measureFace(*s, flat, bottom, {0.0, 0.0}, true);
      StepLoad l = cuttingLoad(EdgeEngagement{}, m, {N, 0.0, R}, 0.0, 10000.0, {&plunge, fa});
      CHECK(l.torque == Approx(torque).epsilon(0.001));
      CHECK(l.force.z() == Approx(thrust).epsilon(0.001));
      // Plunged at the block's corner, a quarter of the face rests on material: a quarter of
      // each (the quadrant's sides fall between the 5 degree samples), within 1 % in dexels
      // (samples 0.03 cells from the block's faces) and 3 % in voxels (the corner's voxel
      // holds two faces and its planes one: the inner ring, inside it, reads 2.8 % low in
      // thrust; the bound).
      const double tol = std::string(model) == "dexel" ? 0.01 : 0.03;
      std::unique_ptr<Stock> q = test::boxStock(model, b, h);
      const Eigen::Vector3d corner(b.max.x(), b.max.y(), b.max.z() - 3.0);
      q->remove(Sweep(flat, test::line(corner + Eigen::Vector3d(0, 0, 5.0), corner), h));
      FaceContact quarter = measureFace(*q, flat, corner, {0.0, 0.0}, true);
      l = cuttingLoad(EdgeEngagement{}, m, {N, 0.0, R}, 0.0, 10000.0, {&quarter, fa});
      CHECK(l.torque == Approx(torque / 4).epsilon(tol));
      CHECK(l.force.z() == Approx(thrust / 4).epsilon(tol));

      std::unique_ptr<Stock> r = test::boxStock(model, b, h);
      const Eigen::Vector3d start(-20.0, 0.0, b.max.z());
      const Eigen::Vector3d end = start + 15.0 * Eigen::Vector3d(1.0, 0.0, -std::tan(kPi / 18));
      r->remove(Sweep(flat, test::line(start, end), h));
      FaceContact ramp = measureFace(*r, flat, end, {1.0, 0.0}, true);
      l = cuttingLoad(EdgeEngagement{}, m, {N, 0.0, R}, 0.0, 10000.0, {&ramp, fa});
      CHECK(l.torque == Approx(torque).epsilon(0.001));
      CHECK(l.force.z() == Approx(thrust).epsilon(0.001));
    }
  }
}
