#include "engine/tools/ToolLibrary.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/units/Quantity.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

namespace engage {
namespace {

using nlohmann::json;
constexpr double kInch = 25.4;
constexpr double kDeg = kPi / 180.0;
/// A tool library (or project) bigger than this is not one.
constexpr std::uintmax_t kMaxLibraryBytes = 64u << 20;

std::string lower(std::string s) {
  for (char& c : s)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// The cutting part of a tool from its shape words, all in mm and radians. `build` throws
/// ParameterError from AptCutter; the caller names the tool.
struct Shape {
  std::string kind;  ///< flat, ball, bull, taper, tapered-ball, chamfer, drill
  double diameter = 0.0;
  double cornerRadius = 0.0;
  double taperRad = 0.0;     ///< side to the axis (taper, chamfer with a tip)
  double tipAngleRad = 0.0;  ///< included angle (chamfer, drill)
  double tipDiameter = 0.0;  ///< flat tip of a taper or a chamfer mill
  double fluteLength = 0.0;  ///< 0: 3 D
  int flutes = 2;
  double shankDiameter = 0.0;  ///< LinuxCNC comment's shank=, 0 when not said
  double stickout = 0.0;       ///< LinuxCNC comment's stickout=, 0 when not said
};

/// A field of a tool is wrong: the message names the field and its value.
[[noreturn]] void fieldError(const std::string& field, const std::string& what) {
  throw ParameterError(field + " " + what);
}

AptCutter buildShape(const Shape& s) {
  if (!(std::isfinite(s.diameter) && s.diameter > 0.0))
    fieldError("diameter", formatNumber(s.diameter) + " mm must be positive");
  if (!(s.flutes >= 1 && s.flutes <= 1000))
    fieldError("flutes", std::to_string(s.flutes) + " must be at least 1");
  const double h = s.fluteLength > 0.0 ? s.fluteLength : 3.0 * s.diameter;
  const double r = s.diameter / 2.0;
  if (s.kind == "flat") return AptCutter::flat(s.diameter, h, s.flutes);
  if (s.kind == "ball") return AptCutter::ball(s.diameter, h, s.flutes);
  if (s.kind == "bull") {
    if (s.cornerRadius > r + 1e-9)
      fieldError("corner radius", formatNumber(s.cornerRadius) + " mm is larger than the radius " +
                                      formatNumber(r) + " mm");
    if (s.cornerRadius <= 0.0) return AptCutter::flat(s.diameter, h, s.flutes);
    if (s.cornerRadius >= r - 1e-9) return AptCutter::ball(s.diameter, h, s.flutes);
    return AptCutter::bull(s.diameter, s.cornerRadius, h, s.flutes);
  }
  if (s.kind == "chamfer" || s.kind == "drill") {
    // A cone from the tip (or a flat tip) out to the diameter.
    if (s.tipDiameter >= s.diameter)
      fieldError("tip diameter", formatNumber(s.tipDiameter) +
                                     " mm is not smaller than the diameter " +
                                     formatNumber(s.diameter) + " mm: the cone does not close");
    if (s.tipDiameter > 0.0) {
      const double beta = s.taperRad > 0.0 ? s.taperRad : kPi / 2.0 - s.tipAngleRad / 2.0;
      if (!(beta > 0.0 && beta < kPi / 2.0))
        fieldError("taper angle", formatNumber(beta / kDeg) + " deg must lie between 0 and 90 deg");
      const double cone = (s.diameter - s.tipDiameter) / 2.0 / std::tan(beta);
      return AptCutter::taper(s.tipDiameter, beta, cone, s.flutes);
    }
    const double included = s.tipAngleRad > 0.0 ? s.tipAngleRad : 2.0 * s.taperRad;
    if (!(included > 0.0 && included < kPi))
      fieldError("tip angle",
                 formatNumber(included / kDeg) + " deg must lie between 0 and 180 deg");
    const double cone = r / std::tan(included / 2.0);
    return AptCutter::chamfer(s.diameter, included, std::max(h, cone * (1.0 + 1e-12)), s.flutes);
  }
  if (s.kind == "taper" || s.kind == "tapered-ball") {
    if (!(s.taperRad > 0.0 && s.taperRad < 85.0 * kDeg))
      fieldError("taper angle",
                 formatNumber(s.taperRad / kDeg) + " deg must lie between 0 and 85 deg");
    if (s.kind == "tapered-ball")
      return AptCutter::taperedBall(s.diameter, s.taperRad, h, s.flutes);
    if (s.cornerRadius > r + 1e-9)
      fieldError("corner radius", formatNumber(s.cornerRadius) +
                                      " mm is larger than the tip radius " + formatNumber(r) +
                                      " mm");
    if (s.cornerRadius <= 0.0) return AptCutter::taper(s.diameter, s.taperRad, h, s.flutes);
    AptParameters p;
    p.radius = r;
    p.cornerRadius = s.cornerRadius;
    p.cornerCenterRadial = std::max(0.0, r - s.cornerRadius);
    p.taperAngleRad = s.taperRad;
    p.height = h;
    return AptCutter::fromApt(p, s.flutes, CutterShape::General);
  }
  throw ParameterError("shape \"" + s.kind + "\" is not a cutter engage can sweep");
}

/// Build the entry's cutter, or keep the reason it cannot be built.
void finish(ToolEntry& e, const std::function<Shape()>& shape) {
  try {
    e.cutter = buildShape(shape());
  } catch (const Error& err) {
    e.problem = err.what();
  }
}

// ------------------------------------------------------------------------------ JSON helpers

json parseJson(const std::string& text, const std::string& path) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    std::string what = e.what();
    const auto cut = what.find("] ");
    throw ParameterError(path + ": not valid JSON (" +
                         (cut == std::string::npos ? what : what.substr(cut + 2)) + ")");
  }
}

/// A number field of a JSON object, or nullopt when absent. A field of another kind is an
/// error naming it.
std::optional<double> number(const json& o, const char* key) {
  if (!o.is_object() || !o.contains(key) || o.at(key).is_null()) return std::nullopt;
  const json& v = o.at(key);
  if (v.is_number()) {
    const double d = v.get<double>();
    if (!std::isfinite(d)) fieldError(key, "is not a finite number");
    return d;
  }
  if (v.is_boolean()) return v.get<bool>() ? 1.0 : 0.0;
  fieldError(key, "expected a number, found " + v.dump());
}

std::string text(const json& o, const char* key) {
  if (!o.is_object() || !o.contains(key) || !o.at(key).is_string()) return {};
  return o.at(key).get<std::string>();
}

// ------------------------------------------------------------------------------ Fusion 360

/// Fusion's geometry fields of one tool into a Shape, mm and radians.
Shape fusionShape(const json& tool, const std::string& type, double unit) {
  const json& g = tool.contains("geometry") ? tool.at("geometry") : json::object();
  auto length = [&](const char* key) { return number(g, key).value_or(0.0) * unit; };
  Shape s;
  s.diameter = length("DC");
  if (!number(g, "DC")) fieldError("geometry.DC", "(the cutting diameter) is missing");
  s.cornerRadius = length("RE");
  s.fluteLength = length("LCF");
  s.flutes = static_cast<int>(number(g, "NOF").value_or(2.0));
  s.taperRad = number(g, "TA").value_or(0.0) * kDeg;
  s.tipAngleRad = number(g, "SIG").value_or(0.0) * kDeg;
  s.tipDiameter = length("tip-diameter");
  if (type == "flat end mill" || type == "face mill" || type == "slot mill" ||
      type == "counter bore" || type == "reamer" || type == "boring bar") {
    s.kind = s.cornerRadius > 0.0 ? "bull" : "flat";
  } else if (type == "ball end mill") {
    s.kind = "ball";
  } else if (type == "bull nose end mill" || type == "radius mill") {
    s.kind = "bull";
    if (!number(g, "RE")) fieldError("geometry.RE", "(the corner radius) is missing");
  } else if (type == "tapered mill") {
    s.kind = s.tipDiameter > 0.0 && s.cornerRadius >= s.tipDiameter / 2.0 - 1e-9 ? "tapered-ball"
                                                                                 : "taper";
    if (s.tipDiameter > 0.0) s.diameter = s.tipDiameter;
    if (s.kind == "tapered-ball") s.diameter = 2.0 * s.cornerRadius;
  } else if (type == "chamfer mill" || type == "counter sink") {
    s.kind = "chamfer";
    if (s.taperRad <= 0.0 && s.tipAngleRad <= 0.0)
      fieldError("geometry.TA", "(the taper angle) is missing");
  } else if (type == "drill" || type == "spot drill" || type == "center drill") {
    s.kind = "drill";
    if (s.tipAngleRad <= 0.0) s.tipAngleRad = 118.0 * kDeg;
    s.tipDiameter = 0.0;
  } else {
    fieldError("type", "\"" + type + "\" is not a cutter engage can sweep");
  }
  return s;
}

double fusionUnit(const json& o, const std::string& fallback) {
  std::string u = text(o, "unit");
  if (u.empty()) u = fallback;
  if (u == "millimeters") return 1.0;
  if (u == "inches") return kInch;
  if (u.empty()) fieldError("unit", "is missing (expected millimeters or inches)");
  fieldError("unit", "\"" + u + "\": expected millimeters or inches");
}

void readFusion(const json& doc, ToolLibrary& lib) {
  const json& data = doc.at("data");
  if (!data.is_array()) throw ParameterError(lib.path + ": \"data\" is not a list of tools");
  for (std::size_t i = 0; i < data.size(); ++i) {
    const json& t = data[i];
    if (!t.is_object()) continue;
    const std::string type = text(t, "type");
    if (type == "holder" || type == "probe" || type == "shaft") continue;
    ToolEntry e;
    e.origin = lib.path + ": tool " + std::to_string(i + 1) + " of \"data\"";
    e.kind = type;
    e.name = text(t, "description");
    try {
      const json& pp = t.contains("post-process") ? t.at("post-process") : json::object();
      e.number = static_cast<int>(number(pp, "number").value_or(0.0));
    } catch (const Error& err) {
      e.problem = std::string("post-process.") + err.what();
    }
    if (e.number <= 0 && e.problem.empty()) continue;  // not in the magazine
    finish(e, [&] {
      const double unit = fusionUnit(t, "");
      const json& g = t.contains("geometry") ? t.at("geometry") : json::object();
      e.shankDiameter = number(g, "SFDM").value_or(0.0) * unit;
      e.stickout = number(g, "LB").value_or(0.0) * unit;
      e.overallLength = number(g, "OAL").value_or(0.0) * unit;
      if (t.contains("holder") && t.at("holder").is_object()) {
        const json& h = t.at("holder");
        e.holderName = text(h, "description");
        if (h.contains("segments") && h.at("segments").is_array() && !h.at("segments").empty()) {
          const double hu = fusionUnit(h, text(t, "unit"));
          for (const json& seg : h.at("segments")) {
            HolderSegment s;
            s.height = number(seg, "height").value_or(0.0) * hu;
            s.lowerDiameter = number(seg, "lower-diameter").value_or(0.0) * hu;
            s.upperDiameter = number(seg, "upper-diameter").value_or(0.0) * hu;
            if (!(s.height >= 0.0 && s.lowerDiameter >= 0.0 && s.upperDiameter >= 0.0))
              fieldError("holder.segments", "has a negative height or diameter");
            e.holder.push_back(s);
          }
        }
      }
      return fusionShape(t, type, unit);
    });
    lib.tools.push_back(std::move(e));
  }
}

// ------------------------------------------------------------------------------ FreeCAD

/// A FreeCAD parameter: "6.0000 mm", "0.25 in", "90.0000 °", or a bare number (mm, deg).
double freecadValue(const json& params, const char* key, Dimension dim) {
  if (!params.contains(key)) fieldError(std::string("parameter.") + key, "is missing");
  const json& v = params.at(key);
  if (v.is_number()) return dim == Dimension::Angle ? v.get<double>() * kDeg : v.get<double>();
  if (!v.is_string())
    fieldError(std::string("parameter.") + key, "expected a value such as \"6 mm\"");
  std::string t;
  for (char c : v.get<std::string>())
    if (!std::isspace(static_cast<unsigned char>(c))) t += c;
  const std::string degree = "\xC2\xB0";  // UTF-8 degree sign
  if (const auto at = t.find(degree); at != std::string::npos) t.replace(at, degree.size(), "deg");
  return parseQuantity(t, dim, UnitSystem::Metric, std::string("parameter.") + key).value;
}

Shape freecadShape(const json& bit) {
  const std::string shapeFile = lower(text(bit, "shape"));
  const json& p = bit.contains("parameter") ? bit.at("parameter") : json::object();
  auto length = [&](const char* key) { return freecadValue(p, key, Dimension::Length); };
  auto optionalLength = [&](const char* key) { return p.contains(key) ? length(key) : 0.0; };
  Shape s;
  s.diameter = length("Diameter");
  s.fluteLength = optionalLength("CuttingEdgeHeight");
  if (p.contains("Flutes")) {
    const json& f = p.at("Flutes");
    s.flutes = f.is_number() ? f.get<int>() : std::atoi(text(p, "Flutes").c_str());
  }
  const std::string shape = shapeFile.substr(0, shapeFile.find('.'));
  if (shape == "endmill") {
    s.kind = "flat";
  } else if (shape == "ballend") {
    s.kind = "ball";
  } else if (shape == "bullnose") {
    s.kind = "bull";
    // FreeCAD gives the radius of the flat part; the corner radius is the rest.
    s.cornerRadius = s.diameter / 2.0 - length("FlatRadius");
    if (s.cornerRadius < -1e-9)
      fieldError("parameter.FlatRadius", "is larger than half the diameter");
  } else if (shape == "v-bit" || shape == "chamfer") {
    s.kind = "chamfer";
    s.tipAngleRad = freecadValue(p, "CuttingEdgeAngle", Dimension::Angle);
    s.tipDiameter = optionalLength("TipDiameter");
    if (s.tipDiameter > 0.0) s.taperRad = s.tipAngleRad / 2.0;
  } else if (shape == "drill") {
    s.kind = "drill";
    s.tipAngleRad = freecadValue(p, "TipAngle", Dimension::Angle);
  } else {
    fieldError("shape", "\"" + text(bit, "shape") + "\" is not a cutter engage can sweep");
  }
  return s;
}

void readFreecadBit(const json& bit, ToolEntry& e) {
  e.name = text(bit, "name");
  e.kind = text(bit, "shape");
  finish(e, [&] {
    const json& p = bit.contains("parameter") ? bit.at("parameter") : json::object();
    if (p.contains("ShankDiameter"))
      e.shankDiameter = freecadValue(p, "ShankDiameter", Dimension::Length);
    if (p.contains("Length")) e.overallLength = freecadValue(p, "Length", Dimension::Length);
    return freecadShape(bit);
  });
}

void readFreecadLibrary(const json& doc, ToolLibrary& lib) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(lib.path).parent_path();
  for (std::size_t i = 0; i < doc.at("tools").size(); ++i) {
    const json& t = doc.at("tools")[i];
    ToolEntry e;
    e.origin = lib.path + ": tool " + std::to_string(i + 1) + " of \"tools\"";
    e.number = static_cast<int>(number(t, "nr").value_or(0.0));
    const std::string bitPath = text(t, "path");
    // FreeCAD keeps bits in Bit/ beside Library/; a path may also be relative to the library.
    fs::path found;
    for (const fs::path& candidate :
         {dir / bitPath, dir / ".." / "Bit" / bitPath, fs::path(bitPath)})
      if (std::error_code ec; !bitPath.empty() && fs::is_regular_file(candidate, ec)) {
        found = candidate;
        break;
      }
    if (found.empty()) {
      e.problem = "path \"" + bitPath + "\": no such tool bit beside the library or in ../Bit";
    } else {
      e.origin = found.string();
      try {
        readFreecadBit(parseJson(readToolFile(found.string(), "tool bit"), found.string()), e);
      } catch (const Error& err) {
        e.problem = err.what();
      }
    }
    lib.tools.push_back(std::move(e));
  }
}

