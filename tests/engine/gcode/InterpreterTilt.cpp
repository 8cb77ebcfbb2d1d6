// Tool centre point control (G43.4, G234), the dynamic work offset (G254) and the tilted work
// plane (G68.2, G53.1, G69): engine/gcode/InterpreterTilt.cpp.

#include "engine/gcode/GcodeReader.h"
#include "engine/sim/ToolPoses.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <string>

using namespace engage;
using Catch::Matchers::Contains;

namespace {

constexpr double kTight = 1e-9;  // mm: sums of a few products of numbers below 1000

ReaderOptions onMachine(Kinematics::Type type, bool tcp = false) {
  ReaderOptions o;
  MachineSetup m;
  m.name = "five.json";
  m.kinematics.type = type;
  m.kinematics.tcp = tcp;
  m.kinematics.rotPoint = {3.0, -4.0, -20.0};
  m.kinematics.offset = {2.0, 1.5, 15.0};
  m.kinematics.pivotLength = 120.0;
  m.workOffset = {-300.0, -200.0, -250.0};
  m.start = {0.0, 0.0, 0.0};
  o.machine = m;
  return o;
}

ToolPose poseAt(const Toolpath& p, const Move& m, bool end) {
  return movePose(m, p.kinematics, p.frameOf(m), end ? m.end : m.start,
                  end ? m.rotaryEnd : m.rotaryStart);
}

void checkNear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = kTight) {
  INFO("(" << a.transpose() << ") vs (" << b.transpose() << ")");
  CHECK((a - b).norm() <= tol);
}

}  // namespace

TEST_CASE("G68.2's origin and Euler angles put the program on the part and G53.1 points the tool",
          "[gcode]") {
  // G68.2 X10 Y5 Z2 I90 J30 K0: the plane's frame is Rz(90) Rx(30) (Fanuc: I about Z, J about
  // the turned X, K about the twice-turned Z), its origin (10, 5, 2) in G54. By hand, the
  // plane's (1, 2, 3): Rx(30) gives (1, 2 cos30 - 3 sin30, 2 sin30 + 3 cos30) = (1, 0.2320508,
  // 3.5980762); Rz(90) turns (x, y) into (-y, x): (-0.2320508, 1, 3.5980762); plus the origin.
  // The plane's Z: Rz(90) (0, -sin30, cos30) = (0.5, 0, 0.8660254). On the table-ac trunnion
  // (axis (sin A sin C, sin A cos C, cos A)) G53.1 turns A30 C90 or A-30 C-90, equally far
  // from A0 C0: the positive tilt.
  const Toolpath p = readProgramText(
      "G21 G90 G54\nG0 Z50\nG68.2 X10 Y5 Z2 I90 J30 K0\nG53.1\nG0 X1 Y2 Z3\nG69\nM2\n", "plane.ngc",
      onMachine(Kinematics::Type::TableAC));
  REQUIRE(p.moves.size() == 3);
  const Move& turnMove = p.moves[1];
  CHECK(turnMove.kind == MoveKind::Rapid);
  CHECK_FALSE(turnMove.tipHeld);  // (the joints hold still while the table turns)
  checkNear(turnMove.rotaryEnd, {30.0, 0.0, 90.0});
  const ToolPose at = poseAt(p, p.moves[2], true);
  checkNear(at.tip, {10.0 - 0.2320508075688772, 6.0, 2.0 + 3.598076211353316});
  checkNear(at.axis, {0.5, 0.0, std::sqrt(0.75)});
  CHECK(p.moves[2].tipHeld);
  CHECK(p.moves[2].frame == 1);
  // The program's own words stay in the plane's terms (a re-fed program writes them back).
  checkNear(p.moves[2].end, {1.0, 2.0, 3.0});
}

