#include "engine/schedule/FeedScheduler.h"

#include "cutters/Error.h"
#include "engine/model/EngagementModel.h"
#include "engine/units/Quantity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace engage {
namespace {

/// A binding that says which physics limit set the wanted feed.
bool physicsBinding(Binding b) {
  return b == Binding::Chip || b == Binding::Force || b == Binding::Torque || b == Binding::Power;
}

/// Steps whose MRR is below this share of the target cut air.
constexpr double kAirShare = 0.01;

bool isFeedStep(const StepRecord& s) {
  return s.kind != MoveKind::Rapid && s.feed > 0.0;
}

/// Lower feeds so that no change between successive feed steps needs more than `a` (mm/s^2):
/// a forward pass limits speeding up, a backward pass makes the cutter slow down before a
/// load peak instead of after it.
void limitAcceleration(const SimulationResult& sim, std::vector<double>& feed, double a) {
  if (!(a > 0.0)) return;
  const auto& st = sim.steps;
  auto v = [&](std::size_t i) { return feed[i] / 60.0; };
  for (std::size_t i = 1; i < st.size(); ++i) {
    if (!isFeedStep(st[i]) || !isFeedStep(st[i - 1])) continue;
    const double cap = std::sqrt(v(i - 1) * v(i - 1) + 2.0 * a * st[i].length) * 60.0;
    feed[i] = std::min(feed[i], cap);
  }
  for (std::size_t i = st.size() - 1; i-- > 0;) {
    if (!isFeedStep(st[i]) || !isFeedStep(st[i + 1])) continue;
    const double cap = std::sqrt(v(i + 1) * v(i + 1) + 2.0 * a * st[i + 1].length) * 60.0;
    feed[i] = std::min(feed[i], cap);
  }
}

/// Where each run of successive feed steps begins (the machine does not stop within one).
std::vector<std::size_t> feedRuns(const SimulationResult& sim) {
  const auto& st = sim.steps;
  std::vector<std::size_t> runStart(st.size(), 0);
  for (std::size_t i = 1; i < st.size(); ++i)
    runStart[i] = isFeedStep(st[i]) && isFeedStep(st[i - 1]) ? runStart[i - 1] : i;
  return runStart;
}

/// The longest distance (mm) a change between the feeds' speeds can need: no change between
/// speeds up to the top one vMax needs more than vMax T(vMax) (mean speed at most vMax, T
/// growing with the change).
double longestChange(const SimulationResult& sim, const std::vector<double>& feed, double a,
                     double j) {
  double vMax = 0.0;
  for (std::size_t i = 0; i < sim.steps.size(); ++i)
    if (isFeedStep(sim.steps[i])) vMax = std::max(vMax, feed[i] / 60.0);
  return vMax * changeTime(vMax, a, j);
}

/// The highest speed (mm/s) reachable from v0 within `distance` (mm) under changeDistance.
double reachable(double v0, double vWanted, double distance, double a, double j) {
  if (changeDistance(v0, vWanted, a, j) <= distance) return vWanted;
  double lo = v0, hi = vWanted;
  for (int k = 0; k < 50; ++k) {
    const double mid = 0.5 * (lo + hi);
    (changeDistance(v0, mid, a, j) <= distance ? lo : hi) = mid;
  }
  return lo;
}

/// With a jerk limit a change of feed is not local: every pair of feed steps i < k on one
/// run of feed moves must leave room for the controller's S-curve between their feeds. A
/// forward pass lowers feeds that rise too fast after an earlier one, a backward pass lowers
/// feeds that would have to fall too fast before a later one. Only pairs closer than the
/// longest change are looked at.
void limitJerk(const SimulationResult& sim, std::vector<double>& feed, double a, double j) {
  if (!(j > 0.0)) return;
  const auto& st = sim.steps;
  const double window = longestChange(sim, feed, a, j);
  const std::vector<std::size_t> runStart = feedRuns(sim);
  for (std::size_t k = 1; k < st.size(); ++k) {
    if (!isFeedStep(st[k])) continue;
    for (std::size_t i = k; i-- > runStart[k];) {
      const double distance = st[k].arcLength - st[i].arcLength;
      if (distance > window) break;
      if (feed[i] < feed[k])
        feed[k] =
            std::min(feed[k], 60.0 * reachable(feed[i] / 60.0, feed[k] / 60.0, distance, a, j));
    }
  }
  for (std::size_t i = st.size(); i-- > 0;) {
    if (!isFeedStep(st[i])) continue;
    for (std::size_t k = i + 1; k < st.size() && runStart[k] == runStart[i]; ++k) {
      const double distance = st[k].arcLength - st[i].arcLength;
      if (distance > window) break;
      if (feed[k] < feed[i])
        feed[i] =
            std::min(feed[i], 60.0 * reachable(feed[k] / 60.0, feed[i] / 60.0, distance, a, j));
    }
  }
}

/// Commanded feeds (F words) that a machine braking only where a lower F word takes effect
/// (no look-ahead) follows without running any step faster than it allows (`allowed`, or up
/// to `slack` above it, relative: an MRR target's band; its own feed where that is higher): where
/// an earlier step's feed could not be braked to a later step's allowed feed in the distance
/// between them (changeDistance: the S-curve under `a` and `j`), the earlier step takes the
/// highest of its F-word levels (its programmed feed times (1 + q)^n) that can be, or the
/// later one's feed, so that the lower F word comes a braking distance ahead. Rises are left
/// to the controller: it speeds up after the higher F word, below it meanwhile. Feeds are
/// only ever set to levels or to other steps' feeds, so they stay levels. `why` says per step
/// lowered which limit did: Acceleration, or Jerk where the acceleration alone would not have.
void brakeAhead(const SimulationResult& sim, std::vector<double>& feed,
                const std::vector<double>& allowed, double slack, double q, double a, double j,
                std::vector<Binding>& why) {
  if (!(a > 0.0) && !(j > 0.0)) return;
  const auto& st = sim.steps;
  const double window = longestChange(sim, feed, a, j);  // farther pairs need no look
  const std::vector<std::size_t> runStart = feedRuns(sim);
  for (std::size_t k = st.size(); k-- > 0;) {
    if (!isFeedStep(st[k])) continue;
    // The speed step k may have.
    const double reach = std::max(allowed[k] * (1.0 + slack), feed[k]) / 60.0;
    const double start = st[k].arcLength - st[k].length;
    for (std::size_t i = k; i-- > runStart[k];) {
      const double gap = start - st[i].arcLength;
      if (gap > window) break;
      if (!(feed[i] / 60.0 > reach) || changeDistance(reach, feed[i] / 60.0, a, j) <= gap) continue;
      // The highest of step i's levels that can still be braked to in time (the S-curve is
      // symmetric: braking from v to `reach` takes as long as speeding up from `reach` to v),
      // and never below step k's own feed.
      const double base = st[i].feed;
      const double v = 60.0 * reachable(reach, feed[i] / 60.0, gap, a, j);
      const double level = base * std::pow(1.0 + q, std::floor(std::log(v / base) / std::log1p(q)));
      // Jerk where the acceleration alone would have left room for the feed it had.
      why[i] = j > 0.0 && changeDistance(reach, feed[i] / 60.0, a, 0.0) <= gap
                   ? Binding::Jerk
                   : Binding::Acceleration;
      feed[i] = std::max(feed[k], std::min(feed[i], level));
    }
  }
}

/// Round feeds down to the levels F (1 + q)^k of the step's programmed feed F (k an integer):
/// the programmed feed is a level, so unchanged steps keep it, and any two levels of a move
/// differ by at least the factor 1 + q. So that the measurement's noise does not toggle F
/// words: a step keeps a lower previous level unless the feed the limits want for it
/// (`wanted`, not lowered by the other rules) clears its own level by the noise (`noise`,
/// relative; this only lowers feeds), and it keeps a higher previous level while that is at
/// most `keep` above its feed (hysteresis; 0: none). Levels below the step's floor are lifted
/// to it.
void quantizeDown(const SimulationResult& sim, std::vector<double>& feed,
                  const std::vector<double>& wanted, const std::vector<double>& floor, double q,
                  double noise, double keep) {
  double previous = 0.0;
  for (std::size_t i = 0; i < feed.size(); ++i) {
    if (!isFeedStep(sim.steps[i])) {
      previous = 0.0;
      continue;
    }
    const double base = sim.steps[i].feed;
    const double k = std::floor(std::log(feed[i] / base) / std::log1p(q) + 1e-9);
    const double lowest = std::min(floor[i], feed[i]);
    double level = std::max(std::min(feed[i], base * std::pow(1.0 + q, k)), lowest);
    if (previous > 0.0 && previous < level && wanted[i] < level * (1.0 + noise))
      level = std::max(previous, lowest);
    else if (previous > level && previous <= feed[i] * (1.0 + keep))
      level = previous;
    feed[i] = level;
    previous = level;
  }
}

}  // namespace