// ------------------------------------------------------------------------------ CAMotics

void readCamotics(const json& tools, ToolLibrary& lib) {
  for (const auto& item : tools.items()) {
    // Not a structured binding: C++17 lambdas (clang) cannot capture one.
    const std::string key = item.key();
    const json& t = item.value();
    ToolEntry e;
    e.origin = lib.path + ": tools." + key;
    try {
      std::size_t used = 0;
      e.number = std::stoi(key, &used);
      if (used != key.size()) throw std::invalid_argument(key);
    } catch (const std::exception&) {
      e.problem = "the key \"" + key + "\" is not a tool number";
    }
    e.name = text(t, "description");
    e.kind = text(t, "shape");
    if (e.problem.empty())
      finish(e, [&] {
        const std::string units = text(t, "units");
        const double unit = units == "imperial" ? kInch : 1.0;
        if (units != "imperial" && units != "metric")
          fieldError("units", "\"" + units + "\": expected metric or imperial");
        Shape s;
        s.diameter = number(t, "diameter").value_or(0.0) * unit;
        const double length = number(t, "length").value_or(0.0) * unit;
        if (!(length > 0.0)) fieldError("length", "must be positive");
        s.fluteLength = length;
        e.overallLength = length;
        // CAMotics sweeps the whole length as cutting; its shapes in APT terms.
        if (e.kind == "cylindrical") {
          s.kind = "flat";
        } else if (e.kind == "ballnose") {
          s.kind = "ball";
        } else if (e.kind == "conical") {  // a cone of `length` up to the diameter
          s.kind = "chamfer";
          s.tipAngleRad = 2.0 * std::atan2(s.diameter / 2.0, length);
        } else if (e.kind == "snubnose") {  // a cone from snub_diameter at the tip
          s.kind = "chamfer";
          s.tipDiameter = number(t, "snub_diameter").value_or(0.0) * unit;
          s.taperRad = std::atan2((s.diameter - s.tipDiameter) / 2.0, length);
        } else {
          fieldError("shape", "\"" + e.kind + "\" is not a cutter engage can sweep");
        }
        return s;
      });
    lib.tools.push_back(std::move(e));
  }
}

