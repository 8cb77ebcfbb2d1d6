#include "engine/run/StepsTable.h"

#include "engine/model/EngagementModel.h"
#include "engine/units/Quantity.h"

#include <ostream>
#include <sstream>

namespace engage {
namespace {

const char* sideName(PathSide s) {
  return s == PathSide::Concave ? "concave" : s == PathSide::Convex ? "convex" : "straight";
}

}  // namespace

double feedScale(const RunResult& result, std::size_t i) {
  const double programmed = result.sim.steps[i].feed;
  if (stillStep(result.sim.steps[i])) return result.plan.stillScale[i];
  return programmed > 0.0 ? result.plan.feed[i] / programmed : 0.0;
}

double scheduledAcceleration(const RunResult& result, std::size_t i) {
  const auto& steps = result.sim.steps;
  // The tip's: none where it stands still (or on its first step after standing).
  if (i == 0 || steps[i].kind == MoveKind::Rapid || steps[i - 1].kind == MoveKind::Rapid ||
      !(steps[i].length > 0.0) || stillStep(steps[i - 1]))
    return 0.0;
  return tangentialAcceleration(result.plan.speed[i - 1], result.plan.speed[i], steps[i].length);
}

void writeStepsTable(std::ostream& os, const RunResult& result,
                     const std::vector<std::size_t>* rows) {
  const UnitSystem sys = result.job.units;
  const bool schedule = result.job.scheduling();
  const bool cross = result.crossChecked;
  const std::string other = stockModelName(result.job.otherModel());
  const std::string L(unitTag(Dimension::Length, sys));
  const std::string F(unitTag(Dimension::Feed, sys));
  const std::string V(unitTag(Dimension::Volume, sys));
  const std::string Q(unitTag(Dimension::VolumeRate, sys));
  const std::string A(unitTag(Dimension::Acceleration, sys));
  const bool physics = !result.sim.loads.empty();
  const std::string N(unitTag(Dimension::Force, sys));
  const std::string T(unitTag(Dimension::Torque, sys));
  const std::string P(unitTag(Dimension::Power, sys));
  auto D = [&](double v, Dimension d) { return formatNumber(toDisplay(v, d, sys)); };
  std::string csv =
      "step,move,line,tool,kind,arc_length_" + L + ",x_" + L + ",y_" + L + ",z_" + L + ",feed_" +
      F + ",dt_s,removed_" + V + ",mrr_" + Q + ",width_" + L + ",depth_" + L +
      ",engagement_deg,curvature_1_" + L + ",path,mrr_exact_" + Q + ",mrr_paper_" + Q +
      ",voxels_changed" +
      (schedule ? ",feed_scheduled_" + F + ",binding,mrr_scheduled_" + Q + ",acceleration_" + A
                : std::string()) +
      (cross ? ",removed_" + other + "_" + V + ",cross_check" : std::string()) +
      (physics ? ",entry_deg,exit_deg,h_max_" + L + ",h_mean_" + L + ",fx_" + N + ",fy_" + N +
                     ",fz_" + N + ",f_peak_" + N + ",torque_" + T + ",power_" + P
               : std::string()) +
      (physics && schedule ? ",h_max_scheduled_" + L + ",f_peak_scheduled_" + N +
                                 ",torque_scheduled_" + T + ",power_scheduled_" + P
                           : std::string()) +
      "\n";
  os << csv;
  const auto& steps = result.sim.steps;
  const Schedule& plan = result.plan;
  const std::size_t count = rows ? rows->size() : steps.size();
  for (std::size_t r = 0; r < count; ++r) {
    const std::size_t i = rows ? (*rows)[r] : r;
    const StepRecord& s = steps[i];
    csv = std::to_string(i) + "," + std::to_string(s.move) + "," + std::to_string(s.line) + "," +
          std::to_string(s.tool) + "," + moveKindName(s.kind) + "," +
          D(s.arcLength, Dimension::Length) + "," + D(s.end.x(), Dimension::Length) + "," +
          D(s.end.y(), Dimension::Length) + "," + D(s.end.z(), Dimension::Length) + "," +
          D(s.feed, Dimension::Feed) + "," + formatNumber(s.dt) + "," +
          D(s.removed, Dimension::Volume) + "," + D(s.mrr, Dimension::VolumeRate) + "," +
          D(s.width, Dimension::Length) + "," + D(s.depth, Dimension::Length) + "," +
          formatNumber(s.engagementRad * kDegPerRad) + "," +
          formatNumber(s.curvature * displayFactor(Dimension::Length, sys)) + "," +
          sideName(s.side) + "," + D(s.mrrExact, Dimension::VolumeRate) + "," +
          D(s.mrrPaper, Dimension::VolumeRate) + "," + std::to_string(s.voxelsChanged) +
          (schedule ? "," + D(plan.feed[i], Dimension::Feed) + "," + bindingName(plan.binding[i]) +
                          "," + D(s.mrr * feedScale(result, i), Dimension::VolumeRate) + "," +
                          D(scheduledAcceleration(result, i), Dimension::Acceleration)
                    : std::string()) +
          (cross ? "," + D(result.cross.other.steps[i].removed, Dimension::Volume) +
                       (result.cross.differs[i] ? ",differs" : ",agrees")
                 : std::string());
    if (physics) {
      // Angles from the feed direction, in the direction of rotation (slot: -90 to 90).
      const StepLoad& l = result.sim.loads[i];
      csv += "," + formatNumber(fromFeedDirection(l.entry) * kDegPerRad) + "," +
             formatNumber(fromFeedDirection(l.exit) * kDegPerRad) + "," +
             D(l.hMax, Dimension::Length) + "," + D(l.hMean, Dimension::Length) + "," +
             D(l.force.x(), Dimension::Force) + "," + D(l.force.y(), Dimension::Force) + "," +
             D(l.force.z(), Dimension::Force) + "," + D(l.peak, Dimension::Force) + "," +
             D(l.torque, Dimension::Torque) + "," + D(l.power, Dimension::Power);
      if (schedule) {
        const ScaledLoad a = scaleLoad(l, feedScale(result, i));
        csv += "," + D(a.hMax, Dimension::Length) + "," + D(a.peak, Dimension::Force) + "," +
               D(a.torque, Dimension::Torque) + "," + D(a.power, Dimension::Power);
      }
    }
    csv += "\n";
    os << csv;
  }
}

std::string stepsTable(const RunResult& result, const std::vector<std::size_t>* rows) {
  std::ostringstream os;
  writeStepsTable(os, result, rows);
  return os.str();
}

}  // namespace engage