double loadNoise(const SimulationResult& sim, const std::vector<double>& wanted) {
  const auto& st = sim.steps;
  std::vector<double> deviation;
  for (std::size_t i = 1; i + 1 < st.size(); ++i) {
    const double a = wanted[i - 1], r = wanted[i], b = wanted[i + 1];
    if (!isFeedStep(st[i]) || !(r > 0.0) || st[i - 1].move != st[i].move ||
        st[i + 1].move != st[i].move || !steadyBetween(a, r, b))
      continue;
    deviation.push_back(std::abs(2.0 * r / (a + b) - 1.0));
  }
  if (deviation.size() < 20) return 0.0;
  const auto at = deviation.begin() + static_cast<long>(99 * (deviation.size() - 1) / 100);
  std::nth_element(deviation.begin(), at, deviation.end());
  return *at;
}

namespace {

/// Runs of one feed shorter than `minSegment` take the lower of their neighbours' feeds.
void mergeShortRuns(const SimulationResult& sim, std::vector<double>& feed, double minSegment) {
  if (!(minSegment > 0.0)) return;
  const auto& st = sim.steps;
  std::size_t i = 0;
  while (i < st.size()) {
    if (!isFeedStep(st[i])) {
      ++i;
      continue;
    }
    std::size_t j = i;
    double length = 0.0;
    while (j < st.size() && isFeedStep(st[j]) && feed[j] == feed[i])
      length += st[j++].length;
    if (length < minSegment) {
      double lower = feed[i];
      if (i > 0 && isFeedStep(st[i - 1])) lower = std::min(lower, feed[i - 1]);
      if (j < st.size() && isFeedStep(st[j])) lower = std::min(lower, feed[j]);
      for (std::size_t k = i; k < j; ++k)
        feed[k] = lower;
    }
    i = j;
  }
}

}  // namespace