// ------------------------------------------------------------------------------ LinuxCNC

/// The comment of a LinuxCNC tool table line, read for the cutter's shape. Words (any case):
/// flat / endmill, ball / ballnose, bull, taper, vbit / v-bit / chamfer / engraving, drill;
/// key=value: r= (corner radius), angle= (included angle of a chamfer or drill, the side to
/// the axis of a taper), flutes=, loc= or flute-length= (length of cut), tip= (tip diameter of
/// a taper or a chamfer mill), shank= (shank diameter, default D) and stickout= (tip to the
/// holder: with it the shank is checked for collisions). Lengths take units (r=0.5mm); bare
/// numbers are the table's. The table's Z is a length offset, not the tool's length: unused.
Shape linuxcncShape(const std::string& comment, double diameter, UnitSystem sys) {
  Shape s;
  s.kind = "flat";
  s.diameter = diameter;
  std::istringstream words(lower(comment));
  std::string w;
  auto length = [&](const std::string& v, const std::string& key) {
    return parseQuantity(v, Dimension::Length, sys, key).value;
  };
  while (words >> w) {
    while (!w.empty() && (w.back() == ',' || w.back() == '.' || w.back() == ')'))
      w.pop_back();
    while (!w.empty() && w.front() == '(')
      w.erase(0, 1);
    const auto eq = w.find('=');
    if (eq != std::string::npos) {
      const std::string key = w.substr(0, eq), v = w.substr(eq + 1);
      if (key == "r")
        s.cornerRadius = length(v, "r=");
      else if (key == "angle")
        s.tipAngleRad = parseQuantity(v, Dimension::Angle, sys, "angle=").value;
      else if (key == "flutes")
        s.flutes = std::atoi(v.c_str());
      else if (key == "loc" || key == "flute-length")
        s.fluteLength = length(v, key + "=");
      else if (key == "tip")
        s.tipDiameter = length(v, "tip=");
      else if (key == "shank")
        s.shankDiameter = length(v, "shank=");
      else if (key == "stickout")
        s.stickout = length(v, "stickout=");
      else if (key == "shape")
        w = v;
      if (key != "shape") continue;
    }
    if (w == "flat" || w == "endmill")
      s.kind = "flat";
    else if (w == "ball" || w == "ballnose" || w == "ball-nose")
      s.kind = "ball";
    else if (w == "bull" || w == "bullnose")
      s.kind = "bull";
    else if (w == "taper")
      s.kind = "taper";
    else if (w == "vbit" || w == "v-bit" || w == "chamfer" || w == "engraving")
      s.kind = "chamfer";
    else if (w == "drill")
      s.kind = "drill";
  }
  if (s.kind == "bull" && !(s.cornerRadius > 0.0))
    fieldError("comment", "names a bull cutter without r= (its corner radius)");
  if (s.kind == "taper") {
    s.taperRad = s.tipAngleRad;
    s.tipAngleRad = 0.0;
    if (s.tipDiameter > 0.0) s.diameter = s.tipDiameter;
  }
  if (s.kind == "chamfer" && s.tipAngleRad <= 0.0)
    fieldError("comment", "names a chamfer / v-bit without angle= (its included angle)");
  if (s.kind == "chamfer" && s.tipDiameter > 0.0) s.taperRad = s.tipAngleRad / 2.0;
  if (s.kind == "drill" && s.tipAngleRad <= 0.0) s.tipAngleRad = 118.0 * kDeg;
  return s;
}

