// Tests of engine/run/MovesTable.h: the columns a 3-axis program and a rotary machine's get.

#include "engine/run/MovesTable.h"

#include "engine/gcode/GcodeReader.h"

#include <catch2/catch.hpp>

#include <string>

using namespace engage;

TEST_CASE("the moves table: a 3-axis program's columns, and a rotary machine's axes and G93 time",
          "[run]") {
  const std::string program = "G21 G90\nG0 X0 Y0 Z10\nG1 X10 F200\nG93 G1 X20 B30 F4\nM2\n";
  // 3 axes (no kinematics): the rotary words are not columns.
  CHECK(movesTable(readProgramText("G21 G90\nG0 X0 Y0 Z10\nG1 X10 F200\nM2\n", "flat.ngc")) ==
        "line,kind,x,y,z,cx,cy,cz,plane,turns,feed_mm_min\n"
        "2,rapid,0.000000,0.000000,10.000000,,,,,,\n"
        "3,line,10.000000,0.000000,10.000000,,,,,,200\n");
  // A head-head machine: B and C at each move's end, and the tool on the part: at B30 the
  // axis is (-sin 30, 0, cos 30) and the tip 100 mm below the pivot, (100 sin 30, 0,
  // 100 (1 - cos 30)) = (50, 0, 13.3975) from the joints' point. The G93 move lasts 1/F =
  // 0.25 min, its feed column the XYZ speed that takes (10 mm in 0.25 min: 40 mm/min).
  ReaderOptions o;
  MachineSetup m;
  m.name = "head.json";
  m.kinematics.type = Kinematics::Type::HeadBC;
  m.kinematics.pivotLength = 100.0;
  o.machine = m;
  CHECK(movesTable(readProgramText(program, "head.ngc", o)) ==
        "line,kind,x,y,z,a_deg,b_deg,c_deg,tip_x,tip_y,tip_z,axis_i,axis_j,axis_k,cx,cy,cz,"
        "plane,turns,feed_mm_min,minutes\n"
        "2,rapid,0.000000,0.000000,10.000000,0.000000,0.000000,0.000000,0.000000,0.000000,"
        "10.000000,0.000000,0.000000,1.000000,,,,,,,\n"
        "3,line,10.000000,0.000000,10.000000,0.000000,0.000000,0.000000,10.000000,0.000000,"
        "10.000000,0.000000,0.000000,1.000000,,,,,,200,\n"
        "4,line,20.000000,0.000000,10.000000,0.000000,30.000000,0.000000,70.000000,0.000000,"
        "23.397460,-0.500000,0.000000,0.866025,,,,,,40,0.25\n");
  // A value that rounds to zero is written without a sign: on a tilted plane G53.1 leaves
  // joints at -1e-15 or so (I0 J-30 on this chain's A: the plane's X along the part's).
  m.kinematics = Kinematics{};
  m.kinematics.type = Kinematics::Type::TableAC;
  o.machine = m;
  const std::string table = movesTable(readProgramText(
      "G21 G90 G94\nG0 X0 Y0 Z60\nG68.2 X10 Y10 Z0 I0 J-30 K0\nG53.1\nG0 X0 Y0 Z10\n"
      "G1 X5 F100\nG69\nG0 Z80\nM2\n",
      "plane.ngc", o));
  CHECK(table.find("-0.000000") == std::string::npos);
  CHECK(table.find(",0.000000,") != std::string::npos);
}
