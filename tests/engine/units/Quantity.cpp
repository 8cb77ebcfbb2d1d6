// Tests of engine/units/Quantity.h: every suffix family, bare numbers, errors, formatting.
// Conversion factors are exact by definition (1 in = 25.4 mm, 1 g = 9806.65 mm/s^2), so the
// expected values are computed here from those definitions; 1e-12 relative is round-off.

#include "engine/units/Quantity.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace engage;
using Catch::Matchers::Contains;

namespace {
constexpr double kRel = 1e-12;
double parse(const char* text, Dimension dim, UnitSystem bare = UnitSystem::Metric) {
  return parseQuantity(text, dim, bare).value;
}
}  // namespace

TEST_CASE("quantities with suffixes convert to mm, rad, mm/min, mm^3/min, mm/s^2", "[units]") {
  CHECK(parse("12mm", Dimension::Length) == Approx(12.0).epsilon(kRel));
  CHECK(parse("0.5in", Dimension::Length) == Approx(12.7).epsilon(kRel));
  CHECK(parse(" 1.5 mm ", Dimension::Length) == Approx(1.5).epsilon(kRel));
  CHECK(parse("+5mm", Dimension::Length) == Approx(5.0).epsilon(kRel));
  CHECK(parse("1e-3in", Dimension::Length) == Approx(0.0254).epsilon(kRel));
  CHECK(parse("100ipm", Dimension::Feed) == Approx(2540.0).epsilon(kRel));
  CHECK(parse("3000mm/min", Dimension::Feed) == Approx(3000.0).epsilon(kRel));
  CHECK(parse("50mm/s", Dimension::Feed) == Approx(3000.0).epsilon(kRel));
  CHECK(parse("30deg", Dimension::Angle) == Approx(std::atan(1.0) * 4.0 / 6.0).epsilon(kRel));
  CHECK(parse("18000mm3/min", Dimension::VolumeRate) == Approx(18000.0).epsilon(kRel));
  CHECK(parse("1.1in3/min", Dimension::VolumeRate) ==
        Approx(1.1 * 25.4 * 25.4 * 25.4).epsilon(kRel));
  CHECK(parse("2000mm/s2", Dimension::Acceleration) == Approx(2000.0).epsilon(kRel));
  CHECK(parse("7.27in/s2", Dimension::Acceleration) == Approx(7.27 * 25.4).epsilon(kRel));
  CHECK(parse("0.3g", Dimension::Acceleration) == Approx(0.3 * 9806.65).epsilon(kRel));
  CHECK(parse("50000mm/s3", Dimension::Jerk) == Approx(50000.0).epsilon(kRel));
  CHECK(parse("2000in/s^3", Dimension::Jerk) == Approx(2000.0 * 25.4).epsilon(kRel));
  CHECK(parse("12000rpm", Dimension::SpindleSpeed) == Approx(12000.0).epsilon(kRel));
  CHECK(parse("0.7J/mm3", Dimension::SpecificEnergy) == Approx(0.7).epsilon(kRel));
  // 1 hp*min/in^3 = 745.69987 W * 60 s / 16387.064 mm^3 = 2.730324 J/mm^3.
  CHECK(parse("1hp*min/in3", Dimension::SpecificEnergy) == Approx(2.730324).epsilon(1e-6));
  CHECK(parse("90lbf", Dimension::Force) == Approx(90.0 * 4.4482216152605).epsilon(kRel));
}

TEST_CASE("a bare number is read in the caller's system", "[units]") {
  CHECK(parse("12", Dimension::Length, UnitSystem::Metric) == Approx(12.0).epsilon(kRel));
  CHECK(parse("12", Dimension::Length, UnitSystem::Inch) == Approx(304.8).epsilon(kRel));
  CHECK(parse("100", Dimension::Feed, UnitSystem::Inch) == Approx(2540.0).epsilon(kRel));
  CHECK(parse("90", Dimension::Angle, UnitSystem::Inch) ==
        Approx(std::atan(1.0) * 2.0).epsilon(kRel));
  CHECK_FALSE(parseQuantity("12", Dimension::Length, UnitSystem::Inch).system.has_value());
  CHECK(parseQuantity("12in", Dimension::Length, UnitSystem::Metric).system == UnitSystem::Inch);
  CHECK(suffixSystem("3000mm/min", Dimension::Feed) == UnitSystem::Metric);
  CHECK_FALSE(suffixSystem("0.3g", Dimension::Acceleration).has_value());
  CHECK_FALSE(suffixSystem("junk", Dimension::Length).has_value());
}

