// Tests of engine/tools/ToolLibrary.h: each format read into the same cutters, checked against
// the geometry the file states (diameters, corner radii, cone radii at a height by hand), and
// the errors a user meets, each naming the tool, the field and the file.

#include "engine/tools/ToolLibrary.h"

#include "cutters/Error.h"
#include "tests/engine/run/RunTestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;

namespace {

const std::string kTools = ENGAGE_SOURCE_DIR "/data/tools/";

/// The message of the ParameterError `f` throws ("" when it does not throw).
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.what();
  }
  return "";
}

const AptCutter& cutterOf(const ToolLibrary& lib, int number) {
  return *lib.require(number).cutter;
}

}  // namespace

// The three tools of data/gcode/multitool/three_tools.ngc as every format states them: a 6 mm
// flat with 3 flutes and 18 mm of cut, a 4 mm ball, a 6 mm 90 deg V-bit (cone radius equal to
// the height above the tip). Tolerances: 1e-9 mm, the rounding of unit conversions. CAMotics
// does not state flutes: 2, engage's default, there.
void checkThreeTools(const ToolLibrary& lib, int flatFlutes = 3) {
  const AptCutter& flat = cutterOf(lib, 1);
  CHECK(flat.shape() == CutterShape::Flat);
  CHECK(flat.radius() == Approx(3.0).margin(1e-9));
  CHECK(flat.fluteCount() == flatFlutes);
  CHECK(flat.height() == Approx(18.0).margin(1e-9));
  const AptCutter& ball = cutterOf(lib, 2);
  CHECK(ball.shape() == CutterShape::Ball);
  CHECK(ball.radius() == Approx(2.0).margin(1e-9));
  CHECK(ball.parameters().cornerRadius == Approx(2.0).margin(1e-9));
  const AptCutter& vbit = cutterOf(lib, 3);
  CHECK(vbit.shape() == CutterShape::Chamfer);
  // 90 deg included: the cone's radius at height z is z tan 45 deg = z.
  CHECK(vbit.radiusAt(1.0) == Approx(1.0).margin(1e-9));
  CHECK(vbit.radiusAt(2.5) == Approx(2.5).margin(1e-9));
  CHECK(vbit.maxRadius() == Approx(3.0).margin(1e-9));
}

TEST_CASE("a LinuxCNC tool table gives each T its cutter from D and the comment", "[tools]") {
  const ToolLibrary lib = readToolLibrary(kTools + "three_tools.tbl");
  CHECK(lib.format == "linuxcnc");
  REQUIRE(lib.tools.size() == 4);
  checkThreeTools(lib);
  const ToolEntry& bull = lib.require(4);
  CHECK(bull.cutter->shape() == CutterShape::Bull);
  CHECK(bull.cutter->radius() == Approx(5.0).margin(1e-9));
  CHECK(bull.cutter->parameters().cornerRadius == Approx(1.0).margin(1e-9));
  CHECK(bull.origin == kTools + "three_tools.tbl:4");
  CHECK(bull.name == "10 mm bull nose bull r=1 flutes=4");

  SECTION("in inches when the machine is") {
    ToolLibraryOptions inch;
    inch.linuxcncInch = true;
    const ToolLibrary lib2 =
        parseToolLibrary("T5 P5 Z1.0 D0.25 ;1/4 ball r=0.1 (not read: ball)\n", "t.tbl", inch);
    // 0.25 in = 6.35 mm.
    CHECK(cutterOf(lib2, 5).radius() == Approx(3.175).margin(1e-9));
    CHECK(cutterOf(lib2, 5).shape() == CutterShape::Ball);
  }
  SECTION("an unreadable word stops the reading at its line") {
    CHECK(errorOf([] { parseToolLibrary("T1 D6\nT2 D4 Zed\n", "shop.tbl"); }) ==
          "shop.tbl:2: expected a word such as T1, D6 or Z35, found 'Zed'");
    CHECK(errorOf([] { parseToolLibrary("P1 D6\n", "shop.tbl"); }) ==
          "shop.tbl:1: expected a T word (the tool number), found none");
  }
  SECTION("a tool without a buildable shape is an error only when used") {
    const ToolLibrary shop = parseToolLibrary(
        "T1 D6 ;flat\nT2 Z30 ;no diameter\nT3 D6 ;bull without its radius\n"
        "T4 D6 ;bull r=4\nT5 D6 ;vbit\n",
        "shop.tbl");
    CHECK(cutterOf(shop, 1).radius() == Approx(3.0).margin(1e-9));
    CHECK(errorOf([&] { shop.require(2); }) ==
          "tool T2 (no diameter) at shop.tbl:2: D (the diameter) is missing");
    CHECK_THAT(errorOf([&] { shop.require(3); }), Catch::Contains("without r="));
    CHECK_THAT(errorOf([&] { shop.require(4); }),
               Catch::Contains("corner radius 4 mm is larger than the radius 3 mm"));
    CHECK_THAT(errorOf([&] { shop.require(5); }), Catch::Contains("without angle="));
  }
}