void readLinuxcnc(const std::string& textIn, ToolLibrary& lib, const ToolLibraryOptions& o) {
  const double unit = o.linuxcncInch ? kInch : 1.0;
  const UnitSystem sys = o.linuxcncInch ? UnitSystem::Inch : UnitSystem::Metric;
  std::istringstream in(textIn);
  std::string line;
  for (int lineNo = 1; std::getline(in, line); ++lineNo) {
    std::string comment;
    if (const auto semi = line.find(';'); semi != std::string::npos) {
      comment = line.substr(semi + 1);
      line.resize(semi);
    }
    std::istringstream words(line);
    std::string w;
    std::map<char, double> v;
    while (words >> w) {
      const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
      char* end = nullptr;
      const double value = std::strtod(w.c_str() + 1, &end);
      if (!std::isalpha(static_cast<unsigned char>(c)) || end == w.c_str() + 1 || *end != '\0' ||
          !std::isfinite(value))
        throw ParameterError(lib.path + ":" + std::to_string(lineNo) +
                             ": expected a word such as T1, D6 or Z35, found '" + w + "'");
      v[c] = value;
    }
    if (v.empty()) continue;
    if (!v.count('T'))
      throw ParameterError(lib.path + ":" + std::to_string(lineNo) +
                           ": expected a T word (the tool number), found none");
    ToolEntry e;
    e.origin = lib.path + ":" + std::to_string(lineNo);
    e.number = static_cast<int>(v['T']);
    e.name = comment;
    while (!e.name.empty() && std::isspace(static_cast<unsigned char>(e.name.front())))
      e.name.erase(0, 1);
    e.kind = "linuxcnc";
    finish(e, [&] {
      if (!v.count('D')) fieldError("D", "(the diameter) is missing");
      const Shape s = linuxcncShape(comment, v['D'] * unit, sys);
      e.shankDiameter = s.shankDiameter;
      e.stickout = s.stickout;
      return s;
    });
    lib.tools.push_back(std::move(e));
  }
}

}  // namespace

