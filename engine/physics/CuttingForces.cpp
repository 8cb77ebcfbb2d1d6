#include "engine/physics/CuttingForces.h"
#include "cutters/Numbers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace engage {
namespace {

constexpr int kRotationSamples = 90;  ///< per tooth pitch, for the peak

/// Gauss-Legendre nodes and weights on [-1, 1], by Newton's method on P_n.
struct Gauss {
  std::vector<double> x, w;
  explicit Gauss(int n) {
    for (int i = 0; i < n; ++i) {
      double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = 0.0;
        for (int k = 1; k <= n; ++k) {
          const double p2 = p1;
          p1 = p0;
          p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
        }
        dp = n * (z * p0 - p1) / (z * z - 1.0);
        const double dz = p0 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-15) break;
      }
      x.push_back(z);
      w.push_back(2.0 / ((1.0 - z * z) * dp * dp));
    }
  }
};

const Gauss& gauss() {
  static const Gauss g(16);
  return g;
}

/// The tangential, radial and axial force per unit edge length at chip thickness h (mm):
/// the parts that grow with the chip (each as h^exponent) and the edge parts.
struct ElementForce {
  std::array<double, 3> cut{}, edge{};
};

ElementForce element(const Material& m, double h) {
  ElementForce f;
  if (m.model == ForceModel::Linear) {
    const LinearCoefficients& k = m.linear;
    f.cut = {k.Ktc * h, k.Krc * h, k.Kac * h};
    f.edge = {k.Kte, k.Kre, k.Kae};
  } else {
    const KienzleCoefficients& k = m.kienzle;
    f.cut = {k.kc11 * std::pow(h, 1.0 - k.mc), k.kf11 * std::pow(h, 1.0 - k.mf),
             k.kp11 * std::pow(h, 1.0 - k.mp)};
  }
  return f;
}

/// Tangential, radial, axial components (per unit of each) in the (feed, side, z) frame.
struct Directions {
  Eigen::Vector3d t, r, a;
};

/// Where a slice's edge is integrated (EdgeSlice::middle): its length, mm, and its lead angle,
/// rad, and radius, mm, there.
struct Edge {
  double length, kappa, radius;
};

Edge edgeOf(const EdgeSlice& s) {
  if (s.middle.length > 0.0) return {s.middle.length, s.middle.kappa, s.middle.radius};
  return {s.dz / std::max(std::sin(s.kappa), 1e-6), s.kappa, s.radius};
}

Directions directions(double phi, double kappa) {
  const double s = std::sin(phi), c = std::cos(phi), sk = std::sin(kappa), ck = std::cos(kappa);
  Directions d;
  d.t = Eigen::Vector3d(-c, s, 0.0);
  d.r = Eigen::Vector3d(-sk * s, -sk * c, ck);
  d.a = Eigen::Vector3d(ck * s, ck * c, sk);
  return d;
}

bool engaged(const EdgeSlice& s, double phi) {
  for (const auto& arc : s.arcs)
    if (phi >= arc[0] && phi <= arc[1]) return true;
  return false;
}

}  // namespace

StepLoad unmodelledLoad() {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  StepLoad l;
  l.entry = l.exit = l.hMax = l.hMean = l.peak = l.torque = l.power = nan;
  l.torqueCut = l.torqueEdge = nan;
  l.force = Eigen::Vector3d::Constant(nan);
  l.peakAt.fill(nan);
  return l;
}

