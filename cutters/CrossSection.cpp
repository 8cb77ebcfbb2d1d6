#include "cutters/CrossSection.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "cutters/Tolerances.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace engage {
namespace {

void checkPass(const AptCutter& cutter, double s, double d) {
  if (!(std::isfinite(s) && s > 0.0))
    throw ParameterError("stepover s = " + formatNumber(s) + " mm must be positive");
  if (!(std::isfinite(d) && d > 0.0))
    throw ParameterError("depth of cut d = " + formatNumber(d) + " mm must be positive");
  if (d > cutter.height() * (1.0 + tol::kParameterRelative))
    throw ParameterError("depth of cut d = " + formatNumber(d) +
                         " mm exceeds the cutting height h = " + formatNumber(cutter.height()) +
                         " mm");
}

/// Exact integrals of W(z) and z W(z) over [u, v] on one profile piece.
struct PieceIntegrals {
  double w;   ///< integral of W dz, mm^2
  double wz;  ///< integral of W z dz, mm^3
};

PieceIntegrals integrate(const ProfileSegment& s, double u, double v) {
  if (s.kind == ProfileSegment::Kind::Line) {
    // W = a + b z through the segment's end points.
    const double b = (s.end.x() - s.start.x()) / (s.end.y() - s.start.y());
    const double a = s.start.x() - b * s.start.y();
    return {a * (v - u) + b * (v * v - u * u) / 2.0,
            a * (v * v - u * u) / 2.0 + b * (v * v * v - u * u * u) / 3.0};
  }
  // Arc: W = e + sqrt(R^2 - t^2), t = z - c, on the outer half of the corner circle.
  const double e = s.center.x();
  const double c = s.center.y();
  const double R = s.radius;
  auto root = [R](double t) { return std::sqrt(std::max(0.0, R * R - t * t)); };
  // F(t) = integral of sqrt(R^2 - t^2) dt; G(t) = integral of t sqrt(R^2 - t^2) dt.
  auto F = [&](double t) {
    return (t * root(t) + R * R * std::asin(std::clamp(t / R, -1.0, 1.0))) / 2.0;
  };
  auto G = [&](double t) { return -std::pow(root(t), 3) / 3.0; };
  const double tu = u - c;
  const double tv = v - c;
  return {e * (v - u) + F(tv) - F(tu),
          e * (v * v - u * u) / 2.0 + G(tv) - G(tu) + c * (F(tv) - F(tu))};
}

/// W on one piece (the piece must span z).
double pieceRadius(const ProfileSegment& s, double z) {
  if (s.kind == ProfileSegment::Kind::Line)
    return s.start.x() + (z - s.start.y()) * (s.end.x() - s.start.x()) / (s.end.y() - s.start.y());
  const double t = z - s.center.y();
  return s.center.x() + std::sqrt(std::max(0.0, s.radius * s.radius - t * t));
}

/// Heights in (u, v) where 2 W(z) = s on one piece.
std::vector<double> crossings(const ProfileSegment& s, double stepover, double u, double v) {
  std::vector<double> out;
  const double half = stepover / 2.0;
  if (s.kind == ProfileSegment::Kind::Line) {
    const double dz = s.end.y() - s.start.y();
    const double dr = s.end.x() - s.start.x();
    if (std::abs(dr) > tol::kLengthMm) out.push_back(s.start.y() + (half - s.start.x()) * dz / dr);
  } else {
    const double q = s.radius * s.radius - (half - s.center.x()) * (half - s.center.x());
    if (half >= s.center.x() && q >= 0.0) {
      out.push_back(s.center.y() - std::sqrt(q));
      out.push_back(s.center.y() + std::sqrt(q));
    }
  }
  out.erase(std::remove_if(out.begin(), out.end(), [&](double z) { return !(z > u && z < v); }),
            out.end());
  return out;
}

}  // namespace

