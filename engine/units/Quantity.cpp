#include "engine/units/Quantity.h"
#include "cutters/Numbers.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace engage {
namespace {

constexpr double kInch = 25.4;                        // mm
constexpr double kCubicInch = kInch * kInch * kInch;  // mm^3
constexpr double kStandardGravity = 9806.65;          // mm/s^2
constexpr double kHorsepower = 745.69987158227022;    // W (mechanical horsepower)
constexpr double kPoundForce = 4.4482216152605;       // N

/// One spelling of a unit: suffix (lower case, no spaces), factor to internal, its system.
struct Unit {
  const char* suffix;
  double factor;
  std::optional<UnitSystem> system;
};

constexpr std::optional<UnitSystem> kM = UnitSystem::Metric;
constexpr std::optional<UnitSystem> kI = UnitSystem::Inch;
constexpr std::optional<UnitSystem> kNone = std::nullopt;

const std::vector<Unit>& unitsOf(Dimension dim) {
  static const std::vector<Unit> length{{"mm", 1.0, kM},
                                        {"cm", 10.0, kM},
                                        {"m", 1000.0, kM},
                                        {"um", 1e-3, kM},
                                        {"in", kInch, kI},
                                        {"inch", kInch, kI},
                                        {"\"", kInch, kI},
                                        {"thou", kInch / 1000.0, kI},
                                        {"mil", kInch / 1000.0, kI},
                                        {"ft", 12.0 * kInch, kI}};
  static const std::vector<Unit> area{
      {"mm2", 1.0, kM}, {"mm^2", 1.0, kM}, {"in2", kInch * kInch, kI}, {"in^2", kInch * kInch, kI}};
  static const std::vector<Unit> volume{{"mm3", 1.0, kM},
                                        {"mm^3", 1.0, kM},
                                        {"cm3", 1000.0, kM},
                                        {"in3", kCubicInch, kI},
                                        {"in^3", kCubicInch, kI}};
  static const std::vector<Unit> angle{{"deg", kPi / 180.0, kNone}, {"rad", 1.0, kNone}};
  static const std::vector<Unit> feed{
      {"mm/min", 1.0, kM},        {"mmpm", 1.0, kM},         {"m/min", 1000.0, kM},
      {"mm/s", 60.0, kM},         {"ipm", kInch, kI},        {"in/min", kInch, kI},
      {"in/s", 60.0 * kInch, kI}, {"ips", 60.0 * kInch, kI}, {"ft/min", 12.0 * kInch, kI}};
  static const std::vector<Unit> surfaceSpeed{
      {"m/min", 1000.0, kM},     {"mm/min", 1.0, kM}, {"ft/min", 12.0 * kInch, kI},
      {"sfm", 12.0 * kInch, kI}, {"ipm", kInch, kI},  {"in/min", kInch, kI}};
  static const std::vector<Unit> volumeRate{{"mm3/min", 1.0, kM},
                                            {"mm^3/min", 1.0, kM},
                                            {"mm3/s", 60.0, kM},
                                            {"mm^3/s", 60.0, kM},
                                            {"cm3/min", 1000.0, kM},
                                            {"cm^3/min", 1000.0, kM},
                                            {"cc/min", 1000.0, kM},
                                            {"in3/min", kCubicInch, kI},
                                            {"in^3/min", kCubicInch, kI},
                                            {"cuin/min", kCubicInch, kI},
                                            {"in3/s", 60.0 * kCubicInch, kI},
                                            {"in^3/s", 60.0 * kCubicInch, kI}};
  static const std::vector<Unit> acceleration{
      {"mm/s2", 1.0, kM},          {"mm/s^2", 1.0, kM},          {"m/s2", 1000.0, kM},
      {"m/s^2", 1000.0, kM},       {"in/s2", kInch, kI},         {"in/s^2", kInch, kI},
      {"ft/s2", 12.0 * kInch, kI}, {"ft/s^2", 12.0 * kInch, kI}, {"g", kStandardGravity, kNone}};
  static const std::vector<Unit> jerk{{"mm/s3", 1.0, kM},   {"mm/s^3", 1.0, kM},
                                      {"m/s3", 1000.0, kM}, {"m/s^3", 1000.0, kM},
                                      {"in/s3", kInch, kI}, {"in/s^3", kInch, kI}};
  static const std::vector<Unit> spindle{
      {"rpm", 1.0, kNone}, {"rev/min", 1.0, kNone}, {"1/min", 1.0, kNone}, {"rev/s", 60.0, kNone}};
  // 1 hp*min/in^3 = 745.7 W * 60 s / 16387.064 mm^3 = 2.7303 J/mm^3.
  static const std::vector<Unit> energy{{"j/mm3", 1.0, kM},
                                        {"j/mm^3", 1.0, kM},
                                        {"ws/mm3", 1.0, kM},
                                        {"w*s/mm3", 1.0, kM},
                                        {"w.s/mm3", 1.0, kM},
                                        {"j/cm3", 1e-3, kM},
                                        {"j/cm^3", 1e-3, kM},
                                        {"hp*min/in3", kHorsepower * 60.0 / kCubicInch, kI},
                                        {"hp*min/in^3", kHorsepower * 60.0 / kCubicInch, kI},
                                        {"hp.min/in3", kHorsepower * 60.0 / kCubicInch, kI},
                                        {"hpmin/in3", kHorsepower * 60.0 / kCubicInch, kI}};
  static const std::vector<Unit> force{
      {"n", 1.0, kM}, {"kn", 1000.0, kM}, {"lbf", kPoundForce, kI}};
  static const std::vector<Unit> time{
      {"s", 1.0, kNone}, {"ms", 1e-3, kNone}, {"min", 60.0, kNone}, {"h", 3600.0, kNone}};
  static const std::vector<Unit> torque{{"nm", 1.0, kM},
                                        {"n*m", 1.0, kM},
                                        {"n.m", 1.0, kM},
                                        {"lbf*ft", kPoundForce * 0.3048, kI},
                                        {"lbfft", kPoundForce * 0.3048, kI},
                                        {"ft*lbf", kPoundForce * 0.3048, kI},
                                        {"lbf*in", kPoundForce * 0.0254, kI},
                                        {"in*lbf", kPoundForce * 0.0254, kI}};
  static const std::vector<Unit> power{{"w", 1.0, kM}, {"kw", 1000.0, kM}, {"hp", kHorsepower, kI}};
  switch (dim) {
    case Dimension::Length:
      return length;
    case Dimension::Area:
      return area;
    case Dimension::Volume:
      return volume;
    case Dimension::Angle:
      return angle;
    case Dimension::Feed:
      return feed;
    case Dimension::SurfaceSpeed:
      return surfaceSpeed;
    case Dimension::VolumeRate:
      return volumeRate;
    case Dimension::Acceleration:
      return acceleration;
    case Dimension::Jerk:
      return jerk;
    case Dimension::SpindleSpeed:
      return spindle;
    case Dimension::SpecificEnergy:
      return energy;
    case Dimension::Force:
      return force;
    case Dimension::Time:
      return time;
    case Dimension::Torque:
      return torque;
    case Dimension::Power:
      return power;
  }
  return length;
}

struct Display {
  const char* metricLabel;
  const char* metricTag;
  double metricFactor;
  const char* inchLabel;
  const char* inchTag;
  double inchFactor;
  const char* example;  // for error messages
};

const Display& displayOf(Dimension dim) {
  static const Display length{"mm", "mm", 1.0, "in", "in", kInch, "a length such as 12mm or 0.5in"};
  static const Display area{
      "mm^2", "mm2", 1.0, "in^2", "in2", kInch * kInch, "an area such as 20mm2 or 0.03in2"};
  static const Display volume{
      "mm^3", "mm3", 1.0, "in^3", "in3", kCubicInch, "a volume such as 500mm3 or 0.03in3"};
  static const Display angle{
      "deg", "deg", kPi / 180.0, "deg", "deg", kPi / 180.0, "an angle such as 30deg or 0.5rad"};
  static const Display feed{
      "mm/min", "mm_min", 1.0, "in/min", "in_min", kInch, "a feed such as 3000mm/min or 100ipm"};
  static const Display surfaceSpeed{"m/min",
                                    "m_min",
                                    1000.0,
                                    "ft/min",
                                    "ft_min",
                                    12.0 * kInch,
                                    "a cutting speed such as 200m/min or 650ft/min"};
  static const Display volumeRate{"mm^3/min",
                                  "mm3_min",
                                  1.0,
                                  "in^3/min",
                                  "in3_min",
                                  kCubicInch,
                                  "a removal rate such as 18000mm3/min or 1.1in3/min"};
  static const Display acceleration{"mm/s^2",
                                    "mm_s2",
                                    1.0,
                                    "in/s^2",
                                    "in_s2",
                                    kInch,
                                    "an acceleration such as 2000mm/s2, 7.27in/s2 or 0.3g"};
  static const Display jerk{
      "mm/s^3", "mm_s3", 1.0, "in/s^3", "in_s3", kInch, "a jerk such as 50000mm/s3 or 2000in/s3"};
  static const Display spindle{
      "rpm", "rpm", 1.0, "rpm", "rpm", 1.0, "a spindle speed such as 12000rpm"};
  static const Display energy{"J/mm^3",
                              "J_mm3",
                              1.0,
                              "hp*min/in^3",
                              "hp_min_in3",
                              kHorsepower * 60.0 / kCubicInch,
                              "a specific energy such as 0.7J/mm3 or 0.3hp*min/in3"};
  static const Display force{
      "N", "N", 1.0, "lbf", "lbf", kPoundForce, "a force such as 400N or 90lbf"};
  static const Display time{"s", "s", 1.0, "s", "s", 1.0, "a time such as 2s or 1.5min"};
  static const Display torque{"N*m",
                              "Nm",
                              1.0,
                              "lbf*ft",
                              "lbf_ft",
                              kPoundForce * 0.3048,
                              "a torque such as 12Nm or 9lbf*ft"};
  static const Display power{
      "kW", "kW", 1000.0, "hp", "hp", kHorsepower, "a power such as 5.5kW or 7.5hp"};
  switch (dim) {
    case Dimension::Length:
      return length;
    case Dimension::Area:
      return area;
    case Dimension::Volume:
      return volume;
    case Dimension::Angle:
      return angle;
    case Dimension::Feed:
      return feed;
    case Dimension::SurfaceSpeed:
      return surfaceSpeed;
    case Dimension::VolumeRate:
      return volumeRate;
    case Dimension::Acceleration:
      return acceleration;
    case Dimension::Jerk:
      return jerk;
    case Dimension::SpindleSpeed:
      return spindle;
    case Dimension::SpecificEnergy:
      return energy;
    case Dimension::Force:
      return force;
    case Dimension::Time:
      return time;
    case Dimension::Torque:
      return torque;
    case Dimension::Power:
      return power;
  }
  return length;
}

std::string trim(std::string_view s) {
  std::size_t a = 0;
  std::size_t b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a])))
    ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1])))
    --b;
  return std::string(s.substr(a, b - a));
}