StepLoad cuttingLoad(const EdgeEngagement& e, const Material& material, const Teeth& teeth,
                     double fz, double rpm, const FaceCut& face) {
  StepLoad out;
  out.exponent = material.exponent();
  out.entry = e.entry;
  out.exit = e.exit;
  const FaceContact* fc =
      face.contact && face.fa > 0.0 && face.contact->any() ? face.contact : nullptr;
  const bool edges = e.any() && fz > 0.0;
  if (!edges && !fc) return out;
  const std::vector<EdgeSlice> none;
  const std::vector<EdgeSlice>& slices = edges ? e.slices : none;
  const int N = std::max(1, teeth.count);
  const Gauss& g = gauss();
  // Mean per revolution: N teeth each sweeping the arcs once in 2 pi.
  Eigen::Vector3d force(0.0, 0.0, 0.0);
  double torqueCut = 0.0, torqueEdge = 0.0, hArea = 0.0, area = 0.0;
  // An element of weight w (length x angle) at radius r cutting a chip h.
  auto addMean = [&](double w, double r, double h, const ElementForce& f, const Directions& d) {
    force += w * ((f.cut[0] + f.edge[0]) * d.t + (f.cut[1] + f.edge[1]) * d.r +
                  (f.cut[2] + f.edge[2]) * d.a);
    torqueCut += w * f.cut[0] * r;
    torqueEdge += w * f.edge[0] * r;
    hArea += w * h;
    area += w;
  };
  // The end face: each ring's samples on material, an element dr x dphi each (the frame is
  // the edges' when they are in contact; a plunge's is the face's own).
  const double faceDr = fc ? fc->radius / fc->rings : 0.0;
  const double faceDphi = fc ? 2.0 * kPi / fc->angles : 0.0;
  const ElementForce faceForce = fc ? element(material, face.fa) : ElementForce{};
  auto faceOn = [&](int ring, double phi) {
    int k = static_cast<int>(std::floor(phi / faceDphi));
    k = ((k % fc->angles) + fc->angles) % fc->angles;
    return fc->onMaterial[static_cast<std::size_t>(ring * fc->angles + k)] != 0;
  };
  if (fc) {
    out.endFace = true;
    out.hMax = face.fa;
    for (int i = 0; i < fc->rings; ++i) {
      const double r = (i + 0.5) * faceDr;
      for (int k = 0; k < fc->angles; ++k) {
        if (!fc->onMaterial[static_cast<std::size_t>(i * fc->angles + k)]) continue;
        addMean(faceDr * faceDphi, r, face.fa, faceForce, directions((k + 0.5) * faceDphi, 0.0));
      }
    }
  }
  // Each slice's chip factor x sin(phi) + y cos(phi) of its feedShare (x, y), as
  // R sin(phi + psi): largest at phi = pi/2 - psi (+ 2 pi k), zero at -psi (+ pi k).
  struct Share {
    double R, psi;
  };
  std::vector<Share> shares;
  shares.reserve(slices.size());
  for (const EdgeSlice& s : slices)
    shares.push_back({s.feedShare.norm(), std::atan2(s.feedShare.y(), s.feedShare.x())});
  for (std::size_t k = 0; k < slices.size(); ++k) {
    const EdgeSlice& s = slices[k];
    const Edge q = edgeOf(s);
    const double sk = std::sin(q.kappa);
    const double R = shares[k].R, psi = shares[k].psi;
    for (const auto& arc : s.arcs) {
      const double top = std::remainder(0.5 * kPi - psi - arc[0], 2.0 * kPi);
      const double sinMax = (top >= 0.0 ? top : top + 2.0 * kPi) <= arc[1] - arc[0]
                                ? 1.0
                                : std::max(std::sin(arc[0] + psi), std::sin(arc[1] + psi));
      out.hMax = std::max(out.hMax, fz * R * sinMax * sk);
      // The arc in pieces where the chip's factor crosses zero (a kink the quadrature would
      // smear), each integrated on its own.
      double from = arc[0];
      for (double zero = -psi + std::ceil((arc[0] + psi) / kPi) * kPi;; zero += kPi) {
        const double to = std::min(zero, arc[1]);
        if (to > from) {
          const double half = 0.5 * (to - from), mid = 0.5 * (to + from);
          for (std::size_t i = 0; i < g.x.size(); ++i) {
            const double phi = mid + half * g.x[i];
            const double w = half * g.w[i] * q.length;
            const double h = fz * std::max(0.0, R * std::sin(phi + psi)) * sk;
            addMean(w, q.radius, h, element(material, h), directions(phi, q.kappa));
          }
        }
        from = std::max(from, to);
        if (!(zero < arc[1])) break;
      }
    }
  }
  const double perRev = N / (2.0 * kPi);
  const Eigen::Vector2d feed2 = edges ? e.feed : fc->feed, side2 = edges ? e.side : fc->side;
  const Eigen::Vector3d feed3(feed2.x(), feed2.y(), 0.0), side3(side2.x(), side2.y(), 0.0);
  force *= perRev;
  out.force = force.x() * feed3 + force.y() * side3 + Eigen::Vector3d(0.0, 0.0, force.z());
  out.hMean = area > 0.0 ? hArea / area : 0.0;
  out.torqueCut = perRev * torqueCut / 1000.0;  // N*mm -> N*m
  out.torqueEdge = perRev * torqueEdge / 1000.0;
  out.torque = out.torqueCut + out.torqueEdge;
  out.power = out.torque * 2.0 * kPi * std::abs(rpm) / 60.0;

  // The revolution, every 1/90 of a pitch: per sample the force's parts that scale with the
  // feed as the tangential, radial and axial exponents, and the edge part.
  const double pitch = 2.0 * kPi / N;
  const double lagPerMm = std::tan(teeth.helix) / std::max(teeth.radius, 1e-9);
  struct Sample {
    Eigen::Vector3d t{0, 0, 0}, r{0, 0, 0}, a{0, 0, 0}, edge{0, 0, 0};
    /// An element of length `len`.
    void add(double len, const ElementForce& f, const Directions& d) {
      t += len * f.cut[0] * d.t;
      r += len * f.cut[1] * d.r;
      a += len * f.cut[2] * d.a;
      edge += len * (f.edge[0] * d.t + f.edge[1] * d.r + f.edge[2] * d.a);
    }
  };
  std::vector<Sample> samples(kRotationSamples);
  for (int m = 0; m < kRotationSamples; ++m) {
    Sample& sm = samples[static_cast<std::size_t>(m)];
    const double theta = pitch * m / kRotationSamples;
    for (std::size_t k = 0; k < slices.size(); ++k) {
      const EdgeSlice& s = slices[k];
      const Edge q = edgeOf(s);
      const double sk = std::sin(q.kappa);
      for (int j = 0; j < N; ++j) {
        double phi = std::fmod(theta + j * pitch - s.z * lagPerMm, 2.0 * kPi);
        if (phi < 0.0) phi += 2.0 * kPi;
        if (!engaged(s, phi)) continue;
        const double h = fz * std::max(0.0, shares[k].R * std::sin(phi + shares[k].psi)) * sk;
        sm.add(q.length, element(material, h), directions(phi, q.kappa));
      }
    }
    // Each tooth's lip on the end face, along the radius at the tooth's angle.
    if (fc)
      for (int j = 0; j < N; ++j) {
        const double phi = std::fmod(theta + j * pitch, 2.0 * kPi);
        const Directions d = directions(phi, 0.0);
        for (int i = 0; i < fc->rings; ++i)
          if (faceOn(i, phi)) sm.add(faceDr, faceForce, d);
      }
  }
  const bool linear = material.model == ForceModel::Linear;
  const double pt = linear ? 1.0 : 1.0 - material.kienzle.mc;
  const double pr = linear ? 1.0 : 1.0 - material.kienzle.mf;
  const double pa = linear ? 1.0 : 1.0 - material.kienzle.mp;
  for (std::size_t k = 0; k < kPeakScales.size(); ++k) {
    const double sc = kPeakScales[k];
    const double st = std::pow(sc, pt), sr = std::pow(sc, pr), sa = std::pow(sc, pa);
    double peak = 0.0;
    for (const Sample& sm : samples)
      peak = std::max(peak, (st * sm.t + sr * sm.r + sa * sm.a + sm.edge).norm());
    out.peakAt[k] = peak;
    if (sc == 1.0) out.peak = peak;
  }
  return out;
}