double changeDistance(double v0, double v1, double a, double j) {
  // T: a triangle of acceleration when it never reaches a, else a trapezoid; 0 without limits.
  return 0.5 * (v0 + v1) * changeTime(v1 - v0, a, j);
}

double changeTime(double dv, double a, double j) {
  dv = std::abs(dv);
  if (j > 0.0 && (!(a > 0.0) || dv < a * a / j)) return 2.0 * std::sqrt(dv / j);
  if (a > 0.0) return dv / a + (j > 0.0 ? a / j : 0.0);
  return 0.0;
}

double rapidTime(const Toolpath& path, double rapidFeed, double a, double j) {
  if (!(rapidFeed > 0.0)) return 0.0;
  const double v = rapidFeed / 60.0;
  double t = 0.0;
  for (const Move& m : path.moves) {
    if (m.kind != MoveKind::Rapid) continue;
    const double length = moveLength(m);
    if (length <= 0.0) continue;
    // From standstill to standstill: cruise at v if there is room for both changes, else
    // turn at the highest speed the length allows.
    const double both = 2.0 * changeDistance(0.0, v, a, j);
    if (length >= both) {
      t += 2.0 * changeTime(v, a, j) + (length - both) / v;
      continue;
    }
    double lo = 0.0, hi = v;
    for (int k = 0; k < 60; ++k) {
      const double mid = 0.5 * (lo + hi);
      (2.0 * changeDistance(0.0, mid, a, j) <= length ? lo : hi) = mid;
    }
    t += 2.0 * changeTime(lo, a, j);
  }
  return t;
}

const char* bindingName(Binding b) {
  switch (b) {
    case Binding::None:
      return "none";
    case Binding::FeedMin:
      return "feed_min";
    case Binding::FeedMax:
      return "feed_max";
    case Binding::Acceleration:
      return "acceleration";
    case Binding::Air:
      return "air";
    case Binding::Plunge:
      return "plunge";
    case Binding::NoTarget:
      return "no_target";
    case Binding::Fixed:
      return "fixed";
    case Binding::Chip:
      return "chip";
    case Binding::Force:
      return "force";
    case Binding::Torque:
      return "torque";
    case Binding::Power:
      return "power";
    case Binding::Unmodelled:
      return "unmodelled";
    case Binding::Jerk:
      return "jerk";
    case Binding::StillTip:
      return "still_tip";
  }
  return "none";
}

