#pragma once
/// \file Kinematics.h
/// The machine's kinematic chain: where the tool is relative to the part for the axis positions
/// a program commands, X, Y, Z (mm, the program's work coordinates) and A, B, C (degrees).
///
/// The part frame is the work frame with every rotary axis at zero: the stock is given in it
/// and stays fixed to the table. A pose is the tool tip in that frame and the tool's axis (unit,
/// from the tip toward the spindle). The chains and their sign conventions are LinuxCNC's
/// kinematics modules:
///
/// - `table-a`, `table-b`: a rotary 4th axis on the table, A about X or B about Y through
///   `rot_point` (trivkins with a rotary coordinate: the part turns, the tool stays vertical);
/// - `table-ac`, `table-bc`: table-table trunnions, a tilting table (A about X, B about Y) with
///   the C rotary (about Z) mounted on it; `rot_point` is where C's axis meets the tilt axis's
///   plane, `offset` the tilt axis's offset from C's (xyzac-trt-kins: y-offset, z-offset;
///   xyzbc-trt-kins: x-offset, z-offset);
/// - `head-bc`: a head-head machine, B tilting the spindle about Y and C turning it about Z
///   about a pivot `pivot_length` above the tip (5axiskins);
/// - `head-b-table-c`: a spindle head tilting B about Y (pivot as head-bc) and a C rotary
///   table through `rot_point` (the chain of LinuxCNC's maxkins, with the table turning the
///   whole of the head's offset).
///
/// Without the controller's tool-centre-point control (`tcp` false: trivkins, G49), X, Y, Z are
/// the machine's joints with the tip as its controlled point, and a move interpolates them
/// linearly: the tip's path in the part frame is the forward kinematics of the joints (a
/// table's rotation carries it on an arc). With it (`tcp` true: LinuxCNC's trt kinematics
/// switched on, Fanuc's G43.4), X, Y, Z are the tip in the part frame and a move takes it on a
/// straight line while the angles turn linearly.

#include <Eigen/Core>

#include <limits>
#include <optional>
#include <string>

namespace engage {

/// A tool pose in the part frame.
struct ToolPose {
  Eigen::Vector3d tip{0.0, 0.0, 0.0};   ///< mm
  Eigen::Vector3d axis{0.0, 0.0, 1.0};  ///< unit, from the tip toward the spindle
};

/// A machine's kinematic chain (see the file's comment).
struct Kinematics {
  enum class Type { Trivial, TableA, TableB, TableAC, TableBC, HeadBC, HeadBTableC };
  Type type = Type::Trivial;
  /// The controller holds the tip (X, Y, Z are the tip in the part frame).
  bool tcp = false;
  /// mm, work coordinates: where the table's rotary axes cross (table types, head-b-table-c).
  Eigen::Vector3d rotPoint{0.0, 0.0, 0.0};
  /// mm: the tilt axis's offset from the C axis (table-ac: y and z used; table-bc: x and z).
  Eigen::Vector3d offset{0.0, 0.0, 0.0};
  /// mm: from the head's pivot to the tool tip along the tool (head types).
  double pivotLength = 0.0;

  /// The rotary letters this chain moves, in order ("", "A", "B", "AC", "BC").
  std::string rotaryAxes() const;
  /// Whether the chain turns the tool relative to the part at all (not Trivial).
  bool rotary() const { return type != Type::Trivial; }
  /// The tool's pose for axis positions `xyz` (mm) and `abc` (degrees).
  ToolPose pose(const Eigen::Vector3d& xyz, const Eigen::Vector3d& abc) const {
    return pose(xyz, abc, tcp);
  }
  /// The same with the controller holding the tip (`tipHeld`: X, Y, Z are the tip in the part
  /// frame) or not, whatever `tcp` says: a program switches it (G43.4, G234, G254, G68.2).
  ToolPose pose(const Eigen::Vector3d& xyz, const Eigen::Vector3d& abc, bool tipHeld) const;
  /// The joints X, Y, Z (mm) that put the tip at `tip` (mm, part frame) at angles `abc`: the
  /// inverse of pose(xyz, abc, false).tip.
  Eigen::Vector3d joints(const Eigen::Vector3d& tip, const Eigen::Vector3d& abc) const;
  /// Angles A, B, C (degrees) that turn the tool's axis to `axis` (unit, part frame), of the
  /// two solutions the one nearest `near` (C taken to the turn nearest near's, or the turn
  /// before or after it) that lies within [lo, hi] (degrees, per axis), else the nearest of
  /// all; nullopt where this chain cannot point the tool that way (a 4th axis off its plane).
  std::optional<Eigen::Vector3d> anglesFor(const Eigen::Vector3d& axis, const Eigen::Vector3d& near,
                                           const Eigen::Vector3d& lo = Eigen::Vector3d::Constant(
                                               -std::numeric_limits<double>::infinity()),
                                           const Eigen::Vector3d& hi = Eigen::Vector3d::Constant(
                                               std::numeric_limits<double>::infinity())) const;
  /// The tool's axis on the part for angles `abc` (degrees): pose(xyz, abc).axis for any xyz.
  Eigen::Vector3d axis(const Eigen::Vector3d& abc) const;
  /// The rotation that takes the part frame to the machine's (a table's turn; the identity for
  /// a head's).
  Eigen::Matrix3d tableRotation(const Eigen::Vector3d& abc) const;

 private:
  /// The head's turn of the tool in the machine's frame (+Z without a head).
  Eigen::Vector3d headAxis(const Eigen::Vector3d& abc) const;
};

/// "trivial", "table-a", "table-b", "table-ac", "table-bc", "head-bc", "head-b-table-c".
const char* kinematicsTypeName(Kinematics::Type type);
/// The type of a name above; throws ParameterError naming the known ones otherwise.
Kinematics::Type kinematicsTypeOf(const std::string& name);

}  // namespace engage
