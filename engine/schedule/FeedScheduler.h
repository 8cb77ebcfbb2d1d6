#pragma once
/// \file FeedScheduler.h
/// Adaptive feed from the simulated engagement (paper §4.2, driven by what the stock really
/// does): per step the feed that brings the measured MRR to a target, within the machine's
/// feed and tangential-acceleration limits, turned into F words the way users of such
/// optimisers ask for them (a minimum relative change between F words, levels rounded down
/// with a band against the measurement's noise (Schedule::noise), a minimum segment length), and
/// the feed plan that GcodeWriter writes back. Steps that cut nothing run at the air feed; plunges
/// never run faster than programmed; lines the writer cannot split (canned cycles, splines) take
/// their lowest feed.

#include "cutters/Error.h"
#include "engine/gcode/GcodeWriter.h"
#include "engine/gcode/Toolpath.h"
#include "engine/sim/Simulation.h"
#include "engine/units/Quantity.h"

#include <map>
#include <string>
#include <vector>

namespace engage {

/// Settings of one schedule. Feeds mm/min, MRR mm^3/min, acceleration mm/s^2, lengths mm.
struct ScheduleOptions {
  /// Target MRR; 0 means "auto": the median measured MRR of the tool's steady straight steps.
  double targetMrr = 0.0;
  /// Per tool number, a target that replaces targetMrr for that tool's steps (e.g. from a
  /// force limit and the tool's own diameter).
  std::map<int, double> targetByTool;
  double feedMin =
      0.0;  ///< lowest feed the scheduler may command (0: kFeedMinShare of each step's)
  double feedMax = 0.0;  ///< highest (0: 2 x the highest programmed feed)
  double airFeed = 0.0;  ///< feed of steps that cut nothing (0: the programmed feed)
  /// Tangential acceleration limit, mm/s^2 (0: none), and jerk limit, mm/s^3 (0: none): every
  /// lower F word comes a braking distance (changeDistance) ahead of the first step that needs
  /// it, so that a machine that brakes only where the F word takes effect is down to it there;
  /// the controller speeds up after a higher F word (below it meanwhile, cutting less). The
  /// times and accelerations reported are those of the machine's speed (machineSpeeds).
  double acceleration = 0.0;
  double jerk = 0.0;
  /// The machine's rapid feed, mm/min (0: rapids are not timed); rapids run from standstill
  /// to standstill under the same acceleration and jerk limits.
  double rapidFeed = 0.0;
  double minChange = 0.05;  ///< relative step between feed levels
  double minSegment = 0.0;  ///< shortest run of one feed level along the path (0: one step)
  /// Schedule from the analytic model of each step (paper Eq 21-23 through its MRR, with the
  /// step's curvature and the simulation's stepover/depth) instead of the measured MRR.
  bool analytic = false;
  /// Hold an MRR target at all (targetMrr, targetByTool, or auto). Off when only the limits
  /// below are given: then each step runs at the feed the lowest of them allows.
  bool mrrTarget = true;
  /// Limits from the cutting physics of each step (SimulationResult::loads; 0: none): the
  /// largest chip thickness h_max (mm), peak resultant force (N), spindle torque (N*m) and
  /// power (W). Any combination; the lowest feed wins.
  double maxChip = 0.0, maxForce = 0.0, maxTorque = 0.0, maxPower = 0.0;
  bool physicsLimits() const {
    return maxChip > 0.0 || maxForce > 0.0 || maxTorque > 0.0 || maxPower > 0.0;
  }
  /// Write the re-fed program even where a limit holds only below the lowest feed allowed
  /// (Schedule::unmet); otherwise the run refuses it (UnmetLimitError).
  bool allowUnmet = false;
};

/// Without --feed-min, the lowest feed a step may get: this share of its programmed feed. A
/// limit that needs less is not met (Schedule::unmet), rather than met by a program that
/// crawls (a force limit below a cut's edge forces is met at no feed at all).
constexpr double kFeedMinShare = 0.1;

/// The MRR that keeps the tangential cutting force at `force` (N), paper Eq 17-18 inverted:
/// MRR = F v / E with v = pi D N. mm^3/min, for specific energy E (J/mm^3), cutter diameter D
/// (mm) and spindle speed N (rpm). Throws ParameterError for non-positive inputs.
double mrrForForce(double force, double specificEnergy, double diameter, double spindleRpm);

/// What keeps a step's feed from the one that meets the target. Fixed: spindle-synchronised
/// or probing moves, whose feed the controller sets (Move::fixedFeed()).
/// NoTarget: a tool of a multi-tool program with no steady straight steps to take an auto
/// target from (a drill): its steps keep their programmed feeds. Chip, Force, Torque, Power:
/// that physics limit (ScheduleOptions::maxChip ...) allows less than the MRR target (or, with
/// no MRR target, less than the other limits). Unmodelled: under a physics limit, a step whose
/// load the force model does not cover (a ball's, a cone's or a corner radius's end cutting
/// where the step descends; a stopped spindle): never faster than programmed.
enum class Binding {
  None,
  FeedMin,
  FeedMax,
  Acceleration,
  Air,
  Plunge,
  Fixed,
  NoTarget,
  Chip,
  Force,
  Torque,
  Power,
  Unmodelled,
  Jerk,  ///< held to brake in time by the jerk limit, where the acceleration alone would not
  /// The tool turning about its standing tip (stillStep): its rate never above the programmed
  /// one, for no rotary rate limit is known to raise it to.
  StillTip
};

/// One physics limit of a schedule: what a step it binds is marked, the option that sets it,
/// its unit and its value in ScheduleOptions.
struct PhysicsLimit {
  Binding binding;
  const char* option;
  Dimension dimension;
  double ScheduleOptions::*value;
};

/// The physics limits, in the order they are reported.
inline constexpr PhysicsLimit kPhysicsLimits[] = {
    {Binding::Chip, "--max-chip", Dimension::Length, &ScheduleOptions::maxChip},
    {Binding::Force, "--max-force", Dimension::Force, &ScheduleOptions::maxForce},
    {Binding::Torque, "--max-torque", Dimension::Torque, &ScheduleOptions::maxTorque},
    {Binding::Power, "--max-power", Dimension::Power, &ScheduleOptions::maxPower}};

/// The load a limit holds, of a step's load (StepLoad) or of one scaled to a feed
/// (ScaledLoad): h_max, the peak force, the torque or the power.
template <class Load>
double limitedLoad(const Load& l, Binding b) {
  return b == Binding::Chip     ? l.hMax
         : b == Binding::Force  ? l.peak
         : b == Binding::Torque ? l.torque
                                : l.power;
}

/// A physics limit a step cannot meet at the lowest feed it may get.
struct UnmetLimit {
  std::size_t step = 0;
  Binding limit = Binding::Force;  ///< Chip, Force, Torque or Power
  double value = 0.0;              ///< the limit (mm, N, N*m, W)
  double load = 0.0;               ///< the step's load at `feed`, same unit
  double feed = 0.0;               ///< the lowest feed it may get, mm/min
};

/// A schedule whose limits cannot all be met, refused (exit status 6 from the application).
class UnmetLimitError : public Error {
 public:
  explicit UnmetLimitError(const std::string& message) : Error(message) {}
};

/// The result: per-step feeds and the plan for the writer.
struct Schedule {
  double targetMrr =
      0.0;  ///< the target of the first tool that has one (one-tool runs: the target)
  std::map<int, double> targets;  ///< per tool number that cuts: its target (0: none, NoTarget)
  std::vector<double> wanted;     ///< per step: the feed that meets the target (clamped)
  std::vector<double> feed;       ///< per step: the scheduled (commanded) feed
  std::vector<double> speed;      ///< per step: the machine's speed (machineSpeeds), mm/min
  std::vector<Binding> binding;   ///< per step: what keeps it from `wanted`
  /// Per step: for a stillStep, the scale of its move's programmed rate (one per move: the
  /// least of kFeedMinShare .. 1 that holds its steps' MRR at the target and their loads
  /// within the physics limits); 0 for other steps.
  std::vector<double> stillScale;
  FeedPlan plan;            ///< per move: the pieces for GcodeWriter
  double timeBefore = 0.0;  ///< feed-move time with the programmed feeds, s
  double timeAfter = 0.0;   ///< with the scheduled feeds, s
  double rapidTime = 0.0;   ///< rapids at ScheduleOptions::rapidFeed (the same before and after), s
  double maxAcceleration = 0.0;  ///< largest |Eq 24 acceleration| of `speed`, mm/s^2
  std::size_t fWords = 0;        ///< feed pieces in the plan
  double feedMax = 0.0;  ///< the highest feed it may command (--feed-max, else 2 x programmed)
  std::vector<UnmetLimit> unmet;  ///< the steps whose limit holds only below their lowest feed
  /// The measurement's noise in the wanted feeds (loadNoise), relative: no F word changes
  /// for less. Under a physics limit (a maximum) a feed rises to a higher level only where its
  /// wanted feed clears that level by the noise; an MRR target keeps a higher level while it
  /// is within the larger of the noise and half a level above the wanted feed.
  double noise = 0.0;
};

/// The noise of the wanted feeds `wanted` (per step of `sim`) where the cut is steady (the
/// step and its neighbours on one move within kSteadyChange): the 99th percentile of each such
/// step's relative difference from its neighbours' mean; 0 with fewer than 20 such steps. The
/// measured MRR of a steady arc in the dexel stock varies by 0.55 % (sd) at the default cell,
/// the voxel stock's by 0.01 %.
double loadNoise(const SimulationResult& sim, const std::vector<double>& wanted);

/// A step whose tool tip stands still on the part while the rotary axes turn the tool about it
/// (a feed move of A, B or C alone under tool-centre-point control): it takes time and may
/// cut at no tip feed. Its move's rate (degrees per minute, or inverse time) is scheduled as a
/// whole: Schedule::stillScale.
bool stillStep(const StepRecord& s);

/// The share of a step's feed (or rate) at which its physics limits hold (infinite where none
/// binds), and which limit sets it (`which`, unchanged where none).
double physicsScale(const StepLoad& l, const ScheduleOptions& o, Binding& which);

/// Per step of `sim` (which has loads) the feed its physics limits allow, mm/min (infinite
/// where none binds or no load is modelled), and which limit sets it (`which`).
void physicsCaps(const SimulationResult& sim, const ScheduleOptions& o, std::vector<double>& cap,
                 std::vector<Binding>& which);

/// Schedule feeds for a simulated tool path. Throws ParameterError for inconsistent limits.
Schedule scheduleFeeds(const Toolpath& path, const SimulationResult& sim,
                       const ScheduleOptions& options);

/// The machine's speed per step (mm/min) under commanded feeds `feed` (mm/min), an
/// acceleration limit (mm/s^2, 0: none) and a jerk limit (mm/s^3, 0: none): never above the
/// feed, speeding up after a rise and braking ahead of a drop at the limits (Eq 24 between
/// successive steps; with jerk, every pair of steps of one run of feed moves leaves room for
/// the S-curve between their speeds).
std::vector<double> machineSpeeds(const SimulationResult& sim, const std::vector<double>& feed,
                                  double acceleration, double jerk);

/// Time to run the feed steps with per-step feeds `feed` (mm/min) at the machine's speeds
/// (machineSpeeds; Eq 24's time between successive speeds). Seconds.
double feedTime(const SimulationResult& sim, const std::vector<double>& feed, double acceleration,
                double jerk = 0.0);

/// The shortest distance (mm) over which a controller limited to acceleration `a` (mm/s^2; 0:
/// none) and jerk `j` (mm/s^3; 0: none) changes speed from v0 to v1 (mm/s), starting and
/// ending at zero acceleration. The S-curve is point-symmetric about its middle, so the
/// distance is the mean speed (v0 + v1)/2 times the time T: T = |dv|/a + a/j when the
/// acceleration reaches a (|dv| >= a^2/j), else 2 sqrt(|dv|/j); without jerk limit T = |dv|/a
/// (Eq 24's distance).
double changeDistance(double v0, double v1, double a, double j);

/// The time of that change, s (0 without limits).
double changeTime(double dv, double a, double j);

/// Time of the program's rapids at `rapidFeed` (mm/min; 0: none), each from standstill to
/// standstill under acceleration `a` and jerk `j` (0: none). Seconds.
double rapidTime(const Toolpath& path, double rapidFeed, double a, double j);

const char* bindingName(Binding b);

}  // namespace engage
