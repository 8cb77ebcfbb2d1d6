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

MachineSetup readMachine(const std::string& path) {
  using nlohmann::json;
  const json doc = readJsonFile(path);
  if (!doc.is_object()) throw Error(path + ": expected a JSON object (a machine description)");
  for (const auto& [key, value] : doc.items())
    if (key != "units" && key != "work_offset" && key != "g28" && key != "g30" && key != "start" &&
        key != "travel" && key != "name" && key != "startup_units")
      throw Error(path + ": unknown key \"" + key +
                  "\" (expected units, work_offset, g28, g30, start, travel, startup_units, "
                  "name)");
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
  if (doc.contains("travel")) {
    const json& t = doc["travel"];
    if (!t.is_object() || !t.contains("min") || !t.contains("max") || t.size() != 2)
      throw Error(path + ": \"travel\" must be {\"min\": [x, y, z], \"max\": [x, y, z]}, found " +
                  t.dump());
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
  return m;
}

}  // namespace engage
