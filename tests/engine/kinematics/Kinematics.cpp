// Tests of engine/kinematics/Kinematics.h against the forward kinematics LinuxCNC documents for
// its modules (xyzac-trt-kins, xyzbc-trt-kins, 5axiskins, maxkins), written here in their own
// scalar form, and against closed forms of a 4th axis. Poses are sums of products of
// trigonometric values of size up to a few hundred mm: 1e-9 mm is round-off.

#include "engine/kinematics/Kinematics.h"

#include "cutters/Error.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <utility>

using namespace engage;

namespace {

constexpr double kTol = 1e-9;  // mm (and unit vectors): round-off
constexpr double kRad = 3.14159265358979323846 / 180.0;

/// Random joints: X, Y, Z in +-200 mm, angles in +-360 degrees.
struct Joints {
  Eigen::Vector3d xyz, abc;
};
Joints randomJoints(std::mt19937& rng) {
  std::uniform_real_distribution<double> lin(-200.0, 200.0), ang(-360.0, 360.0);
  return {{lin(rng), lin(rng), lin(rng)}, {ang(rng), ang(rng), ang(rng)}};
}

void checkNear(const Eigen::Vector3d& got, const Eigen::Vector3d& want) {
  INFO("got " << got.transpose() << ", want " << want.transpose());
  CHECK((got - want).norm() < kTol);
}

/// `k`'s poses at 200 random joints against `reference`'s (tip, axis) of the same joints.
template <typename Reference>
void compareAtRandom(const Kinematics& k, unsigned seed, Reference&& reference) {
  std::mt19937 rng(seed);
  for (int i = 0; i < 200; ++i) {
    const Joints j = randomJoints(rng);
    const auto [tip, axis] = reference(j);
    const ToolPose pose = k.pose(j.xyz, j.abc);
    checkNear(pose.tip, tip);
    checkNear(pose.axis, axis);
  }
}

using Pose = std::pair<Eigen::Vector3d, Eigen::Vector3d>;

}  // namespace

TEST_CASE("a table-ac trunnion puts the tip where xyzac-trt-kins puts it", "[kinematics]") {
  Kinematics k;
  k.type = Kinematics::Type::TableAC;
  k.rotPoint = {12.0, -30.0, 45.0};
  k.offset = {0.0, 7.5, -20.0};  // y-offset, z-offset
  compareAtRandom(k, 7, [&](const Joints& j) {
    const double a = j.abc.x() * kRad, c = j.abc.z() * kRad;
    const double x = j.xyz.x(), y = j.xyz.y(), z = j.xyz.z();
    const double px = k.rotPoint.x(), py = k.rotPoint.y(), pz = k.rotPoint.z();
    const double dy = k.offset.y(), dz = k.offset.z();
    // xyzac-trt-kins' forward transform (tool offset 0: the joints hold the tip); the tool's
    // axis is the machine's +Z seen from the part, the transform's Z column.
    return Pose{{std::cos(c) * (x - px) + std::sin(c) * std::cos(a) * (y - dy - py) +
                     std::sin(c) * std::sin(a) * (z - dz - pz) + std::sin(c) * dy + px,
                 -std::sin(c) * (x - px) + std::cos(c) * std::cos(a) * (y - dy - py) +
                     std::cos(c) * std::sin(a) * (z - dz - pz) + std::cos(c) * dy + py,
                 -std::sin(a) * (y - dy - py) + std::cos(a) * (z - dz - pz) + dz + pz},
                {std::sin(c) * std::sin(a), std::cos(c) * std::sin(a), std::cos(a)}};
  });
}