TEST_CASE("the tip never jumps between moves, whatever the five-axis modes switch", "[gcode]") {
  // Random programs on every chain without the controller's tip control: lines and rotary turns
  // (under G43.5 as the tool's axis I, J, K) with G43.4 / G43.5 / G234 / G49, G254 / G255 and
  // G68.2 + G53.1 / G69 switched in between. Each
  // switch reads the position back as the controller does (joints <-> tip, work <-> plane),
  // so where one move ends the next starts, on the part, to rounding.
  std::mt19937 rng(20261129);
  std::uniform_real_distribution<double> u(-40.0, 40.0), angle(-60.0, 60.0);
  for (const auto type :
       {Kinematics::Type::TableA, Kinematics::Type::TableB, Kinematics::Type::TableAC,
        Kinematics::Type::TableBC, Kinematics::Type::HeadBC, Kinematics::Type::HeadBTableC}) {
    Kinematics k;
    k.type = type;
    const std::string letters = k.rotaryAxes();
    for (int program = 0; program < 20; ++program) {
      std::string text = "G21 G90 G54\nG0 X0 Y0 Z60\n";
      bool dwo = false, plane = false, vector = false;  // (vector: G43.5 in force)
      auto num = [&](double v) { return std::to_string(v); };
      for (int line = 0; line < 12; ++line) {
        const int what = static_cast<int>(rng() % 9);
        if (what == 0) text += "G43.4 H1\n";
        if (what == 1) text += "G234 H1\n";
        if (what == 2) text += "G49\n";
        if (what == 8) text += "G43.5 H1\n";
        if (what <= 2 || what == 8) vector = what == 8;
        if (what == 3 && !plane) {
          text += dwo ? "G255\n" : "G254\n";
          dwo = !dwo;
        }
        if (what == 4 && !dwo) {
          if (plane) {
            text += "G69\n";
          } else {
            // Planes the chain can reach: the tilt about its own axis, any turn about Z when
            // it has a C.
            const bool spin = letters.size() > 1;
            const double tilt = angle(rng);
            text += "G68.2 X" + num(u(rng)) + " Y" + num(u(rng)) + " Z" + num(u(rng)) +
                    (letters[0] == 'A' ? " I0 J" + num(tilt) : " I90 J" + num(tilt)) + " K" +
                    (spin ? num(angle(rng)) : std::string("0")) + "\nG53.1\n";
          }
          plane = !plane;
        }
        if (what == 5 && !dwo && !plane) {
          // The angles, or under G43.5 the tool's axis they give (one the chain reaches).
          std::string words;
          Eigen::Vector3d abc = Eigen::Vector3d::Zero();
          for (const char a : letters) {
            abc[a - 'A'] = angle(rng);
            words += std::string(" ") + a + num(abc[a - 'A']);
          }
          if (vector) {
            const Eigen::Vector3d v = k.axis(abc);
            char ijk[96];
            std::snprintf(ijk, sizeof ijk, " I%.15f J%.15f K%.15f", v.x(), v.y(), v.z());
            words = ijk;
          }
          text += "G0" + words + "\n";
        }
        text += "G1 X" + num(u(rng)) + " Y" + num(u(rng)) + " Z" + num(u(rng) + 40.0) + " F500\n";
      }
      text += "M2\n";
      INFO(kinematicsTypeName(type) << " program " << program << ":\n" << text);
      const Toolpath p = readProgramText(text, "modes.ngc", onMachine(type));
      REQUIRE(p.moves.size() >= 12);
      for (std::size_t i = 1; i < p.moves.size(); ++i) {
        INFO("move " << i << " (line " << p.moves[i].line << ")");
        checkNear(poseAt(p, p.moves[i - 1], true).tip, poseAt(p, p.moves[i], false).tip, 1e-8);
      }
    }
  }
}

TEST_CASE("G43.4 and G234 hold the tip like a TCP machine and G49 lets go", "[gcode]") {
  // The same words on a joints machine under G43.4 (or G234) and on one whose controller
  // always holds the tip: the same poses.
  const std::string body = "G0 X5 Y-3 Z40 A-30 C20\nG1 X12 Y4 Z-1 A-10 C60 F500\n";
  const Toolpath held = readProgramText("G21 G90\n" + body + "M2\n", "tcp.ngc",
                                        onMachine(Kinematics::Type::TableAC, true));
  for (const char* code : {"G43.4 H1", "G234 H1"}) {
    const Toolpath p = readProgramText(std::string("G21 G90\n") + code + "\n" + body + "G49\nM2\n",
                                       "g434.ngc", onMachine(Kinematics::Type::TableAC));
    REQUIRE(p.moves.size() == held.moves.size());
    for (std::size_t i = 0; i < p.moves.size(); ++i) {
      CHECK(p.moves[i].tipHeld);
      const ToolPose a = poseAt(p, p.moves[i], true), b = poseAt(held, held.moves[i], true);
      checkNear(a.tip, b.tip);
      checkNear(a.axis, b.axis);
    }
  }
  // After G49 the words are the joints again.
  const Toolpath after = readProgramText("G21 G90\nG43.4 H1\n" + body + "G49\nG1 X0 F500\nM2\n",
                                         "g49.ngc", onMachine(Kinematics::Type::TableAC));
  CHECK_FALSE(after.moves.back().tipHeld);
}

