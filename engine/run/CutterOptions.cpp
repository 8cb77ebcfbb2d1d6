#include "engine/run/CutterOptions.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"

#include <algorithm>
#include <cmath>

namespace engage {

std::optional<double> optionalQuantity(const std::string& text, Dimension dim, UnitSystem bare,
                                       const char* optionName) {
  if (text.empty()) return std::nullopt;
  return parseQuantity(text, dim, bare, optionName).value;
}

AptCutter buildCutter(const ToolOptions& o, UnitSystem bare) {
  const double diameter = parseQuantity(o.diameter, Dimension::Length, bare, "--diameter").value;
  const auto corner = optionalQuantity(o.cornerRadius, Dimension::Length, bare, "--corner-radius");
  const auto taper = optionalQuantity(o.taperAngle, Dimension::Angle, bare, "--taper-angle");
  const auto tip = optionalQuantity(o.tipAngle, Dimension::Angle, bare, "--tip-angle");
  const auto bottom = optionalQuantity(o.bottomAngle, Dimension::Angle, bare, "--bottom-angle");
  const auto flute = optionalQuantity(o.fluteLength, Dimension::Length, bare, "--flute-length");

  auto only = [&](bool given, const char* option, std::initializer_list<const char*> tools) {
    if (!given) return;
    if (std::find_if(tools.begin(), tools.end(), [&](const char* t) { return o.tool == t; }) !=
        tools.end())
      return;
    std::string list;
    for (const char* t : tools)
      list += (list.empty() ? "" : ", ") + std::string(t);
    throw ParameterError(std::string(option) + " does not apply to a " + o.tool +
                         " cutter (it applies to: " + list + ")");
  };
  only(corner.has_value(), "--corner-radius", {"bull", "apt"});
  only(taper.has_value(), "--taper-angle", {"taper", "tapered-ball", "apt"});
  only(tip.has_value(), "--tip-angle", {"chamfer"});
  only(bottom.has_value(), "--bottom-angle", {"apt"});

  // A side flatter than 85 deg to the axis is a face, not a taper: its sweep reaches metres
  // out and the run would take hours (89.9 deg: 10 m wide at a flute length of 18 mm).
  constexpr double kMaxTaperRad = 85.0 * kPi / 180.0;
  if (taper && std::abs(*taper) > kMaxTaperRad && std::abs(*taper) < kPi / 2)
    throw ParameterError(
        "--taper-angle: expected at most 85 deg (a flatter side is a face, not "
        "a taper), found '" +
        o.taperAngle + "'");
  const double h = flute.value_or(3.0 * diameter);
  if (o.tool == "flat") return AptCutter::flat(diameter, h, o.flutes);
  if (o.tool == "ball") return AptCutter::ball(diameter, h, o.flutes);
  if (o.tool == "bull") {
    if (!corner) throw ParameterError("a bull cutter needs --corner-radius");
    return AptCutter::bull(diameter, *corner, h, o.flutes);
  }
  if (o.tool == "taper") {
    if (!taper) throw ParameterError("a taper cutter needs --taper-angle");
    return AptCutter::taper(diameter, *taper, h, o.flutes);
  }
  if (o.tool == "tapered-ball") {
    if (!taper) throw ParameterError("a tapered-ball cutter needs --taper-angle");
    return AptCutter::taperedBall(diameter, *taper, h, o.flutes);
  }
  if (o.tool == "chamfer") {
    if (!tip) throw ParameterError("a chamfer cutter needs --tip-angle (e.g. 90deg)");
    // Default cutting height: 3 D, raised to the top of the cone when that is taller.
    const double cone = diameter / 2.0 / std::tan(*tip / 2.0);
    return AptCutter::chamfer(diameter, *tip, flute.value_or(std::max(h, cone)), o.flutes);
  }
  // apt: r = D/2, e = r - r_tc, h_tc implied.
  AptParameters p;
  p.radius = diameter / 2.0;
  p.cornerRadius = corner.value_or(0.0);
  p.cornerCenterRadial = std::max(0.0, p.radius - p.cornerRadius);
  p.taperAngleRad = taper.value_or(0.0);
  p.bottomAngleRad = bottom.value_or(0.0);
  p.height = h;
  return AptCutter::fromApt(p, o.flutes, CutterShape::General);
}

std::string describeCutter(const AptCutter& c, UnitSystem sys) {
  const AptParameters& p = c.parameters();
  auto L = [&](double v) { return formatQuantity(v, Dimension::Length, sys); };
  auto A = [&](double v) { return formatQuantity(v, Dimension::Angle, sys); };
  return std::string(shapeName(c.shape())) + ": D " + L(2.0 * p.radius) + ", r_tc " +
         L(p.cornerRadius) + ", e " + L(p.cornerCenterRadial) + ", h_tc " +
         L(p.cornerCenterHeight) + ", beta " + A(p.taperAngleRad) + ", delta " +
         A(p.bottomAngleRad) + ", h " + L(p.height) + ", " + std::to_string(c.fluteCount()) +
         " flutes";
}

UnitSystem chooseUnitSystem(const std::string& unitsOption,
                            const std::vector<std::pair<std::string, Dimension>>& typed) {
  if (const auto named = unitSystemNamed(unitsOption)) return *named;
  if (!unitsOption.empty())
    throw UnitError("--units: expected mm or in, found '" + unitsOption + "'");
  for (const auto& [text, dim] : typed)
    if (const auto sys = suffixSystem(text, dim)) return *sys;
  return UnitSystem::Metric;
}

}  // namespace engage
