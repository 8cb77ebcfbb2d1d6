#pragma once
/// \file Sweep.h
/// The solid swept by a cutter over one step of a tool path (the tip following the step, the
/// tool's axis +Z or, on a 4- or 5-axis machine, tilted): its signed distance and bounds.
///
/// Exact where the geometry allows a closed form: a step that keeps its height (a horizontal
/// line or an XY arc) sweeps the profile along the step's XY path, and since every horizontal
/// slice of the cutter is a disk on its axis, the distance is the profile's 2D distance at
/// the XY distance from the path. Steps that change height take the minimum of the cutter's
/// distance over the tip positions along the step: for straight steps of convex cutters by
/// golden-section search (the distance is convex along the motion), otherwise (helices,
/// arcs in the XZ/YZ planes, inward-leaning sides) sampled every half `resolution` and
/// refined around the best sample. This is exact outside the solid; inside it is the depth
/// below the nearest instance, a little shallower than the swept surface's.
///
/// A tilted tool whose axis stays put over the step (3+2 indexed machining, a 4th axis held)
/// is the same solid turned: everything above holds in the tool's frame, the step's path
/// turned into it (an arc there is a polyline within a thousandth of `resolution`). A tool
/// whose axis turns over the step (simultaneous 4- and 5-axis motion) is sampled as above,
/// each instance at its own axis, with the same refinement.

#include "cutters/AptCutter.h"

#include <Eigen/Core>

#include <limits>
#include <vector>

namespace engage {

/// The path of the tool tip over one step, mm.
struct StepPath {
  enum class Kind { Line, ArcXY, Polyline };
  Kind kind = Kind::Line;
  Eigen::Vector3d start{0.0, 0.0, 0.0};
  Eigen::Vector3d end{0.0, 0.0, 0.0};
  /// ArcXY: centre (x, y used) and signed sweep, radians (+ counter-clockwise); the height
  /// goes linearly from start.z to end.z (a helix when they differ).
  Eigen::Vector3d center{0.0, 0.0, 0.0};
  double sweepRad = 0.0;
  /// Polyline: tip positions from start to end (start and end included), for arcs in other
  /// planes and splines; where the axis turns over the step, at even steps of its parameter
  /// (the tool's pose at even shares of the step's time).
  std::vector<Eigen::Vector3d> points;
  /// The tool's axis (unit, from the tip toward the spindle) at the step's start and end; +Z
  /// for a 3-axis machine. Between them it turns at a steady rate (spherical interpolation
  /// over the step's parameter), unless `axes` says otherwise.
  Eigen::Vector3d axisStart{0.0, 0.0, 1.0};
  Eigen::Vector3d axisEnd{0.0, 0.0, 1.0};
  /// Polyline (optional): the axis at each of `points` (the kinematics' poses), blended
  /// between them: rotary axes turning together move the tool's axis off the great circle
  /// through its ends (C turning at a tilt sweeps a cone).
  std::vector<Eigen::Vector3d> axes;

  /// Whether the tool's axis is anything but +Z on the step.
  bool tilted() const;
  /// Whether the axis turns over the step (a simultaneous 4- or 5-axis step).
  bool turning() const;
  /// The rotation from the tool's frame at the step's end to the part's: its z the axis at
  /// the end, its x and y turned from the part's by the shortest rotation (the identity for an
  /// upright tool). The frame a tilted step's cut is read in.
  Eigen::Matrix3d toolToPart() const;
  /// The tool's axis at parameter u in [0, 1].
  Eigen::Vector3d axisAt(double u) const;
  /// The angle the axis turns through over the step, radians (along `axes` where given).
  double turnRad() const;
  /// The tip's path length, mm (a helix's with its rise).
  double length() const;
  /// Tip position at parameter u in [0, 1] (arc length fraction for lines and arcs).
  Eigen::Vector3d at(double u) const;
  /// Unit direction of travel across the tool at the step's end (the arc's tangent for arcs),
  /// in the tool's frame (toolToPart: XY for an upright tool); +X for steps without such
  /// motion (plunges), as a reference direction.
  Eigen::Vector2d feedDirectionAtEnd() const;
};

/// The parallelogram {o + s a + w b : s, w in [0, 1]}, mm, with its Gram matrix's terms
/// (a.a, a.b, b.b and its determinant), for closest points.
struct Parallelogram {
  Eigen::Vector3d o{0.0, 0.0, 0.0}, a{0.0, 0.0, 0.0}, b{0.0, 0.0, 0.0};
  double aa = 0.0, ab = 0.0, bb = 0.0, det = 0.0;
};

/// The swept solid of one step.
class Sweep {
 public:
  /// `resolution` (mm, e.g. the voxel size) sets the sampling of steps that change height.
  /// `ceiling` (mm): no material lies above this height (the stock's top), so bounds() need
  /// only hold the part of the swept solid below it: a V-bit engraving 0.07 mm deep is asked
  /// about the 0.08 mm it engages, not its whole diameter (a tilted tool's bounds hold all of
  /// it).
  Sweep(const AptCutter& cutter, const StepPath& path, double resolution,
        double ceiling = std::numeric_limits<double>::infinity());

