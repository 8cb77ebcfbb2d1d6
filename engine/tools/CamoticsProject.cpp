#include "engine/tools/CamoticsProject.h"

#include "cutters/Error.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <limits>

namespace engage {

namespace {

/// A file name's extension in lower case (".camotics", ".tpl").
std::string extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

bool isCamoticsProject(const std::string& path) {
  return extension(path) == ".camotics";
}

CamoticsProject readCamoticsProject(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string text = readToolFile(path, "CAMotics project");
  CamoticsProject p;
  p.path = path;
  // (Parsed here and again by parseToolLibrary: a project is a few kB.)
  const nlohmann::json doc = nlohmann::json::parse(text, nullptr, false);
  if (!doc.is_discarded() &&
      !(doc.is_object() && doc.contains("tools") && doc.at("tools").is_object()))
    throw ParameterError(path + ": a CAMotics project has a \"tools\" object; this file has none");
  // The tool table, with the checks of every library format (and its message for bad JSON).
  p.tools = parseToolLibrary(text, path);
  const fs::path dir = fs::path(path).parent_path();
  if (!doc.contains("files") || !doc.at("files").is_array() || doc.at("files").empty())
    throw ParameterError(path + ": \"files\": expected the list of the project's programs");
  for (const auto& f : doc.at("files")) {
    if (!f.is_string()) throw ParameterError(path + ": \"files\": expected file names");
    const fs::path file = dir / f.get<std::string>();
    if (extension(file) == ".tpl")
      throw ParameterError(path + ": \"" + f.get<std::string>() +
                           "\" is a TPL program (CAMotics' JavaScript tool-path language), "
                           "which engage does not run: export its G-code from CAMotics "
                           "(File > Export) and give that");
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      throw ParameterError(path + ": \"files\": no program \"" + file.string() + "\"");
    p.files.push_back(file.lexically_normal().string());
  }
  const nlohmann::json w =
      doc.contains("workpiece") ? doc.at("workpiece") : nlohmann::json::object();
  auto number = [&](const nlohmann::json& o, const char* key, double fallback) {
    if (!o.contains(key)) return fallback;
    if (!o.at(key).is_number())
      throw ParameterError(path + ": workpiece." + key + ": expected a number, found " +
                           o.at(key).dump());
    return o.at(key).get<double>();
  };
  p.automatic = w.contains("automatic") && w.at("automatic").is_boolean()
                    ? w.at("automatic").get<bool>()
                    : true;  // CAMotics' default
  p.marginPercent = number(w, "margin", 5.0);
  if (!(p.marginPercent >= 0.0 && p.marginPercent <= 1000.0))
    throw ParameterError(path + ": workpiece.margin: expected a percentage in [0, 1000]");
  if (!p.automatic) {
    const nlohmann::json b = w.contains("bounds") ? w.at("bounds") : nlohmann::json();
    auto corner = [&](const char* key) {
      if (!b.is_object() || !b.contains(key) || !b.at(key).is_array() || b.at(key).size() != 3 ||
          !std::all_of(b.at(key).begin(), b.at(key).end(),
                       [](const nlohmann::json& v) { return v.is_number(); }))
        throw ParameterError(path + ": workpiece.bounds." + key +
                             ": expected [x, y, z] in mm (or \"automatic\": true)");
      return Eigen::Vector3d(b.at(key)[0].get<double>(), b.at(key)[1].get<double>(),
                             b.at(key)[2].get<double>());
    };
    p.bounds.min = corner("min");
    p.bounds.max = corner("max");
    if (!((p.bounds.max - p.bounds.min).array() > 0.0).all())
      throw ParameterError(path + ": workpiece.bounds: max must exceed min on every axis");
  }
  return p;
}

Box3 camoticsAutomaticWorkpiece(const Toolpath& path,
                                const std::function<const AptCutter&(int tool)>& cutterOf,
                                double marginPercent) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  bool any = false;
  for (const Move& m : path.moves) {
    if (m.kind == MoveKind::Rapid) continue;
    const AptCutter& c = cutterOf(m.tool);
    const double r = c.maxRadius();
    // CAMotics' ball-nose sweep box starts one radius below the tip and reaches at least
    // a diameter above it (sim/SpheroidSweep.cpp, sim/ToolSweep.cpp).
    const bool ball = c.shape() == CutterShape::Ball;
    const double below = ball ? r : 0.0;
    const double above = ball ? std::max(c.height(), 2.0 * r) : c.height();
    // Arcs and splines as CAMotics has them, in line pieces.
    const int pieces = m.kind == MoveKind::Line ? 1 : 64;
    for (int k = 0; k <= pieces; ++k) {
      const Eigen::Vector3d p = k == 0 ? m.start : pointAt(m, static_cast<double>(k) / pieces);
      lo = lo.cwiseMin(p - Eigen::Vector3d(r, r, below));
      hi = hi.cwiseMax(p + Eigen::Vector3d(r, r, above));
    }
    any = true;
  }
  if (!any)
    throw ParameterError("an automatic workpiece needs cutting moves; the program has none");
  if (lo.z() < 0.0) hi.z() = 0.0;
  if (hi.z() - lo.z() < 2.0) lo.z() -= 2.0;  // "at least 2mm thick", as CAMotics has it
  const Eigen::Vector3d margin = (hi - lo) * marginPercent / 100.0;
  lo -= margin;
  hi.x() += margin.x();
  hi.y() += margin.y();
  return {lo, hi};
}

}  // namespace engage
