#include "engine/run/Machine.h"

#include "cutters/Error.h"
#include "engine/run/JsonFile.h"

#include <cmath>
#include <string>

namespace engage {

Dialect dialectOf(const std::string& name) {
  if (name.empty() || name == "linuxcnc") return Dialect::LinuxCNC;
  if (name == "fanuc") return Dialect::Fanuc;
  if (name == "haas") return Dialect::Haas;
  if (name == "grbl") return Dialect::Grbl;
  throw ParameterError("--dialect: expected linuxcnc, fanuc, haas or grbl, found '" + name + "'");
}

namespace {

/// The "kinematics" object of a machine file (Machine.h); `point` reads [x, y, z] in mm.
template <typename Point>
Kinematics readKinematics(const std::string& path, const nlohmann::json& k, Point&& point,
                          double unit) {
  if (!k.is_object() || !k.contains("type") || !k["type"].is_string())
    throw Error(path + ": \"kinematics\" must be an object with a \"type\", found " + k.dump());
  Kinematics out;
  try {
    out.type = kinematicsTypeOf(k["type"].get<std::string>());
  } catch (const ParameterError& e) {
    throw Error(path + ": \"kinematics.type\": " + e.what());
  }
  const bool table = out.type != Kinematics::Type::HeadBC && out.type != Kinematics::Type::Trivial;
  const bool trunnion =
      out.type == Kinematics::Type::TableAC || out.type == Kinematics::Type::TableBC;
  const bool head =
      out.type == Kinematics::Type::HeadBC || out.type == Kinematics::Type::HeadBTableC;
  for (const auto& [key, value] : k.items()) {
    const bool known = key == "type" || key == "tcp" || (key == "rot_point" && table) ||
                       (key == "offset" && trunnion) || (key == "pivot_length" && head);
    if (!known)
      throw Error(path + ": \"kinematics\": unknown key \"" + key + "\" for type " +
                  kinematicsTypeName(out.type) + " (expected type, tcp" +
                  (table ? ", rot_point" : "") + (trunnion ? ", offset" : "") +
                  (head ? ", pivot_length" : "") + ")");
  }
  if (k.contains("tcp")) {
    if (!k["tcp"].is_boolean())
      throw Error(path + ": \"kinematics.tcp\" must be true or false, found " + k["tcp"].dump());
    out.tcp = k["tcp"].get<bool>();
  }
  if (k.contains("rot_point")) out.rotPoint = point(k["rot_point"], "kinematics.rot_point");
  if (k.contains("offset")) {
    out.offset = point(k["offset"], "kinematics.offset");
    const int unused = out.type == Kinematics::Type::TableAC ? 0 : 1;  // x for A's, y for B's
    if (out.offset[unused] != 0.0)
      throw Error(path + ": \"kinematics.offset\" of a " + kinematicsTypeName(out.type) +
                  " trunnion has no " + std::string(1, static_cast<char>('x' + unused)) +
                  " (its tilt axis is offset from C's along " +
                  (unused == 0 ? "y and z" : "x and z") + "), found " + k["offset"].dump());
  }
  if (head) {
    if (!k.contains("pivot_length") || !k["pivot_length"].is_number() ||
        !(k["pivot_length"].get<double>() > 0.0) || !std::isfinite(k["pivot_length"].get<double>()))
      throw Error(path +
                  ": \"kinematics.pivot_length\" must be a positive number (the head's "
                  "pivot to the tool tip) for type " +
                  kinematicsTypeName(out.type) + ", found " +
                  (k.contains("pivot_length") ? k["pivot_length"].dump() : "none"));
    out.pivotLength = k["pivot_length"].get<double>() * unit;
  }
  return out;
}

}  // namespace

MachineSetup readMachine(const std::string& path) {
  using nlohmann::json;
  const json doc = readJsonFile(path);
  if (!doc.is_object()) throw Error(path + ": expected a JSON object (a machine description)");
  for (const auto& [key, value] : doc.items())
    if (key != "units" && key != "work_offset" && key != "g28" && key != "g30" && key != "start" &&
        key != "travel" && key != "name" && key != "startup_units" && key != "kinematics")
      throw Error(path + ": unknown key \"" + key +
                  "\" (expected units, work_offset, g28, g30, start, travel, startup_units, "
                  "kinematics, name)");
  double unit = 1.0;
  if (doc.contains("units")) {
    const json& u = doc["units"];
    if (!u.is_string() || (u != "mm" && u != "in"))
      throw Error(path + ": \"units\" must be \"mm\" or \"in\", found " + u.dump());
    unit = u == "in" ? 25.4 : 1.0;
  }
  auto point = [&](const json& v, const std::string& key) {
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() ||
        !v[2].is_number())
      throw Error(path + ": \"" + key + "\" must be [x, y, z] (three numbers), found " + v.dump());
    Eigen::Vector3d p;
    for (int a = 0; a < 3; ++a) {
      p[a] = v[static_cast<std::size_t>(a)].get<double>() * unit;
      if (!std::isfinite(p[a]))
        throw Error(path + ": \"" + key + "\" must hold finite numbers, found " + v.dump());
    }
    return p;
  };
  MachineSetup m;
  m.name = path;
  if (doc.contains("startup_units")) {
    const json& u = doc["startup_units"];
    if (!u.is_string() || (u != "mm" && u != "in"))
      throw Error(path + ": \"startup_units\" must be \"mm\" or \"in\", found " + u.dump());
    m.startInch = u == "in";
    m.startUnitsGiven = true;
  }
  if (doc.contains("work_offset")) m.workOffset = point(doc["work_offset"], "work_offset");
  if (doc.contains("g28")) m.g28 = point(doc["g28"], "g28");
  if (doc.contains("g30")) m.g30 = point(doc["g30"], "g30");
  if (doc.contains("start")) {
    const json& s = doc["start"];
    m.start = s == "g28" ? m.g28 : s == "g30" ? m.g30 : point(s, "start");
  }
  const json noTravel = json::object();
  const json& t = doc.contains("travel") ? doc["travel"] : noTravel;
  if (doc.contains("travel") &&
      (!t.is_object() || t.empty() || t.contains("min") != t.contains("max")))
    throw Error(path +
                ": \"travel\" must be {\"min\": [x, y, z], \"max\": [x, y, z]} and, for rotary "
                "axes, \"A\", \"B\", \"C\": [min, max] in degrees, found " +
                t.dump());
  for (const auto& [key, value] : t.items())
    if (key != "min" && key != "max" && key != "A" && key != "B" && key != "C")
      throw Error(path + ": \"travel\": unknown key \"" + key + "\" (expected min, max, A, B, C)");
  if (t.contains("min")) {
    m.travelMin = point(t["min"], "travel.min");
    m.travelMax = point(t["max"], "travel.max");
    for (int a = 0; a < 3; ++a)
      if (!(m.travelMin[a] <= m.travelMax[a]))
        throw Error(path + ": \"travel\": min must not exceed max along " +
                    std::string(1, static_cast<char>('X' + a)));
    m.limited = true;
    for (int a = 0; a < 3; ++a)
      if (m.start[a] < m.travelMin[a] - 1e-9 || m.start[a] > m.travelMax[a] + 1e-9)
        throw Error(path + ": \"start\" lies outside the travel along " +
                    std::string(1, static_cast<char>('X' + a)));
  }
  if (doc.contains("kinematics"))
    m.kinematics = readKinematics(path, doc["kinematics"], point, unit);
  // The rotary axes' travel, in degrees whatever the file's units; they start at 0.
  for (int a = 0; a < 3; ++a) {
    const std::string axis(1, static_cast<char>('A' + a));
    if (!t.contains(axis)) continue;
    const json& r = t[axis];
    if (m.kinematics.rotaryAxes().find(axis) == std::string::npos)
      throw Error(path + ": \"travel\": \"" + axis + "\" is not a rotary axis of this machine (" +
                  (m.kinematics.rotary()
                       ? "its kinematics " + std::string(kinematicsTypeName(m.kinematics.type)) +
                             " turns " + m.kinematics.rotaryAxes()
                       : std::string("it has no \"kinematics\"")) +
                  ")");
    if (!r.is_array() || r.size() != 2 || !r[0].is_number() || !r[1].is_number() ||
        !std::isfinite(r[0].get<double>()) || !std::isfinite(r[1].get<double>()) ||
        !(r[0].get<double>() <= r[1].get<double>()))
      throw Error(path + ": \"travel." + axis +
                  "\" must be [min, max] in degrees, min not above max, found " + r.dump());
    m.rotaryMin[a] = r[0].get<double>();
    m.rotaryMax[a] = r[1].get<double>();
    if (m.rotaryMin[a] > 0.0 || m.rotaryMax[a] < 0.0)
      throw Error(path + ": \"travel." + axis +
                  "\" must hold 0 (the rotary axes start there), found " + r.dump());
  }
  return m;
}

}  // namespace engage