  /// Signed distance from a world point to the swept solid, mm (negative inside). With
  /// `gradient`, also its gradient there (unit length up to round-off): the cutter's at the
  /// closest tip position (envelope theorem), from central differences of step resolution/8.
  /// Far from the surface (beyond `resolution`) the value may be a bound of the right sign
  /// and the gradient is not set. With `curvature` (and `gradient`), also the swept
  /// surface's curvature at the point nearest p, 1/mm: the symmetric matrix K on its tangent
  /// plane for which the surface lies u^T K u / 2 inside the tangent plane at a tangent
  /// offset u (positive where the solid is convex). Steps that keep their height: the
  /// profile's curvature (second differences at a quarter `resolution`) and the path's bend;
  /// a ball's straight step: in closed form; a helix: as the XY arc it turns along; a plunge
  /// or retract: second differences of the swept distance; other steps: the closest
  /// instance's, less its curvature along the motion where the surface is the envelope of
  /// the motion (the contour of the tool seen along it). Zero where the tangent plane misses
  /// the cube of side `resolution` about p.
  double signedDistance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient = nullptr,
                        Eigen::Matrix3d* curvature = nullptr) const;
  /// signedDistance with its gradient where it lies within `within` (mm) of the surface; beyond,
  /// for a step whose axis turns, a value beyond `within` of the right sign and the gradient
  /// left as it was (what tells a cube of half-diagonal `within` wholly inside or outside; it
  /// skips most of the search along the step). Other steps: signedDistance.
  double distanceWithin(const Eigen::Vector3d& p, double within, Eigen::Vector3d* gradient) const;
  /// The swept solid near p (within `radius`, mm) as the points inside `count` half-spaces
  /// {x : normals[i] . (x - p) + distances[i] <= 0} (unit normals pointing out of the solid,
  /// distances in mm): two where a sharp corner of the profile (a flat bottom's edge) is
  /// within `radius` of p on a step that keeps its height or on a plunge or retract, the
  /// tangent plane of the signed distance otherwise. On a step that changes height, near
  /// the rim of the closest instance (a lower sharp corner within `radius`) the swept solid
  /// has an edge along the envelope that no pair of planes here follows: `count` is 0 there
  /// (normals[0], distances[0] still the tangent plane), for the caller to sample. Returns the
  /// signed distance, mm. (`normals[0]` is left unset, like the gradient of signedDistance, beyond
  /// `resolution` from the surface.) With `curvature`, the tangent plane's curvature as in
  /// signedDistance where `count` is 1, zero otherwise.
  double localFaces(const Eigen::Vector3d& p, double radius, Eigen::Vector3d normals[2],
                    double distances[2], int& count, Eigen::Matrix3d* curvature = nullptr) const;
  /// World bounding box of the swept solid below the ceiling, mm.
  Box3 bounds() const { return bounds_; }
  const StepPath& path() const { return world_; }
  /// Whether the swept solid is convex: a straight step of a convex cutter (its sides do not
  /// lean inward) that changes height (a height-keeping step's solid is convex too, but is
  /// answered in closed form).
  bool convexLine() const { return convexLine_; }
  /// For a convexLine() step, the support function of the swept solid: the largest n . x over
  /// its points x (mm), for a unit direction n; the plane n . x = support(n) touches the solid
  /// and has all of it on one side, exactly (the hull of the cutter at the step's two ends).
  double support(const Eigen::Vector3d& n) const;
  const AptCutter& cutter() const { return cutter_; }

