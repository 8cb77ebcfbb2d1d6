#include "engine/kinematics/Kinematics.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace engage {
namespace {

Eigen::Matrix3d turn(double degrees, const Eigen::Vector3d& about) {
  return Eigen::AngleAxisd(degrees * kPi / 180.0, about).toRotationMatrix();
}

struct TypeName {
  Kinematics::Type type;
  const char* name;
};
constexpr TypeName kNames[] = {
    {Kinematics::Type::Trivial, "trivial"},
    {Kinematics::Type::TableA, "table-a"},
    {Kinematics::Type::TableB, "table-b"},
    {Kinematics::Type::TableAC, "table-ac"},
    {Kinematics::Type::TableBC, "table-bc"},
    {Kinematics::Type::HeadBC, "head-bc"},
    {Kinematics::Type::HeadBTableC, "head-b-table-c"},
};

}  // namespace

const char* kinematicsTypeName(Kinematics::Type type) {
  for (const TypeName& t : kNames)
    if (t.type == type) return t.name;
  return "trivial";
}

Kinematics::Type kinematicsTypeOf(const std::string& name) {
  std::string known;
  for (const TypeName& t : kNames) {
    if (name == t.name) return t.type;
    known += std::string(known.empty() ? "" : ", ") + t.name;
  }
  throw ParameterError("expected a kinematics type (" + known + "), found '" + name + "'");
}

std::string Kinematics::rotaryAxes() const {
  switch (type) {
    case Type::Trivial:
      return "";
    case Type::TableA:
      return "A";
    case Type::TableB:
      return "B";
    case Type::TableAC:
      return "AC";
    case Type::TableBC:
    case Type::HeadBC:
    case Type::HeadBTableC:
      return "BC";
  }
  return "";
}

Eigen::Matrix3d Kinematics::tableRotation(const Eigen::Vector3d& abc) const {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  switch (type) {
    case Type::TableA:
      return turn(abc.x(), x);
    case Type::TableB:
      return turn(abc.y(), y);
    case Type::TableAC:
      return turn(abc.x(), x) * turn(abc.z(), z);
    case Type::TableBC:
      return turn(abc.y(), y) * turn(abc.z(), z);
    case Type::HeadBTableC:
      return turn(-abc.z(), z);  // (maxkins turns the part by +C)
    case Type::Trivial:
    case Type::HeadBC:
      break;
  }
  return Eigen::Matrix3d::Identity();
}

Eigen::Vector3d Kinematics::headAxis(const Eigen::Vector3d& abc) const {
  const double b = abc.y() * kPi / 180.0, c = abc.z() * kPi / 180.0;
  if (type == Type::HeadBC)
    return {-std::sin(b) * std::cos(c), -std::sin(b) * std::sin(c), std::cos(b)};
  if (type == Type::HeadBTableC) return {-std::sin(b), 0.0, std::cos(b)};
  return Eigen::Vector3d::UnitZ();
}

Eigen::Vector3d Kinematics::axis(const Eigen::Vector3d& abc) const {
  return tableRotation(abc).transpose() * headAxis(abc);
}

ToolPose Kinematics::pose(const Eigen::Vector3d& xyz, const Eigen::Vector3d& abc,
                          bool tipHeld) const {
  // The head's turn of the tool in the machine frame, and the tip's offset from where it is
  // with the head upright (the pivot stays pivotLength above that point).
  const Eigen::Vector3d axis = headAxis(abc);
  const Eigen::Vector3d headOffset = pivotLength * (Eigen::Vector3d::UnitZ() - axis);
  const Eigen::Matrix3d toPart = tableRotation(abc).transpose();
  ToolPose pose;
  pose.axis = toPart * axis;
  if (tipHeld) {
    pose.tip = xyz;
    return pose;
  }
  const Eigen::Vector3d machineTip = xyz + headOffset;
  switch (type) {
    case Type::Trivial:
    case Type::HeadBC:
      pose.tip = machineTip;
      break;
    case Type::TableA:
    case Type::TableB:
    case Type::HeadBTableC:
      pose.tip = toPart * (machineTip - rotPoint) + rotPoint;
      break;
    case Type::TableAC:
    case Type::TableBC: {
      // The tilt turns about its own axis, `offset` from C's; C turns what the tilt carries.
      const Eigen::Matrix3d tilt = type == Type::TableAC ? turn(abc.x(), Eigen::Vector3d::UnitX())
                                                         : turn(abc.y(), Eigen::Vector3d::UnitY());
      const Eigen::Matrix3d spin = turn(abc.z(), Eigen::Vector3d::UnitZ());
      pose.tip = spin.transpose() * (tilt.transpose() * (machineTip - rotPoint - offset) + offset) +
                 rotPoint;
      break;
    }
  }
  return pose;
}

