#pragma once
/// \file CutterOptions.h
/// A cutter from the options as typed (--tool, --diameter, --corner-radius, --taper-angle,
/// --tip-angle, --bottom-angle, --flute-length, --flutes), and the choice of report unit
/// system from what the user typed. The option names themselves are in OptionTable.h.

#include "cutters/AptCutter.h"
#include "engine/units/Quantity.h"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace engage {

/// The option texts of a cutter, as typed, parsed by buildCutter.
struct ToolOptions {
  std::string tool;  ///< flat, ball, bull, taper, tapered-ball, chamfer or apt
  std::string diameter;
  std::string cornerRadius;
  std::string taperAngle;
  std::string tipAngle;
  std::string bottomAngle;
  std::string fluteLength;
  int flutes = 2;
};

/// Build the cutter; bare numbers are read in `bare`. Throws UnitError or ParameterError,
/// e.g. when an option does not fit the tool ("--corner-radius applies to bull and apt").
AptCutter buildCutter(const ToolOptions& options, UnitSystem bare);

/// One line for a cutter: its shape and APT parameters ("flat: D 6 mm, r_tc 0 mm, ...").
std::string describeCutter(const AptCutter& cutter, UnitSystem sys);

/// The report unit system: --units if given ("mm" or "in"; anything else throws UnitError),
/// else the system of the first value in `typed` whose suffix names one, else metric.
UnitSystem chooseUnitSystem(const std::string& unitsOption,
                            const std::vector<std::pair<std::string, Dimension>>& typed);

/// Parse an optional quantity option: nullopt when the option string is empty.
std::optional<double> optionalQuantity(const std::string& text, Dimension dim, UnitSystem bare,
                                       const char* optionName);

}  // namespace engage
