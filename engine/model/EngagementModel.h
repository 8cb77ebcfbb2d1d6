#pragma once
/// \file EngagementModel.h
/// The analytic material-removal model of Kloypayan & Lee (paper §4, Eq 6 and 12-24) for a
/// cutter in steady state on a straight or circular tool path, in two forms side by side:
///
///  - exact: MRR = y_G x (speed of the centroid of y_G). On a circular path whose tool-centre
///    (axis) radius is rho, only the horizontal centroid offset x_bar moves the centroid
///    (Pappus): concave paths (stock on the outer side) give rho + x_bar, convex paths (stock
///    on the inner side) rho - x_bar, so MRR = y_G V_f (rho +- x_bar) / rho.
///  - paper: Eq 15/16 literally. The paper's R is the radius of the path of the cutter
///    contact point on the part wall, at the cutter radius r from the axis: R = rho + r on a
///    concave path, R = rho - r on a convex one. Its m is the distance from that contact
///    point, taken at the tip height (x = r, z = 0), to the centroid, including the vertical
///    offset: m = sqrt((r - x_bar)^2 + z_bar^2). With a purely horizontal m (= r - x_bar) the
///    paper's forms reduce to the exact ones; the vertical part is what makes them differ.
///    The area is Eq 2-3 (NaN where undefined).
///
/// Units: mm, mm/min, mm^3/min, rpm, J/mm^3, N, mm/s^2, s.

#include "cutters/AptCutter.h"
#include "cutters/CrossSection.h"

#include <cstdint>
#include <optional>

namespace engage {

/// Which side of a curved path the stock is on (DESIGN.md "Material side and curvature").
enum class PathSide : std::uint8_t {
  Straight,  ///< no curvature
  Concave,   ///< stock on the outer side of the curve: MRR above linear
  Convex,    ///< stock on the inner side of the curve: MRR below linear
};

/// A steady-state tool path: straight, or a circle of tool-centre radius `radius` (mm).
struct PathShape {
  PathSide side = PathSide::Straight;
  double radius = 0.0;  ///< radius of the tool-centre path, mm; unused when straight
};

/// The model of one cutter at one stepover and depth: cross-sections computed once.
class EngagementModel {
 public:
  /// Throws ParameterError as exactCrossSection.
  EngagementModel(const AptCutter& cutter, double stepover, double depth);

  const AptCutter& cutter() const { return cutter_; }
  double stepover() const { return stepover_; }
  double depth() const { return depth_; }
  const CrossSection& exact() const { return exact_; }
  const PaperCrossSection& paper() const { return paper_; }

  /// The paper's m: distance from the contact point (x = r, z = 0) to the centroid, mm.
  double paperCentroidDistance() const;
  /// The paper's R for a tool-centre path: rho + r (concave), rho - r (convex), mm.
  double paperPathRadius(const PathShape& path) const;

  /// Speed of the centroid over the tool-tip feed, exact (Pappus): (rho +- x_bar) / rho.
  /// Throws ParameterError for a path radius that is not positive and finite or that is
  /// smaller than the cutter's radius within the depth of cut (no steady-state cross-section
  /// exists on so tight an arc).
  double centroidSpeedRatio(const PathShape& path) const;
  /// The same ratio as the paper writes it (Eq 12/13): (R - m)/(R - r) or (R + m)/(R + r).
  double centroidSpeedRatioPaper(const PathShape& path) const;

  /// MRR at tip feed `feed` (mm/min): exact y_G x centroid speed, mm^3/min (Eq 6 when straight).
  double mrr(double feed, const PathShape& path) const;
  /// MRR as the paper writes it (Eq 6, 15, 16 with the Eq 2-3 area), mm^3/min; NaN where
  /// Eq 2 is undefined.
  double mrrPaper(double feed, const PathShape& path) const;

  /// Tip feed that gives the target MRR on this path, exact, mm/min (Eq 21-23 inverted
  /// with the exact ratio).
  double adaptiveFeed(double targetMrr, const PathShape& path) const;
  /// Eq 21-23 literally: V_fc = target / y_G(paper), V_adp = V_fc / paper ratio. mm/min.
  double adaptiveFeedPaper(double targetMrr, const PathShape& path) const;

 private:
  void checkPath(const PathShape& path) const;

  AptCutter cutter_;
  double stepover_;
  double depth_;
  CrossSection exact_;
  PaperCrossSection paper_;
  double widestInDepth_ = 0.0;  ///< max W(z) over [0, d], mm
};

/// Eq 17: cutting speed v = pi D N, mm/min, for diameter D (mm) and spindle speed N (rpm).
double cuttingSpeed(double diameter, double spindleRpm);

/// Eq 18: tangential cutting force F = MRR E / v, N, for MRR (mm^3/min), specific energy E
/// (J/mm^3) and cutting speed v (mm/min). Throws ParameterError when v is not positive.
double tangentialForce(double mrr, double specificEnergy, double cuttingSpeedMmPerMin);

/// Eq 24: tangential acceleration between feeds f0 and f1 (mm/min) over an arc length
/// ds (mm): a = (f1^2 - f0^2) / (2 ds), in mm/s^2. Throws ParameterError when ds <= 0.
double tangentialAcceleration(double feed0, double feed1, double arcLength);

/// Eq 24's time between the two feeds at constant acceleration: dt = 2 ds / (f0 + f1), s.
double transitionTime(double feed0, double feed1, double arcLength);

}  // namespace engage