double mrrForForce(double force, double specificEnergy, double diameter, double spindleRpm) {
  if (!(force > 0.0 && specificEnergy > 0.0 && diameter > 0.0 && spindleRpm > 0.0))
    throw ParameterError(
        "a force-limited target needs a positive force, specific energy, diameter and spindle "
        "speed");
  // Eq 18: F = MRR E / v, so MRR = F v / E (tangentialForce's units: 1000 N = J/mm).
  return force * cuttingSpeed(diameter, spindleRpm) / (1000.0 * specificEnergy);
}

bool stillStep(const StepRecord& s) {
  return s.kind != MoveKind::Rapid && !(s.feed > 0.0) && s.dt > 0.0;
}

double physicsScale(const StepLoad& l, const ScheduleOptions& o, Binding& which) {
  // The share each limit allows: the chip grows as the feed, torque and power as
  // T_cut s^p + T_edge, the peak force as its kept values (CuttingForces.h).
  double scale = std::numeric_limits<double>::infinity();
  auto lower = [&](double s, Binding b) {
    if (s < scale) {
      scale = s;
      which = b;
    }
  };
  if (o.maxChip > 0.0 && l.hMax > 0.0) lower(o.maxChip / l.hMax, Binding::Chip);
  if (o.maxForce > 0.0) lower(scaleForPeak(l, o.maxForce), Binding::Force);
  if (o.maxTorque > 0.0) lower(scaleForTorque(l, o.maxTorque), Binding::Torque);
  if (o.maxPower > 0.0 && l.torque > 0.0)
    lower(scaleForTorque(l, o.maxPower * l.torque / l.power), Binding::Power);
  return scale;
}

namespace {

/// Step i's physics limit `b`, met only below the lowest share allowed (`scale` of its
/// feed): unmet, with the load it still carries there and that lowest feed (0 for a share of
/// a rate, a stillStep's).
void addUnmet(Schedule& out, const ScheduleOptions& o, std::size_t i, Binding b, const StepLoad& l,
              double scale, double feed) {
  for (const PhysicsLimit& k : kPhysicsLimits)
    if (k.binding == b)
      out.unmet.push_back({i, b, o.*k.value, limitedLoad(scaleLoad(l, scale), b), feed});
}

}  // namespace

void physicsCaps(const SimulationResult& sim, const ScheduleOptions& o, std::vector<double>& cap,
                 std::vector<Binding>& which) {
  const auto& st = sim.steps;
  cap.assign(st.size(), std::numeric_limits<double>::infinity());
  which.assign(st.size(), Binding::None);
  if (!o.physicsLimits()) return;
  for (std::size_t i = 0; i < st.size(); ++i) {
    const StepLoad& l = sim.loads[i];
    if (!isFeedStep(st[i]) || std::isnan(l.hMax)) continue;
    cap[i] = st[i].feed * physicsScale(l, o, which[i]);
  }
}

std::vector<double> machineSpeeds(const SimulationResult& sim, const std::vector<double>& feed,
                                  double acceleration, double jerk) {
  std::vector<double> v = feed;
  limitAcceleration(sim, v, acceleration);
  limitJerk(sim, v, acceleration, jerk);
  return v;
}

double feedTime(const SimulationResult& sim, const std::vector<double>& feed, double acceleration,
                double jerk) {
  const std::vector<double> f = machineSpeeds(sim, feed, acceleration, jerk);
  double t = 0.0;
  const auto& st = sim.steps;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (!isFeedStep(st[i]) || !(f[i] > 0.0)) continue;
    // Eq 24's time between successive feeds: dt = 2 ds / (f_i + f_{i+1}).
    const double previous = i > 0 && isFeedStep(st[i - 1]) ? f[i - 1] : f[i];
    t += 2.0 * st[i].length / ((previous + f[i]) / 60.0);
  }
  return t;
}

