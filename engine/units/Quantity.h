#pragma once
/// \file Quantity.h
/// The one parser and formatter of physical quantities for the whole command line and the
/// reports. Internal units: mm, rad, mm/min, mm^3/min, mm/s^2, rev/min, J/mm^3, N, N*m, W,
/// mm^2, mm^3, s. Inputs carry unit suffixes ("12mm", "0.5in", "100ipm", "30deg", "0.3g",
/// "18000mm3/min", "1.1in3/min", "2000mm/s2", "7.27in/s2"); a bare number is read in the
/// caller's default system (mm or inch based, degrees for angles, rpm for spindle speed).

#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <optional>
#include <string>
#include <string_view>

namespace engage {

/// The two unit systems of reports and programs.
enum class UnitSystem { Metric, Inch };

/// What a quantity measures.
enum class Dimension {
  Length,          ///< mm | in
  Area,            ///< mm^2 | in^2
  Volume,          ///< mm^3 | in^3
  Angle,           ///< deg (both systems); internal rad
  Feed,            ///< mm/min | in/min
  SurfaceSpeed,    ///< m/min | ft/min; internal mm/min
  VolumeRate,      ///< mm^3/min | in^3/min
  Acceleration,    ///< mm/s^2 | in/s^2
  Jerk,            ///< mm/s^3 | in/s^3
  SpindleSpeed,    ///< rpm (both systems)
  SpecificEnergy,  ///< J/mm^3 | hp*min/in^3; internal J/mm^3
  Force,           ///< N | lbf; internal N
  Time,            ///< s (both systems)
  Torque,          ///< N*m | lbf*ft; internal N*m
  Power,           ///< kW | hp; internal W
};

/// A quantity or unit that cannot be read. The message names the option when one was given.
class UnitError : public Error {
 public:
  explicit UnitError(const std::string& message) : Error(message) {}
};

/// A value in internal units, and the unit system its suffix belongs to (none for a bare
/// number or a system-free unit such as deg, rpm or g).
struct Quantity {
  double value = 0.0;
  std::optional<UnitSystem> system;
};

/// Parse `text` as a quantity of dimension `dim`. A bare number is read in `bareSystem`.
/// `what` (e.g. "--diameter") prefixes error messages. Throws UnitError:
/// "--diameter: expected a length such as 12mm or 0.5in, found '1 furlong'".
Quantity parseQuantity(std::string_view text, Dimension dim, UnitSystem bareSystem,
                       std::string_view what = {});

/// The unit system of `text`'s suffix, if it has one that belongs to a system (for choosing
/// the report units from what a user typed). Never throws: unreadable text gives nullopt.
std::optional<UnitSystem> suffixSystem(std::string_view text, Dimension dim);

/// Factor from display units of `sys` to internal units (display value * factor = internal).
double displayFactor(Dimension dim, UnitSystem sys);

/// Internal value converted to the display unit of `sys`.
double toDisplay(double internal, Dimension dim, UnitSystem sys);

/// Display unit label for people, e.g. "in^3/min", "mm/s^2", "deg".
std::string_view unitLabel(Dimension dim, UnitSystem sys);

/// Display unit tag for column and key names, e.g. "in3_min", "mm_s2", "deg".
std::string_view unitTag(Dimension dim, UnitSystem sys);

/// "<value> <label>" with six significant digits, e.g. "13.9153 in^3/min".
std::string formatQuantity(double internal, Dimension dim, UnitSystem sys);

/// "mm" or "in".
std::string_view systemName(UnitSystem sys);

/// The unit system an option names: "mm", or "in" or "inch"; nothing for any other text.
std::optional<UnitSystem> unitSystemNamed(std::string_view name);

/// A library's message (which speaks internal units: "5.08 mm", "1.2 mm^3", "600 mm/min") in
/// the report units: for an inch run every "<number> mm", "mm^2", "mm^3", "mm/min",
/// "mm^3/min" and "mm/s^2" becomes its value in inches (six significant digits); metric
/// messages are returned as they are. The command's boundary uses it so that an inch run's
/// errors speak inches.
std::string inReportUnits(const std::string& message, UnitSystem sys);

}  // namespace engage