/// Split "12.5 mm/min" into the number and the lower-cased unit with spaces removed.
/// Returns false when no number starts the text.
bool split(std::string_view text, double& number, std::string& unit) {
  const std::string t = trim(text);
  const char* first = t.data();
  const char* last = t.data() + t.size();
  if (first != last && *first == '+') ++first;  // from_chars does not accept a leading '+'
  const auto [ptr, ec] = std::from_chars(first, last, number);
  if (ec != std::errc()) return false;
  unit.clear();
  for (const char* p = ptr; p != last; ++p)
    if (!std::isspace(static_cast<unsigned char>(*p)))
      unit.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(*p))));
  return true;
}

const Unit* findUnit(Dimension dim, const std::string& unit) {
  for (const Unit& u : unitsOf(dim))
    if (unit == u.suffix) return &u;
  return nullptr;
}

}  // namespace

Quantity parseQuantity(std::string_view text, Dimension dim, UnitSystem bareSystem,
                       std::string_view what) {
  const std::string prefix = what.empty() ? std::string() : std::string(what) + ": ";
  double number = 0.0;
  std::string unit;
  if (!split(text, number, unit))
    throw UnitError(prefix + "expected " + displayOf(dim).example + ", found '" + trim(text) + "'");
  if (!std::isfinite(number))
    throw UnitError(prefix + "expected a finite number, found '" + trim(text) + "'");
  if (unit.empty()) {
    return Quantity{number * displayFactor(dim, bareSystem), std::nullopt};
  }
  const Unit* u = findUnit(dim, unit);
  if (!u) {
    std::string known;
    for (const Unit& k : unitsOf(dim))
      known += (known.empty() ? "" : ", ") + std::string(k.suffix);
    throw UnitError(prefix + "expected " + displayOf(dim).example + ", found '" + trim(text) +
                    "' (unknown unit '" + unit + "'; known: " + known + ")");
  }
  return Quantity{number * u->factor, u->system};
}