namespace {

/// The load a schedule holds per step: the measured MRR, or with --model analytic the exact
/// model's (0 where it has none).
double stepLoad(const StepRecord& r, const ScheduleOptions& o) {
  const double m = o.analytic ? r.mrrExact : r.mrr;
  return std::isfinite(m) ? m : 0.0;
}

/// The target MRR per tool (out.targets) and the first of them (out.targetMrr): given, or the
/// median load of the tool's steady straight steps.
void chooseTargets(const SimulationResult& sim, const ScheduleOptions& o, Schedule& out) {
  const auto& st = sim.steps;
  out.targetMrr = o.targetMrr;
  auto load = [&](const StepRecord& r) { return stepLoad(r, o); };
  std::map<int, std::vector<double>> steady;
  for (const StepRecord& r : st)
    if (isFeedStep(r)) steady[r.tool];
  for (std::size_t i = 1; i + 1 < st.size(); ++i) {
    const StepRecord &a = st[i - 1], &r = st[i], &b = st[i + 1];
    if (r.side != PathSide::Straight || !isFeedStep(r) || load(r) <= 0.0 || a.move != r.move ||
        b.move != r.move)
      continue;
    if (steadyBetween(load(a), load(r), load(b))) steady[r.tool].push_back(load(r));
  }
  for (auto& [tool, values] : steady) {
    double& target = out.targets[tool];
    const auto given = o.targetByTool.find(tool);
    target = given != o.targetByTool.end() ? given->second : o.targetMrr;
    // A tool without steady steps keeps its programmed feeds (NoTarget); if no tool has any,
    // the check below refuses the run.
    if (target > 0.0 || values.empty()) continue;
    std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2),
                     values.end());
    target = values[values.size() / 2];
  }
  for (const auto& [tool, target] : out.targets)
    if (target > 0.0 && !(out.targetMrr > 0.0)) out.targetMrr = target;
}

/// Per step the feed the targets and limits want (out.wanted) and what bounds it
/// (out.binding), within [floor, fMax]; the physics limits that need less than the floor
/// (out.unmet).
void wantedFeeds(const Toolpath& path, const SimulationResult& sim, const ScheduleOptions& o,
                 const std::vector<double>& floor, double fMax, Schedule& out) {
  const auto& st = sim.steps;
  const bool physics = o.physicsLimits();
  out.wanted.assign(st.size(), 0.0);
  out.binding.assign(st.size(), Binding::None);
  std::vector<double> own;
  std::vector<Binding> ownLimit;
  physicsCaps(sim, o, own, ownLimit);
  // A load is known at the steps' ends only; the re-fed program's steps fall elsewhere (its
  // moves are split where the feed changes), and a load that changes within a step would be
  // met only where it was sampled. So each step also takes its neighbours' caps on the same
  // move (never below its floor: only its own load makes it unmet).
  auto neighbours = [&](std::size_t i) {
    std::pair<double, Binding> c{own[i], ownLimit[i]};
    for (const std::size_t k : {i - 1, i + 1})
      if (k < st.size() && st[k].move == st[i].move && own[k] < c.first) c = {own[k], ownLimit[k]};
    return c;
  };
  for (std::size_t i = 0; i < st.size(); ++i) {
    const StepRecord& s = st[i];
    if (!isFeedStep(s)) continue;
    const double fMin = floor[i];
    if (path.moves[s.move].fixedFeed()) {
      // Threading and probing feeds are the controller's (pitch x speed, probe feed).
      out.wanted[i] = s.feed;
      out.binding[i] = Binding::Fixed;
      continue;
    }
    const double target = out.targets[s.tool];
    if (!(target > 0.0) && (o.mrrTarget || !physics)) {
      out.wanted[i] = std::clamp(s.feed, fMin, fMax);
      out.binding[i] = Binding::NoTarget;
      continue;
    }
    if (o.analytic && !std::isfinite(s.mrrExact) && s.removed > 0.0) {
      // A step that cuts where the analytic model has no value (a tool oblique to the part,
      // a retract through material, an arc tighter than the cutter): not air, never faster
      // than programmed.
      out.wanted[i] = std::clamp(s.feed, fMin, fMax);
      out.binding[i] = Binding::Unmodelled;
      continue;
    }
    const double mrr = stepLoad(s, o);
    const bool air = target > 0.0 ? mrr < kAirShare * target
                                  : !(sim.loads[i].hMax > 0.0) && !std::isnan(sim.loads[i].hMax);
    if (air) {
      out.wanted[i] = std::clamp(o.airFeed > 0.0 ? o.airFeed : s.feed, fMin, fMax);
      out.binding[i] = Binding::Air;
      continue;
    }
    double f = target > 0.0 ? s.feed * target / mrr : std::numeric_limits<double>::infinity();
    if (physics) {
      const StepLoad& l = sim.loads[i];
      if (std::isnan(l.hMax)) {
        // No load model (a plunge, a stopped spindle): the programmed feed, or lower.
        if (s.feed < f) {
          f = s.feed;
          out.binding[i] = Binding::Unmodelled;
        }
      } else if (own[i] < f) {
        f = own[i];
        out.binding[i] = ownLimit[i];
      }
      if (!std::isfinite(f)) {  // no limit binds (edge forces alone): as fast as allowed
        f = fMax;
        out.binding[i] = Binding::FeedMax;
      }
      if (physicsBinding(out.binding[i]) && f < fMin) {
        // Met only below the lowest feed allowed: the load that remains there.
        addUnmet(out, o, i, out.binding[i], l, fMin / s.feed, fMin);
      }
      const auto [around, limit] = neighbours(i);
      const double lowered = std::max(around, std::min(f, fMin));
      if (lowered < f) {
        f = lowered;
        out.binding[i] = limit;
      }
    }
    // Plunges (no horizontal motion) load the cutter's end, not its flank: never faster
    // than programmed. Under a physics limit neither is a step that descends where the end's
    // cut is not modelled (a ball's, a cone's or a corner radius's: StepLoad::endFace).
    const Move& m = path.moves[s.move];
    const bool plunge =
        m.kind == MoveKind::Line && (m.end.head<2>() - m.start.head<2>()).norm() < 1e-9;
    if (plunge && f > s.feed) {
      f = s.feed;
      out.binding[i] = Binding::Plunge;
    }
    if (physics && m.end.z() < m.start.z() - 1e-9 && !sim.loads[i].endFace && f > s.feed) {
      f = s.feed;
      out.binding[i] = Binding::Unmodelled;
    }
    out.wanted[i] = std::clamp(f, fMin, fMax);
    if (f < fMin) out.binding[i] = Binding::FeedMin;
    if (f > fMax) out.binding[i] = Binding::FeedMax;
  }
}