CrossSection exactCrossSection(const AptCutter& cutter, double s, double d) {
  checkPass(cutter, s, d);
  d = std::min(d, cutter.height());
  double area = 0.0;
  double momentX = 0.0;
  double momentZ = 0.0;
  double cusp = 0.0;
  for (const ProfileSegment& seg : cutter.profile()) {
    const double z0 = seg.start.y();
    const double z1 = seg.end.y();
    if (!(z1 > z0)) continue;  // the flat bottom and the top cap carry no height
    const double lo = std::max(z0, 0.0);
    const double hi = std::min(z1, d);
    if (!(hi > lo)) continue;
    std::vector<double> cuts = crossings(seg, s, lo, hi);
    cuts.push_back(lo);
    cuts.push_back(hi);
    std::sort(cuts.begin(), cuts.end());
    for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
      const double u = cuts[i];
      const double v = cuts[i + 1];
      if (!(v > u)) continue;
      const PieceIntegrals in = integrate(seg, u, v);
      if (2.0 * pieceRadius(seg, (u + v) / 2.0) < s) {
        // The passes do not overlap here: the whole width 2W is removed, centred on the axis.
        area += 2.0 * in.w;
        momentZ += 2.0 * in.wz;
        cusp = std::max(cusp, v);
      } else {
        // Width s on [W - s, W]: centre at W - s/2.
        area += s * (v - u);
        momentZ += s * (v * v - u * u) / 2.0;
        momentX += s * (in.w - s / 2.0 * (v - u));
      }
    }
  }
  CrossSection out;
  out.area = area;
  out.centroidX = area > 0.0 ? momentX / area : 0.0;
  out.centroidZ = area > 0.0 ? momentZ / area : 0.0;
  out.cuspHeight = cusp;
  return out;
}

PaperCrossSection paperCrossSection(const AptCutter& cutter, double s, double d) {
  checkPass(cutter, s, d);
  const AptParameters& p = cutter.parameters();
  const double rt = p.cornerRadius;
  const double e = p.cornerCenterRadial;
  PaperCrossSection out;
  out.phiRad = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::string> why;
  if (p.bottomAngleRad > tol::kAngleRad)
    why.push_back("the conical bottom (delta > 0) is not in Eq 2-3");

  if (s <= 2.0 * e) {
    out.area = s * d;  // Eq 3
    if (2.0 * cutter.radiusAt(d) < s)
      why.push_back("the side narrows below s/2 within the depth (beta < 0)");
  } else {
    const double cosPhi =
        rt > 0.0 ? (s - 2.0 * e) / (2.0 * rt) : std::numeric_limits<double>::infinity();
    if (!(cosPhi <= 1.0)) {
      out.area = std::numeric_limits<double>::quiet_NaN();
      why.push_back(
          "the stepover s exceeds the diameter 2r: phi = acos((s - 2e)/(2 r_tc)) is undefined");
    } else {
      const double phi = std::acos(cosPhi);
      out.phiRad = phi;
      // Eq 2, as printed.
      out.area = (rt * rt * (kPi - 2.0 * phi) + 2.0 * rt * rt * std::sin(phi) * std::cos(phi) +
                  4.0 * rt * e + 2.0 * s * (d - rt)) /
                 2.0;
      const double cusp = rt * (1.0 - std::sin(phi));
      if (d < cusp)
        why.push_back(
            "the depth d is below the cusp height r_tc (1 - sin phi) = " + formatNumber(cusp) +
            " mm, so Eq 2 subtracts cusp material that is not there");
      if (phi < p.taperAngleRad)
        why.push_back("the stepover meets the taper side, not the corner arc (phi < beta)");
      if (2.0 * cutter.radiusAt(d) < s)
        why.push_back("the side narrows below s/2 within the depth (beta < 0)");
    }
  }
  out.applies = why.empty();
  for (std::size_t i = 0; i < why.size(); ++i)
    out.reason += (i ? "; " : "") + why[i];
  return out;
}

}  // namespace engage