TEST_CASE("five-axis words where the controller refuses them", "[gcode]") {
  const ReaderOptions ac = onMachine(Kinematics::Type::TableAC);
  // Haas: cancel G254 with G255 before any rotary motion.
  CHECK_THROWS_WITH(readProgramText("G21\nG254\nG0 C90\nM2\n", "dwo.ngc", ac),
                    Contains("dwo.ngc:3:4: expected G255 (the dynamic work offset off) before "
                             "rotary motion, found C90 with G254 in force"));
  CHECK_THROWS_WITH(readProgramText("G21\nG68.2 J30\nG68.2 J10\nM2\n", "twice.ngc", ac),
                    Contains("twice.ngc:3:1: expected G69 before another G68.2"));
  CHECK_THROWS_WITH(readProgramText("G21\nG53.1\nM2\n", "none.ngc", ac),
                    Contains("none.ngc:2:1: expected a tilted work plane (G68.2) before G53.1"));
  CHECK_THROWS_WITH(readProgramText("G21\nG68.2 J30\nG55\nM2\n", "offset.ngc", ac),
                    Contains("offset.ngc:3:1: expected G69 (the tilted work plane off) before "
                             "G55, found G68.2 in force"));
  CHECK_THROWS_WITH(readProgramText("G21\nG68.2 J30\nG53 G0 Z0\nM2\n", "g53.ngc", ac),
                    Contains("g53.ngc:3:1: expected G69 (the tilted work plane off) before G53"));
  // A 4th axis about X cannot point the tool across X: Rz(90) Rx(30) z = (0.5, 0, 0.866).
  CHECK_THROWS_WITH(
      readProgramText("G21\nG68.2 I90 J30\nG53.1\nM2\n", "reach.ngc",
                      onMachine(Kinematics::Type::TableA)),
      Contains("reach.ngc:3:1: expected a tilted work plane whose Z the rotary axes of table-a "
               "can reach, found Z along (0.5, 0, 0.866025)"));
  // Without rotary axes G53.1 has nothing to turn.
  CHECK_THROWS_WITH(readProgramText("G21\nG68.2 J30\nG53.1\nM2\n", "flat.ngc", {}),
                    Contains("flat.ngc:3:1: expected the machine's rotary axes to turn the tool"));
}

TEST_CASE("an arc on a tilted plane stays on its circle in the plane", "[gcode]") {
  // G68.2 J90 (Rx(90): the plane's (x, y, z) is the part's (x, -z, y)) with its origin at
  // (0, -10, 0); a G3 half circle of radius 5 about the plane's (0, 0): on the part, the
  // circle about (0, -10, 0) in the plane y = -10 - z_plane (z_plane = -1: y = -9).
  const Toolpath p = readProgramText(
      "G21 G90\nG68.2 X0 Y-10 Z0 I0 J90 K0\nG53.1\nG0 X5 Y0 Z10\nG1 Z-1 F100\nG3 X-5 Y0 I-5 J0\n"
      "G69\nM2\n",
      "arc.ngc", onMachine(Kinematics::Type::TableAC));
  const Move& arc = p.moves.back();
  REQUIRE(arc.kind == MoveKind::Arc);
  const StepPath sp = stepPath(arc, 0.0, 1.0, p);
  REQUIRE(sp.kind == StepPath::Kind::Polyline);
  for (const Eigen::Vector3d& q : sp.points) {
    CHECK(q.y() == Approx(-9.0).margin(kTight));
    CHECK(std::hypot(q.x(), q.z()) == Approx(5.0).margin(kTight));
  }
  checkNear(sp.points[4], {0.0, -9.0, 5.0});  // half way round, counter-clockwise seen from +z'
  checkNear(sp.axisEnd, {0.0, -1.0, 0.0});
}

