#pragma once
/// \file CuttingForces.h
/// Chip thickness, forces, torque and power of one step from its measured edge contact
/// (Engagement.h) and a material's coefficients (Material.h): the mechanistic milling model
/// (Altintas, Manufacturing Automation, 2nd ed., ch. 2.4 for flat, Lee & Altintas 1996 for
/// ball end mills), the edge cut into height slices, each slice's element of edge
/// db = dz / sin(kappa) cutting a chip h = f_z sin(phi) sin(kappa).
///
/// On an element at immersion phi (see Engagement.h), with e = sin(phi) feed + cos(phi) side
/// the outward radial direction, the force on the tool is
///   F = -dF_t (cos(phi) feed - sin(phi) side)      tangential, against the edge's motion
///       -dF_r (sin(kappa) e - cos(kappa) z)         radial, along the inward surface normal
///       +dF_a (cos(kappa) e + sin(kappa) z)         axial
/// which for a cylinder (kappa = pi/2) is the textbook F_x = -F_t cos(phi) - F_r sin(phi),
/// F_y = F_t sin(phi) - F_r cos(phi), F_z = F_a in the feed / side frame.
///
/// Means per revolution integrate each arc exactly enough (16-point Gauss-Legendre: 1e-9 for
/// the linear model's trigonometric integrands, 1e-4 for Kienzle's h^(1-m)); the peak
/// resultant samples the revolution every 1/90 of the tooth pitch, the teeth's edges lagging
/// by z tan(helix) / R with height. The peripheral and corner edges cut with the horizontal
/// feed; the end face of a flat end mill, which cuts where the step descends (plunges, ramps,
/// helices), is the same model on the face's radial edges (lead angle kappa = 0) cutting the
/// axial feed per tooth f_a: per lip element dr at radius r resting on material, tangential
/// (K_tc f_a + K_te) dr, thrust along the axis (K_rc f_a + K_re) dr (the radial coefficient:
/// the force normal to the surface cut), along the lip (K_ac f_a + K_ae) dr; Kienzle's k_c,
/// k_f, k_p the same way. On a face wholly on material (a plunge into solid, a ramp's buried
/// face) that is the drilling form (Altintas, Manufacturing Automation, 2nd ed., ch. 2,
/// mechanics of drilling, the lips as radial edges): torque T = N (K_tc f_a + K_te) R^2 / 2,
/// thrust F_z = N (K_rc f_a + K_re) R. A ball's or a cone's point, and a corner radius,
/// cutting with the axial feed are not modelled (a plunge of such a cutter gets NaN;
/// StepLoad::endFace says which steps hold the end's cut).

#include "engine/physics/Engagement.h"
#include "engine/physics/Material.h"

#include <Eigen/Core>

#include <array>

namespace engage {

/// The teeth: count, helix angle (rad) and the radius the helix lag is taken at (mm).
struct Teeth {
  int count = 2;
  double helix = 0.0;
  double radius = 1.0;
};

/// The feed scales s (scheduled feed / programmed feed) at which StepLoad::peakAt is kept.
constexpr std::array<double, 6> kPeakScales{0.25, 0.5, 1.0, 1.5, 2.0, 4.0};

/// The load of one step at its programmed feed. The machine's frame (the part's where a 4- or
/// 5-axis machine tilts the tool: engine/sim turns it there); N, N*m, W, mm.
struct StepLoad {
  /// The contact's immersion angles (EdgeEngagement::entry, exit), rad; NaN without contact.
  double entry = 0.0, exit = 0.0;
  double hMax = 0.0;   ///< largest chip thickness on the engaged edge
  double hMean = 0.0;  ///< chip thickness averaged over the engaged edge and angle
  Eigen::Vector3d force{0.0, 0.0, 0.0};  ///< mean force on the tool per revolution
  double peak = 0.0;                     ///< largest resultant over a revolution
  double torque = 0.0;                   ///< mean spindle torque, N*m
  double power = 0.0;                    ///< mean spindle power, W
  /// How they change with the feed scale s: the chip thickness as s; the torque and power as
  /// torqueCut s^exponent + torqueEdge (the edge terms do not change); the peak at the
  /// scales kPeakScales (convex in s: interpolating between them errs high).
  double torqueCut = 0.0, torqueEdge = 0.0, exponent = 1.0;
  std::array<double, kPeakScales.size()> peakAt{};
  /// The end face's cut is in it: the step descends and the cutter's end is flat out to its
  /// side (a flat end mill; a corner radius or a point cuts with the axial feed unmodelled).
  bool endFace = false;
};

/// The end face's part of a step that descends: its contact and the axial feed per tooth f_a
/// (mm).
struct FaceCut {
  const FaceContact* contact = nullptr;
  double fa = 0.0;
};

/// The load of a step the model does not cover (a plunge, a stopped spindle): every value NaN.
StepLoad unmodelledLoad();

/// The load of a step with contact `e` cutting `material` with `teeth` at feed per tooth
/// `fz` (mm, horizontal) and spindle speed `rpm` (its magnitude), and its end face's cut
/// `face` where it descends. No contact: all zero.
StepLoad cuttingLoad(const EdgeEngagement& e, const Material& material, const Teeth& teeth,
                     double fz, double rpm, const FaceCut& face = {});

/// The load's chip thickness, peak force, torque and power at feed scale s (the kept peaks
/// interpolated; see StepLoad): what a step carries at a scheduled feed.
struct ScaledLoad {
  double hMax = 0.0, peak = 0.0, torque = 0.0, power = 0.0;
};
ScaledLoad scaleLoad(const StepLoad& load, double s);

/// The largest feed scale s at which `load` keeps its torque at or below `torque` (N*m);
/// +infinity when even the edge terms alone stay below, 0 when they exceed it.
double scaleForTorque(const StepLoad& load, double torque);
/// The same for the peak resultant force (N), from the kept peaks.
double scaleForPeak(const StepLoad& load, double force);

}  // namespace engage
