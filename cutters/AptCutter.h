#pragma once
/// \file AptCutter.h
/// The generalized APT endmill (paper §2, Fig 2) as one immutable, validated profile of
/// revolution. Flat, ball, bull (fillet), taper, tapered-ball and chamfer (V-bit) cutters are
/// named constructors of the same profile, not subclasses.
///
/// Frame: the tool tip (the lowest point on the axis) is the origin, the tool axis is +Z.
/// Units: mm and radians.
///
/// The profile in the (rho, z) half-plane, from the tip upward:
///   1. the lower line from the tip (0, 0) at angle delta above the horizontal, tangent to
///   2. the corner circle of radius r_tc centred at (e, h_tc), followed by
///   3. the side line tangent to the corner circle, at angle beta to the axis (beta > 0: the
///      radius grows with height, as on a taper endmill cutting a draft wall), up to
///   4. the top cap at the cutting height h.
/// r = e + r_tc is the radius at the corner circle's equator; for a flat-bottomed taper it is
/// the tip radius. h_tc follows from the others: h_tc = (r_tc + e sin delta) / cos delta.

#include <Eigen/Core>

#include <string_view>
#include <vector>

namespace engage {

/// The APT parameters of paper Fig 2, in mm and radians.
struct AptParameters {
  double radius = 0.0;              ///< r: radius at the corner circle's equator, mm (r = e + r_tc)
  double cornerRadius = 0.0;        ///< r_tc: corner circle radius, mm, 0 <= r_tc <= r
  double cornerCenterRadial = 0.0;  ///< e: distance from the axis to the corner centre, mm
  double cornerCenterHeight = 0.0;  ///< h_tc: height of the corner centre above the tip, mm
  double taperAngleRad = 0.0;       ///< beta: side line to tool axis, -90 deg < beta < 90 deg
  double bottomAngleRad = 0.0;      ///< delta: lower line above the horizontal, 0 <= delta < 90 deg
  double height = 0.0;              ///< h: cutting height (flute length) above the tip, mm
};

/// h_tc implied by r_tc, e and delta for a lower line through the tip tangent to the corner
/// circle: h_tc = (r_tc + e sin delta) / cos delta. mm.
double impliedCornerCenterHeight(double cornerRadius, double cornerCenterRadial,
                                 double bottomAngleRad);

/// The named family a cutter was built as (for reports; the geometry is the profile).
enum class CutterShape { Flat, Ball, Bull, Taper, TaperedBall, Chamfer, General };

/// Lower-case name of a shape as used on the command line: flat, ball, bull, taper,
/// tapered-ball, chamfer, apt.
std::string_view shapeName(CutterShape shape);

/// One piece of the profile in the (rho, z) half-plane: a line segment or a circular arc
/// (counter-clockwise from start to end about `center` when seen with rho to the right and
/// z up). Points are (rho, z) in mm.
struct ProfileSegment {
  enum class Kind { Line, Arc };
  Kind kind = Kind::Line;
  Eigen::Vector2d start{0.0, 0.0};
  Eigen::Vector2d end{0.0, 0.0};
  Eigen::Vector2d center{0.0, 0.0};  ///< arcs only
  double radius = 0.0;               ///< arcs only, mm
};

/// A sharp convex corner of the profile (a flat bottom meeting a side, a side meeting the top
/// cap): where it is, and the outward unit normals (rho, z) of the faces before and after it.
struct ProfileCorner {
  Eigen::Vector2d at{0.0, 0.0};
  Eigen::Vector2d normalBefore{0.0, 0.0};
  Eigen::Vector2d normalAfter{0.0, 0.0};
};

/// Axis-aligned box, mm.
struct Box3 {
  Eigen::Vector3d min{0.0, 0.0, 0.0};
  Eigen::Vector3d max{0.0, 0.0, 0.0};
};

/// The generalized APT cutter: an immutable value, validated when built.
class AptCutter {
 public:
  /// Flat endmill of diameter D. Throws ParameterError on a non-positive or non-finite size.
  static AptCutter flat(double diameter, double fluteLength, int flutes = 2);
  /// Ball endmill of diameter D (r_tc = r, e = 0).
  static AptCutter ball(double diameter, double fluteLength, int flutes = 2);
  /// Bull (fillet, corner-radius) endmill: e = D/2 - r_tc, 0 < r_tc <= D/2.
  static AptCutter bull(double diameter, double cornerRadius, double fluteLength, int flutes = 2);
  /// Taper endmill with a flat bottom of diameter `tipDiameter` and sides at beta to the axis.
  static AptCutter taper(double tipDiameter, double taperAngleRad, double fluteLength,
                         int flutes = 2);
  /// Tapered ball endmill: a ball of diameter `ballDiameter` at the tip, sides tangent to it
  /// at beta to the axis.
  static AptCutter taperedBall(double ballDiameter, double taperAngleRad, double fluteLength,
                               int flutes = 2);
  /// Chamfer mill / V-bit of largest diameter D with included tip angle (e.g. 90 deg):
  /// delta = 90 deg - included/2. The flute length must reach the top of the cone.
  static AptCutter chamfer(double diameter, double includedAngleRad, double fluteLength,
                           int flutes = 2);
  /// Any APT cutter. Every parameter is checked: non-finite values, r <= 0, r_tc < 0,
  /// r_tc > r, e != r - r_tc, h_tc != the implied value, |beta| >= 90 deg, delta outside
  /// [0, 90 deg), beta + delta > 90 deg, h <= 0, a side that closes below h, flutes < 1:
  /// each throws ParameterError naming the parameter and its value.
  static AptCutter fromApt(const AptParameters& parameters, int flutes = 2,
                           CutterShape shape = CutterShape::General);

  const AptParameters& parameters() const { return p_; }
  CutterShape shape() const { return shape_; }
  int fluteCount() const { return flutes_; }
  /// r, mm.
  double radius() const { return p_.radius; }
  /// h, mm.
  double height() const { return p_.height; }
  /// Largest silhouette radius over [0, h], mm.
  double maxRadius() const { return maxRadius_; }
  /// Largest silhouette radius over [0, min(z, h)], mm: how far from its axis the part of the
  /// cutter within z of its tip reaches (the bottom's radius for z <= 0).
  double maxRadiusBelow(double zMm) const;

  /// Silhouette radius W(z) at height z above the tip, mm; 0 outside [0, h].
  double radiusAt(double zMm) const;

  /// Signed distance in the (rho, z) half-plane to the profile region, mm: negative inside.
  double profileSignedDistance(double rhoMm, double zMm) const;

  /// Signed distance from a point in the tool frame (tip at origin, axis +Z) to the solid
  /// cutter, mm: negative inside, exact (Euclidean) for a solid of revolution.
  double signedDistance(const Eigen::Vector3d& pointMm) const;

  /// Bounding box in the tool frame, mm.
  Box3 bounds() const;

  /// The profile from the tip up to and including the top cap, degenerate pieces omitted.
  const std::vector<ProfileSegment>& profile() const { return profile_; }
  /// The profile's sharp convex corners (where the tangent turns by more than 1 deg), off
  /// the axis.
  const std::vector<ProfileCorner>& corners() const { return corners_; }

 private:
  AptCutter(const AptParameters& p, int flutes, CutterShape shape);

  AptParameters p_;
  int flutes_ = 2;
  CutterShape shape_ = CutterShape::General;
  std::vector<ProfileSegment> profile_;
  std::vector<ProfileCorner> corners_;
  double maxRadius_ = 0.0;
  bool roundedBox_ = false;  ///< beta = delta = 0 and h >= 2 r_tc: closed-form distance
};

}  // namespace engage