/// The wanted feeds made into feeds the machine can follow and F words a shop wants
/// (out.feed): acceleration and jerk, F-word levels, short runs merged, one feed for the lines
/// the writer cannot split; steps held below what they wanted by that marked Acceleration
/// (Jerk where braking for the jerk limit held them).
void settleFeeds(const Toolpath& path, const SimulationResult& sim, const ScheduleOptions& o,
                 const std::vector<double>& floor, Schedule& out) {
  const auto& st = sim.steps;
  const bool physics = o.physicsLimits();
  // Lines that the writer cannot split (canned cycles: several feed moves on one line;
  // splines) take one feed: the lowest their steps want.
  std::map<int, int> blockFeedMoves;
  for (const Move& m : path.moves)
    if (m.kind != MoveKind::Rapid) ++blockFeedMoves[m.block];
  auto oneFeed = [&](const Move& m) {
    return m.kind == MoveKind::Spline || blockFeedMoves[m.block] > 1;
  };
  auto unify = [&](std::vector<double>& feed) {
    std::map<int, double> lowest;
    for (std::size_t i = 0; i < st.size(); ++i) {
      const Move& m = path.moves[st[i].move];
      if (!isFeedStep(st[i]) || !oneFeed(m)) continue;
      const auto it = lowest.find(m.block);
      lowest[m.block] = it == lowest.end() ? feed[i] : std::min(it->second, feed[i]);
    }
    for (std::size_t i = 0; i < st.size(); ++i) {
      const Move& m = path.moves[st[i].move];
      if (isFeedStep(st[i]) && oneFeed(m)) feed[i] = lowest[m.block];
    }
  };

  // Braking ahead of drops, F-word levels, short runs and unsplittable lines, until nothing
  // changes. The levels' hysteresis may lift a feed by up to half a level, which can undo a
  // motion limit (and the two can settle on lifting and lowering the same feed); so a second
  // loop repeats the same steps without hysteresis: there every step only lowers feeds, the
  // levels are discrete, and it ends with every limit met.
  // Physics limits are maxima, not targets: no level may lift a feed above what they allow,
  // so the hysteresis pass is left out.
  out.feed = out.wanted;
  out.noise = loadNoise(sim, out.wanted);
  // An MRR target's band: its levels may stay up to this above the wanted feed, and so may the
  // machine's speed while it brakes for a lower one. A physics limit has none.
  const double band = physics ? 0.0 : std::max(0.5 * o.minChange, out.noise);
  std::vector<Binding> motion(st.size(), Binding::Acceleration);  // what braking held a step
  for (const bool hysteresis : {true, false})
    for (int round = 0; (round < 50 && !physics) || !hysteresis; ++round) {
      const std::vector<double> before = out.feed;
      brakeAhead(sim, out.feed, out.wanted, band, o.minChange, o.acceleration, o.jerk, motion);
      quantizeDown(sim, out.feed, out.wanted, floor, o.minChange, physics ? out.noise : 0.0,
                   hysteresis ? band : 0.0);
      mergeShortRuns(sim, out.feed, o.minSegment);
      unify(out.feed);
      if (out.feed == before) break;
    }
  for (std::size_t i = 0; i < st.size(); ++i)
    if (isFeedStep(st[i]) && (out.binding[i] == Binding::None || physicsBinding(out.binding[i])) &&
        out.feed[i] < out.wanted[i] / (1.0 + o.minChange) - 1e-9)
      out.binding[i] = motion[i];
}

