#include "engine/model/EngagementModel.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/units/Quantity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace engage {
namespace {

/// Largest W(z) over [0, d]: W is monotone between profile break heights and arc equators.
double widestWithin(const AptCutter& cutter, double depth) {
  double widest = std::max(cutter.radiusAt(0.0), cutter.radiusAt(depth));
  for (const ProfileSegment& s : cutter.profile()) {
    for (double z : {s.start.y(), s.end.y()})
      if (z >= 0.0 && z <= depth) widest = std::max(widest, cutter.radiusAt(z));
    if (s.kind == ProfileSegment::Kind::Arc && s.center.y() >= s.start.y() &&
        s.center.y() <= s.end.y() && s.center.y() <= depth)
      widest = std::max(widest, s.center.x() + s.radius);
  }
  return widest;
}

}  // namespace

EngagementModel::EngagementModel(const AptCutter& cutter, double stepover, double depth)
    : cutter_(cutter),
      stepover_(stepover),
      depth_(depth),
      exact_(exactCrossSection(cutter, stepover, depth)),
      paper_(paperCrossSection(cutter, stepover, depth)),
      widestInDepth_(widestWithin(cutter, depth)) {}

void EngagementModel::checkPath(const PathShape& path) const {
  if (path.side == PathSide::Straight) return;
  if (!(std::isfinite(path.radius) && path.radius > 0.0))
    throw ParameterError("path radius = " + formatNumber(path.radius) + " mm must be positive");
  if (path.radius < widestInDepth_)
    throw ParameterError("path radius = " + formatNumber(path.radius) +
                         " mm is smaller than the cutter radius within the depth of cut (" +
                         formatNumber(widestInDepth_) +
                         " mm): no steady-state cross-section exists on so tight an arc");
}

double EngagementModel::paperCentroidDistance() const {
  return std::hypot(cutter_.radius() - exact_.centroidX, exact_.centroidZ);
}

double EngagementModel::paperPathRadius(const PathShape& path) const {
  switch (path.side) {
    case PathSide::Concave:
      return path.radius + cutter_.radius();
    case PathSide::Convex:
      return path.radius - cutter_.radius();
    case PathSide::Straight:
      break;
  }
  return std::numeric_limits<double>::infinity();
}

double EngagementModel::centroidSpeedRatio(const PathShape& path) const {
  checkPath(path);
  switch (path.side) {
    case PathSide::Concave:
      return (path.radius + exact_.centroidX) / path.radius;
    case PathSide::Convex:
      return (path.radius - exact_.centroidX) / path.radius;
    case PathSide::Straight:
      break;
  }
  return 1.0;
}

double EngagementModel::centroidSpeedRatioPaper(const PathShape& path) const {
  checkPath(path);
  const double R = paperPathRadius(path);
  const double m = paperCentroidDistance();
  const double r = cutter_.radius();
  switch (path.side) {
    case PathSide::Concave:
      return (R - m) / (R - r);  // Eq 12
    case PathSide::Convex:
      return (R + m) / (R + r);  // Eq 13
    case PathSide::Straight:
      break;
  }
  return 1.0;
}

double EngagementModel::mrr(double feed, const PathShape& path) const {
  return exact_.area * feed * centroidSpeedRatio(path);
}

double EngagementModel::mrrPaper(double feed, const PathShape& path) const {
  return paper_.area * feed * centroidSpeedRatioPaper(path);
}

double EngagementModel::adaptiveFeed(double targetMrr, const PathShape& path) const {
  return targetMrr / (exact_.area * centroidSpeedRatio(path));
}

double EngagementModel::adaptiveFeedPaper(double targetMrr, const PathShape& path) const {
  const double feedAtCentroid = targetMrr / paper_.area;  // V_fc, held constant
  return feedAtCentroid / centroidSpeedRatioPaper(path);  // Eq 21-23
}

double cuttingSpeed(double diameter, double spindleRpm) {
  return kPi * diameter * spindleRpm;
}

double tangentialForce(double mrr, double specificEnergy, double cuttingSpeedMmPerMin) {
  if (!(cuttingSpeedMmPerMin > 0.0))
    throw ParameterError("cutting speed v = " + formatNumber(cuttingSpeedMmPerMin) +
                         " mm/min must be positive");
  // E [J/mm^3] * MRR [mm^3/min] is a power in J/min; over v [mm/min] it is J/mm = 1000 N.
  return 1000.0 * mrr * specificEnergy / cuttingSpeedMmPerMin;
}

double tangentialAcceleration(double feed0, double feed1, double arcLength) {
  if (!(arcLength > 0.0))
    throw ParameterError("arc length between feeds = " + formatNumber(arcLength) +
                         " mm must be positive");
  const double v0 = feed0 / 60.0;  // mm/s
  const double v1 = feed1 / 60.0;
  return (v1 * v1 - v0 * v0) / (2.0 * arcLength);
}

double transitionTime(double feed0, double feed1, double arcLength) {
  if (!(arcLength > 0.0))
    throw ParameterError("arc length between feeds = " + formatNumber(arcLength) +
                         " mm must be positive");
  if (!(feed0 + feed1 > 0.0)) throw ParameterError("two zero feeds never cover an arc length");
  return 2.0 * arcLength / ((feed0 + feed1) / 60.0);
}

}  // namespace engage