std::string readToolFile(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw ParameterError(path + ": is a folder, not a " + what);
  const auto size = fs::file_size(path, ec);
  if (ec) throw ParameterError(path + ": cannot read the " + what + " (" + ec.message() + ")");
  if (size > kMaxLibraryBytes)
    throw ParameterError(path + ": " + std::to_string(size) + " bytes is too large for a " + what +
                         " (64 MiB at most)");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  if (!in && !in.eof()) throw ParameterError(path + ": cannot read the " + what);
  return s.str();
}

std::vector<const ToolEntry*> ToolLibrary::numbered(int number) const {
  std::vector<const ToolEntry*> out;
  for (const ToolEntry& e : tools)
    if (e.number == number) out.push_back(&e);
  return out;
}

const ToolEntry& ToolLibrary::require(int number) const {
  const auto found = numbered(number);
  if (found.empty()) {
    std::set<int> numbers;
    for (const ToolEntry& e : tools)
      if (e.number > 0) numbers.insert(e.number);
    std::string have;
    for (const int n : numbers)
      have += (have.empty() ? "" : ", ") + ("T" + std::to_string(n));
    throw ParameterError(path + ": no tool T" + std::to_string(number) + " (it has " +
                         (have.empty() ? std::string("none") : have) + ")");
  }
  if (found.size() > 1)
    throw ParameterError(path + ": " + std::to_string(found.size()) + " tools are numbered T" +
                         std::to_string(number) + " (" + found[0]->origin + ", " +
                         found[1]->origin + "): number them apart");
  const ToolEntry& e = *found.front();
  if (!e.cutter)
    throw ParameterError("tool T" + std::to_string(number) +
                         (e.name.empty() ? "" : " (" + e.name + ")") + " at " + e.origin + ": " +
                         e.problem);
  return e;
}