/// The feed plan the writer follows: per move, its runs of one feed as pieces; the F words.
/// A piece ends where a step ends (StepRecord::t1: the fraction of the move's words).
///
/// A move that turns rotary axes runs all its axes at one rate per F word, so its tip's speed
/// on the part follows the joints' motion along it: a piece scales the programmed rate, by
/// the least of its steps' new-to-programmed speed ratios (no step runs faster than
/// scheduled); a new piece starts where its steps' ratios would spread by more than
/// `minChange`. Those steps' feeds become the speeds the scale gives them.
void planPieces(const Toolpath& path, const SimulationResult& sim, double minChange,
                Schedule& out) {
  const auto& st = sim.steps;
  out.plan.assign(path.moves.size(), {});
  double pieceMax = 0.0, pieceSlowest = 0.0;  // a turning move's piece: its largest ratio and
                                              // its steps' lowest programmed speed
  for (std::size_t i = 0; i < st.size(); ++i) {
    const StepRecord& s = st[i];
    if (!isFeedStep(s)) continue;
    auto& pieces = out.plan[s.move];
    const double until = std::min(1.0, s.t1);
    if (!turnsRotary(path.moves[s.move])) {
      if (!pieces.empty() && pieces.back().feed == out.feed[i])
        pieces.back().until = until;
      else
        pieces.push_back({until, out.feed[i], 0.0});
      continue;
    }
    const double ratio = out.feed[i] / s.feed;
    if (pieces.empty() ||
        std::max(pieceMax, ratio) > std::min(pieces.back().scale, ratio) * (1.0 + minChange)) {
      pieces.push_back({until, 0.0, ratio});
      pieceMax = ratio;
      pieceSlowest = s.feed;
    }
    FeedPiece& p = pieces.back();
    p.until = until;
    p.scale = std::min(p.scale, ratio);
    pieceMax = std::max(pieceMax, ratio);
    pieceSlowest = std::min(pieceSlowest, s.feed);
    p.feed = p.scale * pieceSlowest;
  }
  // The turning moves' steps at the speeds their pieces' scales give them.
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (!isFeedStep(st[i]) || !turnsRotary(path.moves[st[i].move])) continue;
    const auto& pieces = out.plan[st[i].move];
    const auto piece =
        std::lower_bound(pieces.begin(), pieces.end(), std::min(1.0, st[i].t1) - 1e-12,
                         [](const FeedPiece& p, double t) { return p.until < t; });
    out.feed[i] = piece->scale * st[i].feed;
  }
  for (auto& pieces : out.plan) {
    if (pieces.empty()) continue;
    pieces.back().until = 1.0;
    out.fWords += pieces.size();
  }
}