TEST_CASE("a table-bc trunnion puts the tip where xyzbc-trt-kins puts it", "[kinematics]") {
  Kinematics k;
  k.type = Kinematics::Type::TableBC;
  k.rotPoint = {-5.0, 18.0, 60.0};
  k.offset = {11.0, 0.0, -35.0};  // x-offset, z-offset
  compareAtRandom(k, 11, [&](const Joints& j) {
    const double b = j.abc.y() * kRad, c = j.abc.z() * kRad;
    const double x = j.xyz.x(), y = j.xyz.y(), z = j.xyz.z();
    const double px = k.rotPoint.x(), py = k.rotPoint.y(), pz = k.rotPoint.z();
    const double dx = k.offset.x(), dz = k.offset.z();
    // xyzbc-trt-kins' forward transform.
    return Pose{{std::cos(c) * std::cos(b) * (x - dx - px) + std::sin(c) * (y - py) -
                     std::cos(c) * std::sin(b) * (z - dz - pz) + std::cos(c) * dx + px,
                 -std::sin(c) * std::cos(b) * (x - dx - px) + std::cos(c) * (y - py) +
                     std::sin(c) * std::sin(b) * (z - dz - pz) - std::sin(c) * dx + py,
                 std::sin(b) * (x - dx - px) + std::cos(b) * (z - dz - pz) + dz + pz},
                {-std::cos(c) * std::sin(b), std::sin(c) * std::sin(b), std::cos(b)}};
  });
}

TEST_CASE("a head-bc machine puts the tip where 5axiskins puts it", "[kinematics]") {
  Kinematics k;
  k.type = Kinematics::Type::HeadBC;
  k.pivotLength = 250.0;
  std::mt19937 rng(13);
  for (int i = 0; i < 200; ++i) {
    const Joints j = randomJoints(rng);
    // 5axiskins: the tip is the joints plus the pivot's height plus the spherical vector of
    // length L at polar angle 180 - B and azimuth C.
    const double L = k.pivotLength, t = j.abc.z() * kRad, p = (180.0 - j.abc.y()) * kRad;
    const Eigen::Vector3d r(L * std::sin(p) * std::cos(t), L * std::sin(p) * std::sin(t),
                            L * std::cos(p));
    const ToolPose pose = k.pose(j.xyz, j.abc);
    checkNear(pose.tip, j.xyz + r + Eigen::Vector3d(0, 0, L));
    // The pivot, L up the tool from the tip, stays where the head holds it.
    checkNear(pose.tip + L * pose.axis, j.xyz + Eigen::Vector3d(0, 0, L));
    CHECK(std::abs(pose.axis.norm() - 1.0) < kTol);
  }
}

TEST_CASE("a head-b-table-c machine agrees with maxkins where one axis is at zero",
          "[kinematics]") {
  // maxkins (its default, unconventional B direction) adds the head's offset after the
  // table's turn; the part frame turns it too. The two agree where B or C is zero, and the
  // tip's distance from C's axis and its height agree everywhere.
  Kinematics k;
  k.type = Kinematics::Type::HeadBTableC;
  k.pivotLength = 80.0;
  std::mt19937 rng(17);
  auto maxkins = [&](const Eigen::Vector3d& xyz, const Eigen::Vector3d& abc) {
    const double L = k.pivotLength, b = abc.y() * kRad;
    const double r = std::hypot(xyz.x(), xyz.y());
    const double th = std::atan2(xyz.y(), xyz.x()) + abc.z() * kRad;
    return Eigen::Vector3d(r * std::cos(th) + L * std::sin(b), r * std::sin(th),
                           xyz.z() - L * std::cos(b) + L);
  };
  for (int i = 0; i < 100; ++i) {
    Joints j = randomJoints(rng);
    Joints noB = j, noC = j;
    noB.abc.y() = 0.0;
    noC.abc.z() = 0.0;
    checkNear(k.pose(noB.xyz, noB.abc).tip, maxkins(noB.xyz, noB.abc));
    checkNear(k.pose(noC.xyz, noC.abc).tip, maxkins(noC.xyz, noC.abc));
    const Eigen::Vector3d ours = k.pose(j.xyz, j.abc).tip, theirs = maxkins(j.xyz, j.abc);
    const Eigen::Vector3d machine =
        j.xyz + Eigen::Vector3d(k.pivotLength * std::sin(j.abc.y() * kRad), 0.0,
                                k.pivotLength * (1.0 - std::cos(j.abc.y() * kRad)));
    CHECK(std::abs(ours.head<2>().norm() - machine.head<2>().norm()) < kTol);
    CHECK(std::abs(ours.z() - theirs.z()) < kTol);
  }
}