Eigen::Vector3d Kinematics::joints(const Eigen::Vector3d& tip, const Eigen::Vector3d& abc) const {
  // The joints carry the tip rigidly: tip = toPart * xyz + pose(0).tip.
  const Eigen::Vector3d at0 = pose(Eigen::Vector3d::Zero(), abc, false).tip;
  return tableRotation(abc) * (tip - at0);
}

std::optional<Eigen::Vector3d> Kinematics::anglesFor(const Eigen::Vector3d& want,
                                                     const Eigen::Vector3d& near,
                                                     const Eigen::Vector3d& lo,
                                                     const Eigen::Vector3d& hi) const {
  // Every chain here tilts the tool by one angle (its axis's Z is the tilt's cosine) and spins
  // the tilted axis about Z by the other: both tilts, each with the spin that brings the axis
  // round to `want` (the turn nearest near's, and the turns either side of it), checked
  // through axis() itself.
  const std::string letters = rotaryAxes();
  if (letters.empty()) {
    if ((want - Eigen::Vector3d::UnitZ()).norm() <= 1e-9) return near;
    return std::nullopt;
  }
  const int tilt = letters[0] - 'A';
  const int spin = letters.size() > 1 ? letters[1] - 'A' : -1;
  const double tiltDeg = std::acos(std::clamp(want.z(), -1.0, 1.0)) * 180.0 / kPi;
  std::optional<Eigen::Vector3d> best, bestWithin;
  double bestCost = 0.0, bestWithinCost = 0.0;
  auto offer = [&](const Eigen::Vector3d& abc) {
    if ((axis(abc) - want).norm() > 1e-9) return;
    const double cost = (abc - near).cwiseAbs().sum();
    if (!best || cost < bestCost - 1e-9) best = abc, bestCost = cost;
    const bool within = ((abc - lo).array() >= -1e-9).all() && ((hi - abc).array() >= -1e-9).all();
    if (within && (!bestWithin || cost < bestWithinCost - 1e-9))
      bestWithin = abc, bestWithinCost = cost;
  };
  for (const double sign : {1.0, -1.0}) {
    Eigen::Vector3d abc = near;
    abc[tilt] = sign * tiltDeg;
    if (spin < 0) {
      offer(abc);
      continue;
    }
    Eigen::Vector3d at0 = abc;
    at0[spin] = 0.0;
    const Eigen::Vector3d v = axis(at0);
    if (!(std::hypot(v.x(), v.y()) > 1e-12 && std::hypot(want.x(), want.y()) > 1e-12)) {
      offer(abc);  // (upright: any spin; the present one)
      continue;
    }
    const double turn = (std::atan2(want.y(), want.x()) - std::atan2(v.y(), v.x())) * 180.0 / kPi;
    // The spin's sense differs between chains: the one that lands on `want`.
    for (const double s : {1.0, -1.0}) {
      abc[spin] = s * turn;
      if ((axis(abc) - want).norm() <= 1e-9) break;
    }
    abc[spin] += 360.0 * std::round((near[spin] - abc[spin]) / 360.0);
    for (const double wrap : {0.0, -360.0, 360.0}) {
      Eigen::Vector3d turned = abc;
      turned[spin] += wrap;
      offer(turned);
    }
  }
  return bestWithin ? bestWithin : best;
}

}  // namespace engage