ScaledLoad scaleLoad(const StepLoad& load, double s) {
  ScaledLoad out;
  out.hMax = load.hMax * s;
  out.torque = load.torqueCut * std::pow(s, load.exponent) + load.torqueEdge;
  out.power = load.torque > 0.0 ? out.torque * load.power / load.torque : 0.0;
  const auto& k = kPeakScales;
  const auto& p = load.peakAt;
  std::size_t i = 1;
  while (i + 1 < k.size() && k[i] < s)
    ++i;
  // Between the kept scales, or on along the first or last chord.
  out.peak = std::max(0.0, p[i - 1] + (p[i] - p[i - 1]) * (s - k[i - 1]) / (k[i] - k[i - 1]));
  if (std::isnan(load.hMax)) out.hMax = out.peak = out.torque = out.power = load.hMax;
  return out;
}

double scaleForTorque(const StepLoad& load, double torque) {
  if (load.torqueEdge >= torque) return 0.0;
  if (!(load.torqueCut > 0.0)) return std::numeric_limits<double>::infinity();
  return std::pow((torque - load.torqueEdge) / load.torqueCut, 1.0 / load.exponent);
}

double scaleForPeak(const StepLoad& load, double force) {
  const auto& s = kPeakScales;
  const auto& p = load.peakAt;
  if (p[0] > force) {
    // Below the first kept scale: towards the edge forces at s = 0, linearly (errs high).
    const double slope = (p[1] - p[0]) / (s[1] - s[0]);
    const double atZero = std::max(0.0, p[0] - slope * s[0]);
    return atZero >= force ? 0.0 : s[0] * (force - atZero) / (p[0] - atZero);
  }
  for (std::size_t k = 1; k < s.size(); ++k)
    if (p[k] > force) return s[k - 1] + (s[k] - s[k - 1]) * (force - p[k - 1]) / (p[k] - p[k - 1]);
  // Beyond the last: on along the last chord.
  const std::size_t n = s.size() - 1;
  const double slope = (p[n] - p[n - 1]) / (s[n] - s[n - 1]);
  if (!(slope > 0.0)) return std::numeric_limits<double>::infinity();
  return s[n] + (force - p[n]) / slope;
}

}  // namespace engage
