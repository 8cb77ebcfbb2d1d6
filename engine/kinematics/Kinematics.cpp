#include "engine/kinematics/Kinematics.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <Eigen/Geometry>

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

ToolPose Kinematics::pose(const Eigen::Vector3d& xyz, const Eigen::Vector3d& abc) const {
  // The head's turn of the tool in the machine frame, and the tip's offset from where it is
  // with the head upright (the pivot stays pivotLength above that point).
  const Eigen::Vector3d axis = headAxis(abc);
  const Eigen::Vector3d headOffset = pivotLength * (Eigen::Vector3d::UnitZ() - axis);
  const Eigen::Matrix3d toPart = tableRotation(abc).transpose();
  ToolPose pose;
  pose.axis = toPart * axis;
  if (tcp) {
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

}  // namespace engage
