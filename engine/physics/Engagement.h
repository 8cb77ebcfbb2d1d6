#pragma once
/// \file Engagement.h
/// Which part of a cutter's edge is in contact with the material, measured in the stock after
/// a step: per height slice of the flutes, the arcs of immersion angle where material lies
/// just outside the cutter's surface. This is what the cutting-force model integrates over
/// (CuttingForces.h), taken from the real stock rather than a nominal stepover and depth.
///
/// Angles follow milling mechanics (Altintas): the immersion angle phi of an edge point is
/// measured in the direction of rotation from the side where a tooth starts its sweep of the
/// front half: for a clockwise spindle (M3) from the left of the feed direction, phi = pi/2
/// straight ahead, pi on the right. Up milling engages [0, phi_ex], down milling
/// [phi_st, pi], a slot [0, pi]. Only the front half (0 <= phi <= pi) cuts: behind it the
/// chip thickness f_z sin(phi) is negative.

#include "cutters/AptCutter.h"
#include "cutters/Numbers.h"
#include "stock/Stock.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace engage {

/// An immersion angle (rad, as measured here) from the feed direction instead, in the direction
/// of rotation, as steps.csv and the Python module give it: a slot engages -pi/2 to pi/2.
inline double fromFeedDirection(double immersion) {
  return immersion - 0.5 * kPi;
}

/// One height slice of the edge.
struct EdgeSlice {
  double z = 0.0;       ///< height of its middle above the tip, mm
  double dz = 0.0;      ///< its thickness, mm
  double radius = 0.0;  ///< the cutter's radius there, mm
  /// Lead angle kappa: between the tool axis and the surface normal, rad (pi/2 on a
  /// cylinder, towards 0 at a ball's tip). The chip is f_z sin(phi) sin(kappa) thick and
  /// the edge dz / sin(kappa) long.
  double kappa = 0.0;
  /// The slice's own feed per tooth across the axis over the step's f_z, along the contact's
  /// `feed` and `side` (EdgeEngagement): (1, 0) where every slice moves as the step does. A
  /// tool whose axis turns moves each height differently; its chip at phi is then
  /// f_z (x sin(phi) + y cos(phi)) sin(kappa).
  Eigen::Vector2d feedShare{1.0, 0.0};
  std::vector<std::array<double, 2>> arcs;  ///< engaged immersion angles [from, to], rad
  /// Where the force model takes the slice: the middle of its edge by length along the
  /// profile (near a ball's tip well below the middle height, where kappa and the edge's
  /// length per height change fastest), the edge's `length` over the slice (mm), and the lead
  /// angle (rad) and radius (mm) there. `length` 0 (a contact put together by hand): the
  /// slice's own, dz / sin(kappa) at kappa and radius.
  struct Middle {
    double length = 0.0, kappa = 0.0, radius = 0.0;
  } middle;
};

/// The contact of one step's end position.
struct EdgeEngagement {
  std::vector<EdgeSlice> slices;  ///< the slices in contact, bottom up
  /// The frame of the angles: `feed` the horizontal feed direction, `side` the direction of
  /// phi = 0 (the left of the feed for a clockwise spindle, its right for M4).
  Eigen::Vector2d feed{1.0, 0.0}, side{0.0, 1.0};
  /// The smallest start and largest end of the arcs, rad (NaN without contact).
  double entry = 0.0, exit = 0.0;
  /// The path's signed curvature at the step's end, 1/mm (+ turning left; 0 straight): the
  /// frame radialDepth measures in.
  double curvature = 0.0;
  bool any() const { return !slices.empty(); }
};

/// The cutter's flat end face on material: where material lies just below the face, which is
/// where the face cuts when the step descends (a plunge, a ramp, a helix). Rings of the face
/// from the axis out to its flat radius, each sampled at `angles` immersion angles in the
/// EdgeEngagement frame (phi_k = (k + 1/2) 2 pi / angles).
struct FaceContact {
  double radius = 0.0;  ///< the flat end's radius, mm (0: the cutter has none)
  int rings = 0, angles = 0;
  std::vector<std::uint8_t> onMaterial;  ///< rings x angles, ring by ring
  Eigen::Vector2d feed{1.0, 0.0}, side{0.0, 1.0};
  bool any() const;
};

/// Measure the end face of `cutter` with its tip at `tip`, in the stock as after step
/// `afterStep` (as measureEngagement; `feed` may be zero: a plunge's frame is +X): 8 rings, 72
/// angles (5 degrees), each point read a tenth of a cell below the face.
FaceContact measureFace(const Stock& stock, const AptCutter& cutter, const Eigen::Vector3d& tip,
                        const Eigen::Vector2d& feed, bool clockwise,
                        std::size_t afterStep = Stock::kLatest,
                        const Eigen::Matrix3d& toPart = Eigen::Matrix3d::Identity());

/// Measure the contact of `cutter` with its tip at `tip`, moving horizontally along `feed`
/// (any length, not zero), spinning clockwise seen from above (M3) or not (M4), up to `zTop`
/// above the tip (the flutes, clipped to the stock's top), in the stock as it was after step
/// `afterStep` of its last batch (Stock::materialReader), the path's signed curvature there
/// `curvature` (1/mm, + turning left). Slices a cell thick (at most 64; one
/// between two that read the same takes their contact); the edge sampled every 6 degrees a
/// tenth of a cell outside the cutter's surface (Stock::materialReader: to a fraction of a
/// cell), each boundary refined by bisection, then read again where it ends at a wall: the
/// wall beyond the cells the step's cut crossed (Stock::readingReach), its trace through three
/// points followed back to the edge (exact for plane and cylindrical walls). The top and
/// bottom slices end where the contact does, found by bisection. Arcs and gaps shorter than 2
/// degrees are dropped. docs/physics.md "The contact"; accuracy: docs/accuracy.md.
///
/// A tilted tool (a 4- or 5-axis step) is measured in its own frame: `toPart` turns that frame
/// about the tip into the part's (its z the tool's axis, StepPath::toolToPart); `feed`, the
/// curvature, heights and the result's angles and frame are then the tool frame's.
EdgeEngagement measureEngagement(const Stock& stock, const AptCutter& cutter,
                                 const Eigen::Vector3d& tip, const Eigen::Vector2d& feed,
                                 bool clockwise, double zTop, double curvature = 0.0,
                                 std::size_t afterStep = Stock::kLatest,
                                 const Eigen::Matrix3d& toPart = Eigen::Matrix3d::Identity());

/// The radial depth of cut a_e of a contact, mm: per slice, how far the arcs in contact
/// reach across the path, measured from the path's centre line (straight) or as distances
/// from the arc's centre (e.curvature: the stepover between two concentric passes, not the
/// chord across the crescent), summed over the slice's arcs; the largest over the slices. A
/// slot reads the diameter; NaN without contact.
double radialDepth(const EdgeEngagement& e);

/// The axial depth of cut a_p: from the bottom of the lowest slice in contact to the top of
/// the highest, mm (NaN without contact).
double axialDepth(const EdgeEngagement& e);

}  // namespace engage
