#include "engine/physics/Material.h"

#include "cutters/Error.h"
#include "engine/paths/DataDirectory.h"
#include "engine/tools/ToolLibrary.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace engage {
namespace {

using json = nlohmann::json;

/// A number field of `o`: `required` or 0 when absent. Throws naming the file and field.
double number(const json& o, const std::string& block, const char* key, bool required,
              const std::string& file) {
  const auto it = o.find(key);
  if (it == o.end()) {
    if (required)
      throw ParameterError(file + ": \"" + block + "\" needs \"" + key + "\" (a number)");
    return 0.0;
  }
  if (!it->is_number() || !std::isfinite(it->get<double>()))
    throw ParameterError(file + ": \"" + block + "." + key + "\" must be a number, found " +
                         it->dump());
  return it->get<double>();
}

std::string text(const json& o, const char* key) {
  const auto it = o.find(key);
  return it != o.end() && it->is_string() ? it->get<std::string>() : std::string();
}

}  // namespace

std::string materialFolder() {
  return dataDirectory() + "/materials";
}

std::vector<std::string> bundledMaterials() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(materialFolder(), ec))
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

bool materialIsFile(const std::string& nameOrPath) {
  return nameOrPath.find('/') != std::string::npos ||
         (nameOrPath.size() > 5 && nameOrPath.substr(nameOrPath.size() - 5) == ".json");
}

std::string materialFile(const std::string& nameOrPath) {
  return materialIsFile(nameOrPath) ? nameOrPath : materialFolder() + "/" + nameOrPath + ".json";
}

Material readMaterial(const std::string& nameOrPath, const std::string& model) {
  const std::string path = materialFile(nameOrPath);
  if (!materialIsFile(nameOrPath)) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
      std::string list;
      for (const std::string& n : bundledMaterials())
        list += (list.empty() ? "" : ", ") + n;
      throw ParameterError("--material: no material named '" + nameOrPath +
                           "'; the bundled ones are " + (list.empty() ? "(none found)" : list) +
                           ", or give a .json file");
    }
  }
  json j;
  try {
    j = json::parse(readToolFile(path, "material file"));
  } catch (const json::exception& e) {
    throw ParameterError(path + ": not a material file (JSON): " + e.what());
  }
  if (!j.is_object()) throw ParameterError(path + ": a material file is a JSON object");
  Material m;
  m.path = path;
  m.name = text(j, "name");
  if (m.name.empty()) m.name = std::filesystem::path(path).stem().string();
  const bool hasLinear = j.contains("linear"), hasKienzle = j.contains("kienzle");
  std::string pick = model.empty() ? text(j, "model") : model;
  if (pick.empty()) pick = hasLinear ? "linear" : "kienzle";
  if (pick != "linear" && pick != "kienzle")
    throw ParameterError(path + ": the model is \"linear\" or \"kienzle\", found \"" + pick + "\"");
  const bool linear = pick == "linear";
  if (linear ? !hasLinear : !hasKienzle)
    throw ParameterError(path + ": has no \"" + pick + "\" coefficients" +
                         (hasLinear || hasKienzle ? std::string(" (it has \"") +
                                                        (hasLinear ? "linear" : "kienzle") + "\")"
                                                  : std::string()));
  const std::string block = linear ? "linear" : "kienzle";
  const json& c = j.at(block);
  if (!c.is_object()) throw ParameterError(path + ": \"" + block + "\" must be an object");
  m.source = text(c, "source");
  m.conditions = text(c, "conditions");
  if (m.source.empty())
    throw ParameterError(path + ": \"" + block +
                         ".source\" is missing: say where the coefficients come from");
  if (linear) {
    m.model = ForceModel::Linear;
    LinearCoefficients& k = m.linear;
    k.Ktc = number(c, block, "Ktc", true, path);
    k.Krc = number(c, block, "Krc", true, path);
    k.Kac = number(c, block, "Kac", false, path);
    k.Kte = number(c, block, "Kte", false, path);
    k.Kre = number(c, block, "Kre", false, path);
    k.Kae = number(c, block, "Kae", false, path);
    if (!(k.Ktc > 0.0))
      throw ParameterError(path + ": \"linear.Ktc\" must be positive (N/mm^2), found " +
                           c.at("Ktc").dump());
  } else {
    m.model = ForceModel::Kienzle;
    KienzleCoefficients& k = m.kienzle;
    k.kc11 = number(c, block, "kc11", true, path);
    k.mc = number(c, block, "mc", true, path);
    k.kf11 = number(c, block, "kf11", false, path);
    k.mf = number(c, block, "mf", false, path);
    k.kp11 = number(c, block, "kp11", false, path);
    k.mp = number(c, block, "mp", false, path);
    if (!(k.kc11 > 0.0))
      throw ParameterError(path + ": \"kienzle.kc11\" must be positive (N/mm^2), found " +
                           c.at("kc11").dump());
    for (const auto& [key, value] : {std::pair{"mc", k.mc}, {"mf", k.mf}, {"mp", k.mp}})
      if (!(value >= 0.0 && value < 1.0))
        throw ParameterError(path + ": \"kienzle." + key + "\" must be in [0, 1), found " +
                             std::to_string(value));
    if (k.kf11 < 0.0 || k.kp11 < 0.0)
      throw ParameterError(path + ": \"kienzle.kf11\" and \"kp11\" must not be negative");
  }
  return m;
}

}  // namespace engage