TEST_CASE("a 4th axis turns the part about its axis: a tool on top meets the side",
          "[kinematics]") {
  // A cylinder of radius R about X through (0, 20, 30): the tool straight above its axis at
  // Z = 30 + R touches its top; with the table at A = +90 it touches what was the part's
  // side at +Y (Rx(-90) takes +Z to +Y), its axis radial there.
  Kinematics k;
  k.type = Kinematics::Type::TableA;
  k.rotPoint = {0.0, 20.0, 30.0};
  const double R = 15.0;
  const ToolPose top = k.pose({40.0, 20.0, 30.0 + R}, {0.0, 0.0, 0.0});
  checkNear(top.tip, {40.0, 20.0, 30.0 + R});
  checkNear(top.axis, {0.0, 0.0, 1.0});
  const ToolPose side = k.pose({40.0, 20.0, 30.0 + R}, {90.0, 0.0, 0.0});
  checkNear(side.tip, {40.0, 20.0 + R, 30.0});
  checkNear(side.axis, {0.0, 1.0, 0.0});
  // Any angle: the tip stays R from the axis, the tool's axis along the radius.
  for (double a = -400.0; a <= 400.0; a += 37.0) {
    const ToolPose p = k.pose({-3.0, 20.0, 30.0 + R}, {a, 0.0, 0.0});
    const Eigen::Vector3d radial = p.tip - Eigen::Vector3d(p.tip.x(), 20.0, 30.0);
    CHECK(std::abs(radial.norm() - R) < kTol);
    checkNear(p.axis, radial / R);
  }
  // B about Y: Ry(-90) takes +Z to -X.
  k.type = Kinematics::Type::TableB;
  k.rotPoint = {0.0, 0.0, 0.0};
  const ToolPose b = k.pose({0.0, 5.0, R}, {0.0, 90.0, 0.0});
  checkNear(b.tip, {-R, 5.0, 0.0});
  checkNear(b.axis, {-1.0, 0.0, 0.0});
}

TEST_CASE("with tool-centre-point control the program holds the tip", "[kinematics]") {
  std::mt19937 rng(19);
  for (const Kinematics::Type type :
       {Kinematics::Type::TableAC, Kinematics::Type::TableBC, Kinematics::Type::HeadBC}) {
    Kinematics joint;
    joint.type = type;
    joint.rotPoint = {3.0, -4.0, 12.0};
    joint.offset = {2.0, 1.0, -6.0};
    joint.pivotLength = 150.0;
    Kinematics held = joint;
    held.tcp = true;
    for (int i = 0; i < 20; ++i) {
      const Joints j = randomJoints(rng);
      const ToolPose p = held.pose(j.xyz, j.abc);
      checkNear(p.tip, j.xyz);
      checkNear(p.axis, joint.pose(j.xyz, j.abc).axis);
    }
  }
}

TEST_CASE("a trivial machine keeps the tool vertical, and kinematics types go by name",
          "[kinematics]") {
  const Kinematics k;
  const ToolPose p = k.pose({1.0, 2.0, 3.0}, {30.0, 40.0, 50.0});
  checkNear(p.tip, {1.0, 2.0, 3.0});
  checkNear(p.axis, {0.0, 0.0, 1.0});
  CHECK(k.rotaryAxes().empty());
  for (const char* name :
       {"trivial", "table-a", "table-b", "table-ac", "table-bc", "head-bc", "head-b-table-c"})
    CHECK(std::string(kinematicsTypeName(kinematicsTypeOf(name))) == name);
  CHECK_THROWS_AS(kinematicsTypeOf("xyzac"), ParameterError);
  Kinematics ac;
  ac.type = Kinematics::Type::TableAC;
  CHECK(ac.rotaryAxes() == "AC");
}