TEST_CASE("G43.5's tool axis I, J, K turns the rotary axes as G43.4's angles do", "[gcode]") {
  // Fanuc's tool centre point control type 2: the axis at each line's end, an omitted component
  // 0, none at all: the axis stays. By hand, the chains' axes:
  // - head-bc (-sin B cos C, -sin B sin C, cos B): (0, 0.5, sqrt(3)/2) is B30 C-90 or B-30 C90,
  //   as far from B0 C0; the first, B30 C-90. Then (0.5, 0, sqrt(3)/2): B30 C-180 (90 deg of C
  //   away) against B-30 C0 (150 away);
  // - table-ac (sin A sin C, sin A cos C, cos A): A30 C0, then A30 C90.
  const std::string axes =
      "G1 X5 Y2 Z1 J0.5 K0.866025403784439 F300\nG1 X9 Y-1 I0.5 J0 K0.866025403784439\n"
      "G1 X12\nG1 Z3 K1\n";
  const std::pair<Kinematics::Type, std::string> cases[] = {
      {Kinematics::Type::HeadBC,
       "G1 X5 Y2 Z1 B30 C-90 F300\nG1 X9 Y-1 B30 C-180\nG1 X12\n"
       "G1 Z3 B0\n"},
      {Kinematics::Type::TableAC,
       "G1 X5 Y2 Z1 A30 C0 F300\nG1 X9 Y-1 A30 C90\nG1 X12\n"
       "G1 Z3 A0\n"}};
  for (const auto& [type, angles] : cases) {
    INFO(kinematicsTypeName(type));
    const std::string head = "G21 G90\nG0 X0 Y0 Z40\n";
    const Toolpath vector =
        readProgramText(head + "G43.5 H1\n" + axes + "G49\nM2\n", "g435.ngc", onMachine(type));
    const Toolpath turned =
        readProgramText(head + "G43.4 H1\n" + angles + "G49\nM2\n", "g434.ngc", onMachine(type));
    REQUIRE(vector.moves.size() == turned.moves.size());
    for (std::size_t i = 0; i < vector.moves.size(); ++i) {
      INFO("move " << i);
      // (K to 15 digits: the angles to about 1e-12 deg)
      checkNear(vector.moves[i].rotaryEnd, turned.moves[i].rotaryEnd, 1e-9);
      const ToolPose a = poseAt(vector, vector.moves[i], true);
      const ToolPose b = poseAt(turned, turned.moves[i], true);
      checkNear(a.tip, b.tip);
      checkNear(a.axis, b.axis);
      CHECK(vector.moves[i].axisVector == (i >= 1));
    }
  }
  // On a tilted plane the axis is the plane's: G68.2 J30 is Rx(30), whose (0, 0, 1) is the
  // part's (0, -0.5, sqrt(3)/2); on the trunnion A-30 C0 (30 deg away) rather than A30 C180.
  const Toolpath plane =
      readProgramText("G21 G90\nG68.2 X0 Y0 Z0 I0 J30 K0\nG43.5 H1\nG1 X1 K1 F200\nG69\nM2\n",
                      "plane35.ngc", onMachine(Kinematics::Type::TableAC));
  checkNear(plane.moves.back().rotaryEnd, {-30.0, 0.0, 0.0}, 1e-9);
  checkNear(poseAt(plane, plane.moves.back(), true).axis, {0.0, -0.5, std::sqrt(0.75)});
}

TEST_CASE("G43.5 words the controller refuses", "[gcode]") {
  const ReaderOptions ac = onMachine(Kinematics::Type::TableAC);
  const ReaderOptions head = onMachine(Kinematics::Type::HeadBC);
  CHECK_THROWS_WITH(readProgramText("G21\nG43.5 H1\nG1 X1 A30 F100\nM2\n", "abc.ngc", ac),
                    Contains("abc.ngc:3:7: expected the tool's axis as I, J, K under G43.5 (tool "
                             "centre point control type 2), found A30"));
  CHECK_THROWS_WITH(readProgramText("G21\nG43.5 H1 Q2\nM2\n", "q.ngc", head),
                    Contains("q.ngc:2:10: expected no tool inclination with G43.5"));
  CHECK_THROWS_WITH(readProgramText("G21\nG43.5 H1 P1\nM2\n", "p.ngc", head),
                    Contains("p.ngc:2:10: expected P0 (conventional control: the rotary axes "
                             "turn evenly) with G43.5, found P1 (tool posture control)"));
  CHECK_THROWS_WITH(readProgramText("G21\nG43.5 H1\nG2 X2 I1 J0 F100\nM2\n", "arc.ngc", ac),
                    Contains("arc.ngc:3:7: expected G0 or G1 with the tool's axis I, J, K under "
                             "G43.5 (arcs take R), found G2"));
  // Fanuc's PS5421: I, J, K on the G43.5 line only where the head turns the tool.
  CHECK_THROWS_WITH(readProgramText("G21\nG43.5 H1 X0 Y0 Z5 J0.5 K0.8\nM2\n", "line.ngc", ac),
                    Contains("line.ngc:2:19: expected I, J, K on the G43.5 line only on a machine "
                             "whose head turns the tool, found them on table-ac (five.json)"));
  CHECK_NOTHROW(readProgramText("G21\nG0 Z5\nG43.5 H1 X0 Y0 Z5 J0.5 K0.8\nM2\n", "h.ngc", head));
  // A 4th axis about X cannot lean the tool along X.
  CHECK_THROWS_WITH(
      readProgramText("G21\nG43.5 H1\nG1 X1 I0.5 K0.8 F100\nM2\n", "reach.ngc",
                      onMachine(Kinematics::Type::TableA)),
      Contains("reach.ngc:3:7: expected a tool axis the rotary axes of table-a can reach, found "
               "(0.5, 0, 0.8)"));
  CHECK_THROWS_WITH(readProgramText("G21\nG43.5 H1\nG1 X1 I0 J0 K0 F100\nM2\n", "zero.ngc", ac),
                    Contains("zero.ngc:3:7: expected a tool axis I, J, K of some length, found "
                             "(0, 0, 0)"));
  // Without rotary axes only the upright axis.
  CHECK_NOTHROW(readProgramText("G21\nG43.5 H1\nG1 X1 K1 F100\nM2\n", "up.ngc", {}));
  CHECK_THROWS_WITH(readProgramText("G21\nG43.5 H1\nG1 X1 J1 F100\nM2\n", "flat5.ngc", {}),
                    Contains("flat5.ngc:3:7: expected the machine's rotary axes to turn the tool"));
}

