// Tests of engine/run/Machine.h: the machine description file, its units and its refusals.

#include "engine/run/Machine.h"

#include "cutters/Error.h"

#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>

#include <string>

using namespace engage;
using Catch::Matchers::Contains;

namespace {

std::string errorOf(const std::string& text) {
  const test::TempFolder dir("machine_bad");
  try {
    readMachine(dir.write("machine.json", text));
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("a machine description: positions in mm or inches, the start at G28 or G30",
          "[machine]") {
  const MachineSetup m = readMachine(ENGAGE_SOURCE_DIR "/data/machines/vmc_mm.json");
  CHECK(m.workOffset == Eigen::Vector3d(-250, -200, -180));
  CHECK(m.g30 == Eigen::Vector3d(-10, -10, 0));
  CHECK(m.start == m.g28);  // "start": "g28"
  CHECK(m.limited);
  CHECK(m.travelMin == Eigen::Vector3d(-510, -410, -300));
  // Inches: every number times 25.4 (exact in binary for these values' products to 1e-12).
  const test::TempFolder dir("machine_inch");
  const MachineSetup i = readMachine(
      dir.write("machine.json", R"({"units": "in", "work_offset": [-10, -8, -7], "g30": [-1, -1, 0],
                          "start": "g30"})"));
  CHECK(i.workOffset.x() == Approx(-254.0).margin(1e-12));
  CHECK(i.start.x() == Approx(-25.4).margin(1e-12));
  CHECK_FALSE(i.limited);
  CHECK_FALSE(i.startUnitsGiven);
  // The units it starts up in (G20 at power-on), apart from the file's own units.
  const MachineSetup h = readMachine(dir.write("haas.json", R"({"startup_units": "in"})"));
  CHECK(h.startInch);
  CHECK(h.startUnitsGiven);
}

TEST_CASE("a machine description that cannot be right is refused, naming the key", "[machine]") {
  CHECK_THAT(errorOf(R"({"home": [0, 0, 0]})"), Contains("unknown key \"home\""));
  CHECK_THAT(errorOf(R"({"units": "cm"})"), Contains("\"units\" must be \"mm\" or \"in\""));
  CHECK_THAT(errorOf(R"({"startup_units": "inch"})"),
             Contains("\"startup_units\" must be \"mm\" or \"in\", found \"inch\""));
  CHECK_THAT(errorOf(R"({"g28": [0, 0]})"), Contains("\"g28\" must be [x, y, z]"));
  CHECK_THAT(errorOf(R"({"travel": {"min": [0, 0, 0], "max": [-1, 10, 10]}})"),
             Contains("min must not exceed max along X"));
  CHECK_THAT(errorOf(R"({"start": [5, 0, 0], "travel": {"min": [-9, -9, -9], "max": [0, 0, 0]}})"),
             Contains("\"start\" lies outside the travel along X"));
  CHECK_THAT(errorOf(R"({"g28": [0, 0, 0], "g28": [1, 1, 1]})"),
             Contains("the key \"g28\" is given twice"));
  CHECK_THAT(errorOf("not json"), Contains("not valid JSON"));
}

TEST_CASE("a machine's kinematics: the chain, its points in the file's units, its refusals",
          "[machine]") {
  const test::TempFolder dir("machine_kinematics");
  const MachineSetup m = readMachine(
      dir.write("trunnion.json",
                R"({"units": "in", "kinematics": {"type": "table-ac", "rot_point": [1, 2, -3],
          "offset": [0, 0.5, 1], "tcp": true}})"));
  CHECK(m.kinematics.type == Kinematics::Type::TableAC);
  CHECK(m.kinematics.tcp);
  // Inches to mm: 25.4 exactly.
  CHECK((m.kinematics.rotPoint - Eigen::Vector3d(25.4, 50.8, -76.2)).norm() < 1e-12);
  CHECK((m.kinematics.offset - Eigen::Vector3d(0.0, 12.7, 25.4)).norm() < 1e-12);
  const MachineSetup head = readMachine(
      dir.write("head.json", R"({"kinematics": {"type": "head-bc", "pivot_length": 150}})"));
  CHECK(head.kinematics.pivotLength == 150.0);
  CHECK_FALSE(head.kinematics.tcp);

  CHECK_THAT(errorOf(R"({"kinematics": {"type": "xyzac"}})"),
             Contains("\"kinematics.type\": expected a kinematics type"));
  CHECK_THAT(errorOf(R"({"kinematics": "table-a"})"),
             Contains("must be an object with a \"type\""));
  CHECK_THAT(errorOf(R"({"kinematics": {"type": "head-bc"}})"),
             Contains("\"kinematics.pivot_length\" must be a positive number"));
  CHECK_THAT(errorOf(R"({"kinematics": {"type": "head-bc", "pivot_length": -5}})"),
             Contains("\"kinematics.pivot_length\" must be a positive number"));
  CHECK_THAT(errorOf(R"({"kinematics": {"type": "table-a", "pivot_length": 5}})"),
             Contains("unknown key \"pivot_length\" for type table-a"));
  CHECK_THAT(
      errorOf(R"({"kinematics": {"type": "head-bc", "pivot_length": 5, "offset": [0, 0, 1]}})"),
      Contains("unknown key \"offset\" for type head-bc"));
  CHECK_THAT(errorOf(R"({"kinematics": {"type": "table-ac", "offset": [1, 0, 0]}})"),
             Contains("a table-ac trunnion has no x"));
  CHECK_THAT(errorOf(R"({"kinematics": {"type": "table-bc", "offset": [0, 2, 0]}})"),
             Contains("a table-bc trunnion has no y"));
  CHECK_THAT(errorOf(R"({"kinematics": {"type": "table-a", "tcp": "yes"}})"),
             Contains("\"kinematics.tcp\" must be true or false"));
}

TEST_CASE("a machine's rotary travel: degrees, on the chain's axes only", "[machine]") {
  const test::TempFolder dir("machine_rotary_travel");
  // Degrees whatever the units; X, Y, Z's travel may be left out.
  const MachineSetup m = readMachine(dir.write("ac.json", R"({"units": "in",
      "travel": {"A": [-120, 30]}, "kinematics": {"type": "table-ac"}})"));
  CHECK(m.rotaryMin.x() == -120.0);
  CHECK(m.rotaryMax.x() == 30.0);
  CHECK(std::isinf(m.rotaryMin.z()));  // C: no limit given
  CHECK_FALSE(m.limited);
  CHECK_THAT(errorOf(R"({"travel": {"B": [-90, 90]}, "kinematics": {"type": "table-ac"}})"),
             Contains("\"travel\": \"B\" is not a rotary axis of this machine (its kinematics "
                      "table-ac turns AC)"));
  CHECK_THAT(errorOf(R"({"travel": {"A": [-90, 90]}})"),
             Contains("\"A\" is not a rotary axis of this machine (it has no \"kinematics\")"));
  CHECK_THAT(errorOf(R"({"travel": {"A": [30, -30]}, "kinematics": {"type": "table-a"}})"),
             Contains("\"travel.A\" must be [min, max] in degrees, min not above max"));
  CHECK_THAT(errorOf(R"({"travel": {"A": [10, 90]}, "kinematics": {"type": "table-a"}})"),
             Contains("\"travel.A\" must hold 0 (the rotary axes start there), found [10,90]"));
  CHECK_THAT(errorOf(R"({"travel": {"min": [0, 0, 0]}})"), Contains("\"travel\" must be"));
  CHECK_THAT(errorOf(R"({"travel": {"U": [0, 1]}})"),
             Contains("\"travel\": unknown key \"U\" (expected min, max, A, B, C)"));
}