/// The moves that turn the tool about its standing tip (stillStep): each one piece, its
/// programmed rate scaled by the least of its steps' shares that hold the MRR target and the
/// physics limits, between kFeedMinShare and 1 (Schedule::stillScale); a step whose limit
/// holds only below kFeedMinShare is unmet (UnmetLimit::feed 0: the share, not a feed).
void stillScales(const SimulationResult& sim, const ScheduleOptions& o, Schedule& out) {
  const auto& st = sim.steps;
  out.stillScale.assign(st.size(), 0.0);
  std::map<std::size_t, std::pair<double, Binding>> ofMove;  // move: scale, what sets it
  for (std::size_t i = 0; i < st.size(); ++i) {
    const StepRecord& s = st[i];
    if (!stillStep(s)) continue;
    std::pair<double, Binding> share{1.0, Binding::StillTip};
    const auto target = out.targets.find(s.tool);
    const double mrr = stepLoad(s, o);
    if (o.mrrTarget && target != out.targets.end() && target->second > 0.0 && mrr > target->second)
      share = {target->second / mrr, Binding::None};
    if (o.physicsLimits() && i < sim.loads.size() && !std::isnan(sim.loads[i].hMax)) {
      Binding which = Binding::None;
      const double limit = physicsScale(sim.loads[i], o, which);
      if (limit < share.first) share = {limit, which};
    }
    const auto [it, made] = ofMove.try_emplace(s.move, share);
    if (share.first < it->second.first) it->second = share;
    if (physicsBinding(share.second) && share.first < kFeedMinShare)
      addUnmet(out, o, i, share.second, sim.loads[i], kFeedMinShare, 0.0);
  }
  for (auto& [move, share] : ofMove) {
    if (share.first < kFeedMinShare) share = {kFeedMinShare, Binding::FeedMin};
    out.plan[move] = {{1.0, 0.0, share.first}};
    ++out.fWords;
  }
  for (std::size_t i = 0; i < st.size(); ++i)
    if (stillStep(st[i])) {
      const auto& [scale, which] = ofMove.at(st[i].move);
      out.stillScale[i] = scale;
      out.binding[i] = which;
      out.timeBefore += st[i].dt;
      out.timeAfter += st[i].dt / scale;
    }
}

}  // namespace

Schedule scheduleFeeds(const Toolpath& path, const SimulationResult& sim,
                       const ScheduleOptions& o) {
  const auto& st = sim.steps;
  Schedule out;
  chooseTargets(sim, o, out);
  if (o.physicsLimits() && sim.loads.size() != st.size())
    throw ParameterError("--max-chip, --max-force, --max-torque and --max-power need --material");
  if (!o.mrrTarget) {
    out.targetMrr = 0.0;
    for (auto& [tool, target] : out.targets)
      target = 0.0;
  } else if (!(out.targetMrr > 0.0)) {
    throw ParameterError(
        "--target-mrr auto needs steady straight cutting steps; this program has none: give a "
        "target");
  }
  double programmedMax = 0.0;
  for (const StepRecord& s : st)
    programmedMax = std::max(programmedMax, s.feed);
  const double fMax = o.feedMax > 0.0 ? o.feedMax : 2.0 * programmedMax;
  out.feedMax = fMax;
  if (o.feedMin > 0.0 && !(o.feedMin <= fMax))
    throw ParameterError(
        "--feed-min " + formatQuantity(o.feedMin, Dimension::Feed, UnitSystem::Metric) +
        " exceeds --feed-max " + formatQuantity(fMax, Dimension::Feed, UnitSystem::Metric));
  // Each step's lowest feed: --feed-min, else a share of its programmed feed.
  std::vector<double> floor(st.size(), 0.0);
  for (std::size_t i = 0; i < st.size(); ++i)
    floor[i] = std::min(fMax, o.feedMin > 0.0 ? o.feedMin : kFeedMinShare * st[i].feed);
  if (!(o.minChange > 0.0)) throw ParameterError("--min-change must be positive");
  if (o.jerk < 0.0 || o.acceleration < 0.0)
    throw ParameterError("--accel and --jerk must not be negative");

  wantedFeeds(path, sim, o, floor, fMax, out);
  settleFeeds(path, sim, o, floor, out);
  planPieces(path, sim, o.minChange, out);
  std::vector<double> programmed(st.size(), 0.0);
  for (std::size_t i = 0; i < st.size(); ++i)
    programmed[i] = st[i].feed;
  out.timeBefore = feedTime(sim, programmed, o.acceleration, o.jerk);
  out.timeAfter = feedTime(sim, out.feed, o.acceleration, o.jerk);
  stillScales(sim, o, out);
  out.rapidTime = rapidTime(path, o.rapidFeed, o.acceleration, o.jerk);
  out.speed = machineSpeeds(sim, out.feed, o.acceleration, o.jerk);
  for (std::size_t i = 1; i < st.size(); ++i)
    if (isFeedStep(st[i]) && isFeedStep(st[i - 1])) {
      const double v0 = out.speed[i - 1] / 60.0, v1 = out.speed[i] / 60.0;
      out.maxAcceleration =
          std::max(out.maxAcceleration, std::abs(v1 * v1 - v0 * v0) / (2.0 * st[i].length));
    }
  return out;
}

}  // namespace engage