TEST_CASE("a Fusion 360 library gives numbered tools, their holders, in either unit", "[tools]") {
  const ToolLibrary lib = readToolLibrary(kTools + "three_tools.json");
  CHECK(lib.format == "fusion360");
  // The probe is no cutter and the holder no tool: neither is listed.
  CHECK(lib.tools.size() == 3);
  CHECK(lib.numbered(99).empty());
  checkThreeTools(lib);
  const ToolEntry& t1 = lib.require(1);
  CHECK(t1.name == "6 mm flat end mill");
  CHECK(t1.stickout == Approx(25.0).margin(1e-9));
  CHECK(t1.shankDiameter == Approx(6.0).margin(1e-9));
  REQUIRE(t1.holder.size() == 2);
  CHECK(t1.holder[1].height == Approx(30.0).margin(1e-9));
  CHECK(t1.holder[1].upperDiameter == Approx(40.0).margin(1e-9));
  CHECK(t1.holderName == "ER16 collet chuck");

  const std::string inches = R"({"data": [
      {"type": "bull nose end mill", "unit": "inches", "description": "1/2 bull",
       "geometry": {"DC": 0.5, "RE": 0.0625, "LCF": 1.0, "NOF": 4},
       "post-process": {"number": 7}},
      {"type": "bull nose end mill", "unit": "millimeters", "description": "bad",
       "geometry": {"DC": 6, "RE": 4}, "post-process": {"number": 8}},
      {"type": "flat end mill", "description": "no unit",
       "geometry": {"DC": 6}, "post-process": {"number": 9}},
      {"type": "thread mill", "unit": "millimeters", "description": "M6 thread mill",
       "geometry": {"DC": 4.8}, "post-process": {"number": 10}},
      {"type": "flat end mill", "unit": "millimeters", "description": "spare",
       "geometry": {"DC": 6}, "post-process": {"number": 0}}]})";
  const ToolLibrary mixed = parseToolLibrary(inches, "mixed.json");
  // 0.5 in = 12.7 mm, 0.0625 in = 1.5875 mm, 1 in = 25.4 mm.
  const AptCutter& bull = cutterOf(mixed, 7);
  CHECK(bull.radius() == Approx(6.35).margin(1e-9));
  CHECK(bull.parameters().cornerRadius == Approx(1.5875).margin(1e-9));
  CHECK(bull.height() == Approx(25.4).margin(1e-9));
  CHECK(bull.fluteCount() == 4);
  CHECK(errorOf([&] { mixed.require(8); }) ==
        "tool T8 (bad) at mixed.json: tool 2 of \"data\": corner radius 4 mm is larger than the "
        "radius 3 mm");
  CHECK_THAT(errorOf([&] { mixed.require(9); }), Catch::Contains("unit is missing"));
  CHECK_THAT(errorOf([&] { mixed.require(10); }),
             Catch::Contains("type \"thread mill\" is not a cutter engage can sweep"));
  // Number 0: not in the magazine.
  CHECK(mixed.tools.size() == 4);
}