 private:
  /// localFaces in the frame the step is computed in (the tool's, where it is tilted).
  double facesInFrame(const Eigen::Vector3d& p, double radius, Eigen::Vector3d normals[2],
                      double distances[2], int& count, Eigen::Matrix3d* curvature) const;
  /// The signed distance from p to the cutter at parameter u of the step (its own axis where
  /// the axis turns), mm.
  double instance(const Eigen::Vector3d& p, double u) const;
  /// distance() for a step whose axis turns.
  double turningDistance(
      const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* curvature,
      double* closest,
      double within = std::numeric_limits<double>::infinity()) const;  // (distanceWithin)
  /// signedDistance, and where it searched along the step (not a closed form or a bound) the
  /// parameter of the closest tool position in `closest` (NaN otherwise).
  double distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* curvature,
                  double* closest) const;
  /// Minimum over the step of the cutter's distance; the minimising parameter in `best`. Where
  /// the samples' minimum lies further than `looseBeyond` (mm) from the surface, or below
  /// `insideBelow` (already inside by that much: the minimum is no higher), it is returned
  /// unrefined (outside, a bound from below from how far the cutter moves between samples)
  /// and `best` is NaN. `ends`, where given, holds the first and last samples' distances.
  double sampled(const Eigen::Vector3d& p, double& best,
                 double looseBeyond = std::numeric_limits<double>::infinity(),
                 double insideBelow = -std::numeric_limits<double>::infinity(),
                 const double* ends = nullptr) const;
  /// XY distance from p to a height-keeping step's path, with its gradient (unit, or zero
  /// on the path) and the curvature of its level line through p, 1/mm (its second
  /// derivative across the gradient: 0 beside a line, +-1/distance about a point or an arc's
  /// centre, negative inside the arc).
  double flatRho(const Eigen::Vector3d& p, Eigen::Vector2d* gradient, double* bend = nullptr) const;
  /// The curvature (as in signedDistance) at the surface point `foot` with unit normal n of
  /// the profile swept along the path's XY trace at tip height tipZ; `radial` stands for the
  /// XY direction away from the path where the foot is on it.
  Eigen::Matrix3d alongPathCurvature(const Eigen::Vector3d& foot, double tipZ,
                                     const Eigen::Vector3d& n, const Eigen::Vector2d& radial) const;
  /// The tip position at parameter u (StepPath::at, with an arc's radius and start angle
  /// computed once).
  Eigen::Vector3d tip(double u) const;
  /// The tool's axis at parameter u (StepPath::axisAt's axes, blended between the samples'
  /// without its sines).
  Eigen::Vector3d axis(double u) const;

  AptCutter cutter_;
  StepPath path_;         ///< in the frame the step is computed in (the tool's where it is tilted)
  StepPath world_;        ///< as given
  bool rotated_ = false;  ///< a tilted axis that stays put: path_ in the tool's frame
  Eigen::Matrix3d toWorld_ = Eigen::Matrix3d::Identity();  ///< rotated_: tool frame to world
  bool turning_ = false;  ///< the axis turns over the step: instances sampled, world frame
  std::vector<Eigen::Vector3d> sampleAxes_;  ///< turning_: the axis at samples_[i]
  /// turning_: the cutter's middle (tip + height/2 along the axis) at the step's ends, and
  /// how far from the segment between them the middle strays and the cutter reaches (mm).
  Eigen::Vector3d middle0_{0.0, 0.0, 0.0}, middle1_{0.0, 0.0, 0.0};
  double middleSpread_ = 0.0, reach_ = 0.0;
  double gap_ = 0.0;     ///< turning_: how far any point of the cutter moves between samples, mm
  double travel_ = 0.0;  ///< turning_: how far any point of the cutter moves over the step, mm
  bool flat_ = false;    ///< the step keeps its height: closed form
  bool convexLine_ = false;      ///< a straight step of a convex cutter: golden-section search
  bool capsuleLine_ = false;     ///< a straight step of a ball end mill: closed form
  Parallelogram capsule_;        ///< capsuleLine_: the ball centre's path, up to h - r
  bool vertical_ = false;        ///< a plunge or retract (no horizontal motion)
  bool lowerCorner_ = false;     ///< the profile has a sharp corner in its lower half (a rim)
  double band_ = 0.0;            ///< distances beyond this only need their sign, mm
  double resolution_ = 0.0;      ///< mm
  double arcRadius_ = 0.0;       ///< ArcXY: the tip's distance from the centre in XY, mm
  double arcStartRad_ = 0.0;     ///< ArcXY: the start's angle about the centre, radians
  double zLow_ = 0.0;            ///< lowest tip height over the step, mm
  double zHigh_ = 0.0;           ///< highest point of the cutter over the step, mm
  std::vector<double> samples_;  ///< sample parameters for steps that change height
  std::vector<Eigen::Vector3d> sampleTips_;  ///< tip(samples_[i])
  Box3 bounds_;
};

}  // namespace engage