std::optional<UnitSystem> suffixSystem(std::string_view text, Dimension dim) {
  double number = 0.0;
  std::string unit;
  if (!split(text, number, unit) || unit.empty()) return std::nullopt;
  const Unit* u = findUnit(dim, unit);
  return u ? u->system : std::nullopt;
}

double displayFactor(Dimension dim, UnitSystem sys) {
  const Display& d = displayOf(dim);
  return sys == UnitSystem::Inch ? d.inchFactor : d.metricFactor;
}

double toDisplay(double internal, Dimension dim, UnitSystem sys) {
  return internal / displayFactor(dim, sys);
}

std::string_view unitLabel(Dimension dim, UnitSystem sys) {
  const Display& d = displayOf(dim);
  return sys == UnitSystem::Inch ? d.inchLabel : d.metricLabel;
}

std::string_view unitTag(Dimension dim, UnitSystem sys) {
  const Display& d = displayOf(dim);
  return sys == UnitSystem::Inch ? d.inchTag : d.metricTag;
}

std::string formatQuantity(double internal, Dimension dim, UnitSystem sys) {
  return formatNumber(toDisplay(internal, dim, sys)) + " " + std::string(unitLabel(dim, sys));
}

std::string inReportUnits(const std::string& message, UnitSystem sys) {
  if (sys == UnitSystem::Metric) return message;
  // Longest unit first, so that "mm^3/min" is not read as "mm^3".
  struct Unit {
    const char* mm;
    Dimension dim;
  };
  static const Unit units[] = {
      {" mm^3/min", Dimension::VolumeRate}, {" mm/s^2", Dimension::Acceleration},
      {" mm/min", Dimension::Feed},         {" mm^3", Dimension::Volume},
      {" mm^2", Dimension::Area},           {" mm", Dimension::Length}};
  const std::string& m = message;
  const std::size_t n = m.size();
  auto digit = [&](std::size_t k) {
    return k < n && std::isdigit(static_cast<unsigned char>(m[k]));
  };
  // The end of a number starting at k (k itself when there is none): sign, digits and point,
  // exponent.
  auto numberEnd = [&](std::size_t k) {
    std::size_t e = k;
    if (e < n && (m[e] == '-' || m[e] == '+')) ++e;
    const std::size_t first = e;
    while (digit(e) || (e < n && m[e] == '.'))
      ++e;
    if (e == first || !(digit(e - 1) || digit(first))) return k;
    if (e < n && (m[e] == 'e' || m[e] == 'E')) {
      std::size_t f = e + 1;
      if (f < n && (m[f] == '-' || m[f] == '+')) ++f;
      const std::size_t g = f;
      while (digit(f))
        ++f;
      if (f > g) e = f;
    }
    return e;
  };
  // The unit right after a number ending at e, as a whole word.
  auto unitAt = [&](std::size_t e) -> const Unit* {
    for (const Unit& u : units) {
      const std::size_t len = std::char_traits<char>::length(u.mm);
      if (m.compare(e, len, u.mm) == 0 &&
          (e + len >= n || !std::isalnum(static_cast<unsigned char>(m[e + len]))))
        return &u;
    }
    return nullptr;
  };
  auto value = [&](std::size_t from, std::size_t to) {
    double v = 0.0;
    const char* b = m.data() + from + (m[from] == '+' ? 1 : 0);
    return std::from_chars(b, m.data() + to, v).ptr == m.data() + to ? v : std::nan("");
  };
  std::string out;
  for (std::size_t i = 0; i < n;) {
    const bool boundary = i == 0 || !(std::isalnum(static_cast<unsigned char>(m[i - 1])) ||
                                      m[i - 1] == '_' || m[i - 1] == '.');
    const std::size_t e = boundary ? numberEnd(i) : i;
    if (e > i) {
      const double v = value(i, e);
      if (const Unit* u = unitAt(e); u && !std::isnan(v)) {
        out += formatQuantity(v, u->dim, sys);
        i = e + std::char_traits<char>::length(u->mm);
        continue;
      }
      // The first end of a range: "-12.7 to 12.7 mm".
      if (m.compare(e, 4, " to ") == 0 && !std::isnan(v)) {
        const std::size_t e2 = numberEnd(e + 4);
        if (const Unit* u = e2 > e + 4 ? unitAt(e2) : nullptr) {
          out += formatNumber(toDisplay(v, u->dim, sys));
          i = e;
          continue;
        }
      }
      out.append(m, i, e - i);
      i = e;
      continue;
    }
    out += m[i++];
  }
  return out;
}

std::string_view systemName(UnitSystem sys) {
  return sys == UnitSystem::Inch ? "in" : "mm";
}

std::optional<UnitSystem> unitSystemNamed(std::string_view name) {
  if (name == "mm") return UnitSystem::Metric;
  if (name == "in" || name == "inch") return UnitSystem::Inch;
  return std::nullopt;
}

}  // namespace engage