TEST_CASE("a FreeCAD library finds its bits in ../Bit and reads their quantities", "[tools]") {
  const ToolLibrary lib = readToolLibrary(kTools + "freecad/Library/three_tools.fctl");
  CHECK(lib.format == "freecad");
  checkThreeTools(lib);
  CHECK(lib.require(2).name == "4mm Ballend");
  CHECK(lib.require(1).overallLength == Approx(57.0).margin(1e-9));

  SECTION("one bit alone is tool 1; a bull nose from its flat radius") {
    const ToolLibrary bit = parseToolLibrary(
        R"({"name": "8mm bull", "shape": "bullnose.fcstd",
            "parameter": {"Diameter": "8 mm", "FlatRadius": "3 mm", "CuttingEdgeHeight": "20 mm"}})",
        "bull.fctb");
    // Corner radius = D/2 - flat radius = 4 - 3 = 1 mm.
    CHECK(cutterOf(bit, 1).parameters().cornerRadius == Approx(1.0).margin(1e-9));
    CHECK(cutterOf(bit, 1).radius() == Approx(4.0).margin(1e-9));
  }
  SECTION("a missing bit names its path") {
    test::TempFolder dir("tools_fctl");
    const std::string fctl =
        dir.write("lib.fctl", R"({"tools": [{"nr": 4, "path": "gone.fctb"}], "version": 1})");
    const ToolLibrary lib2 = readToolLibrary(fctl);
    CHECK_THAT(errorOf([&] { lib2.require(4); }),
               Catch::Contains("path \"gone.fctb\": no such tool bit"));
  }
}

TEST_CASE("a CAMotics tool table in imperial and metric", "[tools]") {
  const ToolLibrary lib = readToolLibrary(kTools + "three_tools.camotics");
  CHECK(lib.format == "camotics");
  // CAMotics' length is the whole cutting length: 18 mm for T1, as in the other formats.
  checkThreeTools(lib, 2);
  const ToolLibrary inch = parseToolLibrary(
      R"({"tools": {"1": {"units": "imperial", "shape": "cylindrical", "length": 1,
                          "diameter": 0.125},
                    "2": {"units": "imperial", "shape": "snubnose", "length": 0.5,
                          "diameter": 0.25, "snub_diameter": 0.05},
                    "3": {"units": "furlongs", "shape": "cylindrical", "length": 1,
                          "diameter": 1}}})",
      "p.camotics");
  // 1/8 in = 3.175 mm diameter.
  CHECK(cutterOf(inch, 1).radius() == Approx(1.5875).margin(1e-9));
  CHECK(cutterOf(inch, 1).height() == Approx(25.4).margin(1e-9));
  // Snub: a cone from 0.05 in at the tip to 0.25 in at 0.5 in up: radius at mid-height
  // (0.025 + 0.125) / 2 in = 0.075 in = 1.905 mm.
  CHECK(cutterOf(inch, 2).radiusAt(0.25 * 25.4) == Approx(1.905).margin(1e-9));
  CHECK_THAT(errorOf([&] { inch.require(3); }), Catch::Contains("units \"furlongs\""));
}

TEST_CASE("a library's numbering errors name the tools", "[tools]") {
  const ToolLibrary lib = parseToolLibrary("T1 D6\nT2 D4\nT1 D8\n", "dup.tbl");
  CHECK(errorOf([&] { lib.require(1); }) ==
        "dup.tbl: 2 tools are numbered T1 (dup.tbl:1, dup.tbl:3): number them apart");
  CHECK(errorOf([&] { lib.require(7); }) == "dup.tbl: no tool T7 (it has T1, T2)");
  CHECK_THAT(errorOf([] { parseToolLibrary("{\"data\": [", "cut.json"); }),
             Catch::StartsWith("cut.json: not valid JSON"));
  CHECK_THAT(errorOf([] { parseToolLibrary("{\"machine\": 1}", "other.json"); }),
             Catch::Contains("none of \"data\""));
  CHECK_THAT(errorOf([] { readToolLibrary(kTools + "no_such_file.tbl"); }),
             Catch::Contains("cannot read the tool library"));
}