TEST_CASE("the joints for a tip, and the angles for an axis, undo the pose", "[kinematics]") {
  // Random poses on every chain: joints(tip) puts the tip back where it was; anglesFor(axis)
  // points the tool the same way (checked through the forward map, which the tests above hold
  // to LinuxCNC's equations), the one of its two solutions nearer the given angles.
  std::mt19937 rng(48);
  std::uniform_real_distribution<double> u(-50.0, 50.0), angle(-80.0, 80.0);
  for (const auto type :
       {Kinematics::Type::TableA, Kinematics::Type::TableB, Kinematics::Type::TableAC,
        Kinematics::Type::TableBC, Kinematics::Type::HeadBC, Kinematics::Type::HeadBTableC}) {
    Kinematics k;
    k.type = type;
    k.rotPoint = {3.0, -4.0, -20.0};
    k.offset = {2.0, 1.5, 15.0};
    k.pivotLength = 120.0;
    INFO(kinematicsTypeName(type));
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d xyz(u(rng), u(rng), u(rng)), abc(angle(rng), angle(rng), angle(rng));
      const ToolPose p = k.pose(xyz, abc, false);
      checkNear(k.joints(p.tip, abc), xyz);
      const std::optional<Eigen::Vector3d> back = k.anglesFor(p.axis, abc);
      REQUIRE(back);
      checkNear(k.axis(*back), p.axis);
      // The angles it came from are one solution: the one chosen is no further from them.
      CHECK((*back - abc).cwiseAbs().sum() <= 1e-9);
    }
  }
  // Table A about X: an axis with an X component is out of its reach; C goes the short way
  // round: from C350 the axis of A30 C10 is reached at C370.
  Kinematics a;
  a.type = Kinematics::Type::TableA;
  CHECK_FALSE(a.anglesFor(Eigen::Vector3d(0.6, 0.0, 0.8), Eigen::Vector3d::Zero()));
  Kinematics ac;
  ac.type = Kinematics::Type::TableAC;
  const std::optional<Eigen::Vector3d> c = ac.anglesFor(ac.axis({30.0, 0.0, 10.0}), {30, 0, 350});
  REQUIRE(c);
  checkNear(*c, {30.0, 0.0, 370.0});
  // Within the travel: the axis of A30 C10, (sin A sin C, sin A cos C, cos A), is also A-30
  // with C 10 + 180: C190 or C-170. From A0 C0 the nearest is A30 C10 (40 deg away); a tilt
  // held to -120 .. 0 takes A-30 C-170 (200 away; C190 is 220); C also held to -90 .. 360
  // takes C190; with C to 0 .. 90 no solution is within, and the nearest of all comes back.
  const Eigen::Vector3d want = ac.axis({30.0, 0.0, 10.0}), inf = Eigen::Vector3d::Constant(1e300);
  checkNear(*ac.anglesFor(want, Eigen::Vector3d::Zero()), {30.0, 0.0, 10.0});
  checkNear(*ac.anglesFor(want, Eigen::Vector3d::Zero(), {-120.0, -inf.y(), -inf.z()},
                          {0.0, inf.y(), inf.z()}),
            {-30.0, 0.0, -170.0});
  checkNear(*ac.anglesFor(want, Eigen::Vector3d::Zero(), {-120.0, -inf.y(), -90.0},
                          {0.0, inf.y(), 360.0}),
            {-30.0, 0.0, 190.0});
  checkNear(
      *ac.anglesFor(want, Eigen::Vector3d::Zero(), {-120.0, -inf.y(), 0.0}, {0.0, inf.y(), 90.0}),
      {30.0, 0.0, 10.0});
}