TEST_CASE("the rotary axes' travel, and the joints' on their way while the tip is held",
          "[gcode]") {
  ReaderOptions o;
  MachineSetup m;
  m.name = "a.json";
  m.kinematics.type = Kinematics::Type::TableA;  // A about X through the work origin
  m.rotaryMin = {-100.0, 0.0, 0.0};
  m.rotaryMax = {95.0, 0.0, 0.0};
  o.machine = m;
  CHECK_NOTHROW(readProgramText("G21\nG0 A-100\nG0 A95\nM2\n", "in.ngc", o));
  CHECK_THROWS_WITH(readProgramText("G21\nG0 A-90\nG0 A96\nM2\n", "a.ngc", o),
                    Contains("a.ngc:3:1: expected moves within the travel of the machine (a.json: "
                             "A -100 deg to 95 deg), found one to A 96 deg"));
  // The tip held at (0, 0, 50) while A turns -90 -> 90: the joints are Rx(A) (0, 0, 50) =
  // (0, -50 sin A, 50 cos A), Z 0 at both ends and 50 at A0, half way. Z's travel to 40.
  o.machine->limited = true;
  o.machine->travelMin = {-100.0, -100.0, -100.0};
  o.machine->travelMax = {100.0, 100.0, 40.0};
  const std::string turn = "G21 G90\nG0 A-90\nG43.4 H1\nG0 X0 Y0 Z50\nG1 A90 F1000\nM2\n";
  CHECK_THROWS_WITH(readProgramText(turn, "held.ngc", o),
                    Contains("held.ngc:5:1: expected moves within the travel of the machine "
                             "(a.json: Z -100 mm to 40 mm, machine coordinates), found one "
                             "through Z 50 mm on its way, the rotary axes turning"));
  // Its ends alone are within: A -90 (0, 50, 0) and A90 (0, -50, 0).
  o.machine->travelMax.z() = 50.0;
  CHECK_NOTHROW(readProgramText(turn, "held.ngc", o));
}

TEST_CASE("G43.5 and G53.1 take the solution within the rotary travel", "[gcode]") {
  // The trunnion's axis (sin A sin C, sin A cos C, cos A): (0, 0.5, sqrt(3)/2) is A30 C0, 30 deg
  // from A0 C0, or A-30 C180 (or C-180), 210 away. With A held to -120 .. 0 the second.
  ReaderOptions o = onMachine(Kinematics::Type::TableAC);
  o.machine->rotaryMin = {-120.0, 0.0, -1e300};
  o.machine->rotaryMax = {0.0, 0.0, 1e300};
  for (const char* program : {"G21\nG43.5 H1\nG1 X1 J0.5 K0.866025403784439 F100\nM2\n",
                              "G21\nG68.2 X0 Y0 Z0 I180 J30 K180\nG53.1\nM2\n"}) {
    INFO(program);
    const Toolpath p = readProgramText(program, "within.ngc", o);
    const Move& last = p.moves.back();
    CHECK(last.rotaryEnd.x() == Approx(-30.0).margin(1e-9));
    CHECK(std::abs(last.rotaryEnd.z()) == Approx(180.0).margin(1e-9));
    checkNear(o.machine->kinematics.axis(last.rotaryEnd), {0.0, 0.5, std::sqrt(0.75)});
  }
}