ToolLibrary parseToolLibrary(const std::string& text, const std::string& path,
                             const ToolLibraryOptions& options) {
  ToolLibrary lib;
  lib.path = path;
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && text[first] == '{') {
    const json doc = parseJson(text, path);
    try {
      if (doc.contains("data")) {
        lib.format = "fusion360";
        readFusion(doc, lib);
      } else if (doc.contains("tools") && doc.at("tools").is_array()) {
        lib.format = "freecad";
        readFreecadLibrary(doc, lib);
      } else if (doc.contains("tools") && doc.at("tools").is_object()) {
        lib.format = "camotics";
        readCamotics(doc.at("tools"), lib);
      } else if (doc.contains("shape")) {
        lib.format = "freecad";
        ToolEntry e;
        e.origin = path;
        e.number = 1;
        readFreecadBit(doc, e);
        lib.tools.push_back(std::move(e));
      } else {
        throw ParameterError(path +
                             ": a JSON file with none of \"data\" (Fusion 360), \"tools\" "
                             "(FreeCAD .fctl, CAMotics) or \"shape\" (FreeCAD .fctb)");
      }
    } catch (const json::exception& e) {
      throw ParameterError(path + ": unexpected JSON (" + std::string(e.what()) + ")");
    }
  } else {
    lib.format = "linuxcnc";
    readLinuxcnc(text, lib, options);
  }
  return lib;
}

ToolLibrary readToolLibrary(const std::string& path, const ToolLibraryOptions& options) {
  return parseToolLibrary(readToolFile(path, "tool library"), path, options);
}

}  // namespace engage