TEST_CASE("unreadable quantities name the option, the expectation and what was found", "[units]") {
  CHECK_THROWS_WITH(parseQuantity("1 furlong", Dimension::Length, UnitSystem::Metric, "--diameter"),
                    Contains("--diameter: expected a length") && Contains("found '1 furlong'") &&
                        Contains("unknown unit 'furlong'"));
  CHECK_THROWS_WITH(parseQuantity("abc", Dimension::Feed, UnitSystem::Metric, "--feed"),
                    Contains("--feed: expected a feed") && Contains("found 'abc'"));
  CHECK_THROWS_WITH(parseQuantity("", Dimension::Length, UnitSystem::Metric), Contains("found ''"));
  CHECK_THROWS_WITH(parseQuantity("nan mm", Dimension::Length, UnitSystem::Metric),
                    Contains("finite"));
  // A unit of the wrong dimension is an unknown unit for this option.
  CHECK_THROWS_AS(parseQuantity("12mm", Dimension::Feed, UnitSystem::Metric), UnitError);
}

TEST_CASE("formatting converts back and labels the unit", "[units]") {
  CHECK(formatQuantity(2540.0, Dimension::Feed, UnitSystem::Inch) == "100 in/min");
  CHECK(formatQuantity(2540.0, Dimension::Feed, UnitSystem::Metric) == "2540 mm/min");
  CHECK(formatQuantity(16387.064, Dimension::VolumeRate, UnitSystem::Inch) == "1 in^3/min");
  CHECK(formatQuantity(0.0, Dimension::Length, UnitSystem::Metric) == "0 mm");
  CHECK(formatQuantity(-0.0, Dimension::Length, UnitSystem::Metric) == "0 mm");
  CHECK(std::string(unitTag(Dimension::VolumeRate, UnitSystem::Metric)) == "mm3_min");
  CHECK(formatNumber(std::nan("")) == "nan");
}

TEST_CASE("a library's message speaks the run's units", "[units]") {
  const UnitSystem in = UnitSystem::Inch;
  // 5.08 mm = 0.2 in and 3.175 mm = 0.125 in exactly (1 in = 25.4 mm).
  CHECK(inReportUnits("corner radius r_tc = 5.08 mm must not exceed the cutter radius r = 3.175 mm",
                      in) ==
        "corner radius r_tc = 0.2 in must not exceed the cutter radius r = 0.125 in");
  // A range names its unit once: both ends are converted.
  CHECK(inReportUnits("stock box is empty along X: -12.7 to -12.7 mm", in) ==
        "stock box is empty along X: -0.5 to -0.5 in");
  // Volumes (25.4^3 = 16387.064 mm^3 a cubic inch), feeds, rates, accelerations.
  CHECK(inReportUnits("met 1638.7064 mm^3", in) == "met 0.1 in^3");
  CHECK(inReportUnits("at 2540 mm/min", in) == "at 100 in/min");
  CHECK(inReportUnits("target 16387.064 mm^3/min", in) == "target 1 in^3/min");
  CHECK(inReportUnits("limit 254 mm/s^2.", in) == "limit 10 in/s^2.");
  CHECK(inReportUnits("a move of 2.54e+09 mm", in) == "a move of 1e+08 in");
  // Not a length in mm: typed values ("12mm"), words ("D6 mm", "mmx"), other units, counts.
  CHECK(inReportUnits("expected a length such as 12mm, found '1furlong'", in) ==
        "expected a length such as 12mm, found '1furlong'");
  CHECK(inReportUnits("tool D6 mm", in) == "tool D6 mm");
  CHECK(inReportUnits("6 mmx, 4 GB, 3 voxels", in) == "6 mmx, 4 GB, 3 voxels");
  // Metric runs: unchanged.
  CHECK(inReportUnits("r = 3.175 mm", UnitSystem::Metric) == "r = 3.175 mm");
}
