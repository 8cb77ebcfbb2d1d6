#include "engine/run/RunReport.h"

#include "engine/report/HtmlPage.h"
#include "engine/report/SurfaceSteps.h"
#include "engine/run/Output.h"
#include "engine/run/StepsTable.h"
#include "engine/units/Quantity.h"
#include "stock/VoxelStock.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

namespace engage {
namespace {

using nlohmann::json;

/// Every step summary.json names (peaks, largest differences, collisions): kept in the plots.
void namedSteps(const json& j, std::set<std::size_t>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string& k = it.key();
      if ((k == "step" || k == "first_step" || k == "last_step") && it->is_number_unsigned())
        out.insert(it->get<std::size_t>());
      else
        namedSteps(*it, out);
    }
  } else if (j.is_array()) {
    for (const json& e : j)
      namedSteps(e, out);
  }
}

/// A number for the page: NaN and infinities (no model) become null, which the plots leave as
/// gaps; six significant digits otherwise, enough for any plot and hover.
json value(double v) {
  if (!std::isfinite(v)) return nullptr;
  return std::stod(formatNumber(v));
}

/// One column of the plots' table.
struct Column {
  std::string name;
  std::vector<double> values;  ///< per step of the run, display units
};

/// The series along the path, per step of the run, display units.
std::vector<Column> stepColumns(const RunResult& result) {
  const UnitSystem sys = result.job.units;
  const auto& steps = result.sim.steps;
  const bool schedule = result.job.scheduling();
  const bool physics = !result.sim.loads.empty();
  std::vector<Column> c;
  auto add = [&](const std::string& name, auto&& fn) {
    Column col{name, std::vector<double>(steps.size())};
    for (std::size_t i = 0; i < steps.size(); ++i)
      col.values[i] = fn(i);
    c.push_back(std::move(col));
  };
  auto D = [&](double v, Dimension d) { return toDisplay(v, d, sys); };
  add("arc", [&](std::size_t i) { return D(steps[i].arcLength, Dimension::Length); });
  add("x", [&](std::size_t i) { return D(steps[i].end.x(), Dimension::Length); });
  add("y", [&](std::size_t i) { return D(steps[i].end.y(), Dimension::Length); });
  add("z", [&](std::size_t i) { return D(steps[i].end.z(), Dimension::Length); });
  add("mrr", [&](std::size_t i) { return D(steps[i].mrr, Dimension::VolumeRate); });
  add("mrr_exact", [&](std::size_t i) { return D(steps[i].mrrExact, Dimension::VolumeRate); });
  add("feed", [&](std::size_t i) { return D(steps[i].feed, Dimension::Feed); });
  if (schedule) {
    add("feed_scheduled", [&](std::size_t i) { return D(result.plan.feed[i], Dimension::Feed); });
    add("mrr_scheduled", [&](std::size_t i) {
      return D(steps[i].mrr * feedScale(result, i), Dimension::VolumeRate);
    });
    add("acceleration", [&](std::size_t i) {
      return D(scheduledAcceleration(result, i), Dimension::Acceleration);
    });
  }
  if (physics) {
    const auto& loads = result.sim.loads;
    add("h_max", [&](std::size_t i) { return D(loads[i].hMax, Dimension::Length); });
    add("f_peak", [&](std::size_t i) { return D(loads[i].peak, Dimension::Force); });
    add("torque", [&](std::size_t i) { return D(loads[i].torque, Dimension::Torque); });
    add("power", [&](std::size_t i) { return D(loads[i].power, Dimension::Power); });
    if (schedule) {
      auto scaled = [&](std::size_t i) { return scaleLoad(loads[i], feedScale(result, i)); };
      add("h_max_scheduled", [&](std::size_t i) { return D(scaled(i).hMax, Dimension::Length); });
      add("f_peak_scheduled", [&](std::size_t i) { return D(scaled(i).peak, Dimension::Force); });
      add("torque_scheduled",
          [&](std::size_t i) { return D(scaled(i).torque, Dimension::Torque); });
      add("power_scheduled", [&](std::size_t i) { return D(scaled(i).power, Dimension::Power); });
    }
  }
  return c;
}

const Column* find(const std::vector<Column>& c, const std::string& name) {
  for (const Column& col : c)
    if (col.name == name) return &col;
  return nullptr;
}

/// The source lines of the given steps, "file:line" -> text (main program and subroutine files).
json sourceLines(const RunResult& result, const std::vector<std::size_t>& steps) {
  const Toolpath& path = result.job.path;
  std::map<int, std::vector<std::string>> files;
  json out = json::object();
  for (std::size_t s : steps) {
    const StepRecord& r = result.sim.steps[s];
    const int file = path.moves[r.move].file;
    const std::string key = std::to_string(file) + ":" + std::to_string(r.line);
    if (out.contains(key)) continue;
    auto it = files.find(file);
    if (it == files.end()) {
      std::vector<std::string> lines;
      try {
        std::istringstream in(readFile(path.files[static_cast<std::size_t>(file)]));
        for (std::string l; std::getline(in, l);) {
          if (!l.empty() && l.back() == '\r') l.pop_back();
          lines.push_back(l.size() > 200 ? l.substr(0, 200) + "..." : l);
        }
      } catch (const Error&) {
        // A program read from a generated text (a pocket) has no file: lines stay unnamed.
      }
      it = files.emplace(file, std::move(lines)).first;
    }
    if (r.line >= 1 && static_cast<std::size_t>(r.line) <= it->second.size())
      out[key] = it->second[static_cast<std::size_t>(r.line - 1)];
  }
  return out;
}

/// The stock's surface for the 3D view, in display units, with per vertex the step that last
/// cut there (an index into the returned table's steps, -1 for faces never cut).
json surfaceJson(const RunResult& result, const VoxelStock& voxels,
                 std::vector<std::size_t>& tableSteps) {
  double cell = 0.0;
  const TriangleMesh mesh = voxels.viewMesh(kMaxTriangles, &cell);
  const double h = result.stock->resolution();
  // Within a meshing cell and a half of the swept surface; steps below a hundredth of a
  // voxel removed nothing (air).
  const std::vector<int> last =
      lastCuttingSteps(mesh.points, result.job.path, result.sim.steps, result.job.cutters, h,
                       1.5 * cell, 0.01 * h * h * h);
  std::map<int, int> index;  // step -> its row in the table
  for (int s : last)
    if (s >= 0) index.emplace(s, 0);
  int row = 0;
  for (auto& [s, r] : index) {
    r = row++;
    tableSteps.push_back(static_cast<std::size_t>(s));
  }
  std::vector<std::int32_t> vertexRow(mesh.points.size());
  for (std::size_t i = 0; i < last.size(); ++i)
    vertexRow[i] = last[i] < 0 ? -1 : index[last[i]];
  const float f = static_cast<float>(displayFactor(Dimension::Length, result.job.units));
  std::vector<float> positions;
  positions.reserve(3 * mesh.points.size());
  for (const auto& p : mesh.points)
    for (float v : p)
      positions.push_back(v * f);
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    for (unsigned v : t)
      indices.push_back(v);
  return {{"vertices", mesh.points.size()},
          {"triangles", mesh.triangles.size()},
          {"cell", value(toDisplay(cell, Dimension::Length, result.job.units))},
          {"positions", base64(positions.data(), positions.size() * sizeof(float))},
          {"indices", base64(indices.data(), indices.size() * sizeof(std::uint32_t))},
          {"vertex_row", base64(vertexRow.data(), vertexRow.size() * sizeof(std::int32_t))}};
}

/// Columns of the given steps: step, file, line, tool, and every series.
json table(const RunResult& result, const std::vector<Column>& columns,
           const std::vector<std::size_t>& which) {
  const Toolpath& path = result.job.path;
  json t = json::object();
  json step = json::array(), file = json::array(), line = json::array(), tool = json::array();
  for (std::size_t s : which) {
    const StepRecord& r = result.sim.steps[s];
    step.push_back(s);
    file.push_back(path.moves[r.move].file);
    line.push_back(r.line);
    tool.push_back(r.tool);
  }
  t["step"] = std::move(step);
  t["file"] = std::move(file);
  t["line"] = std::move(line);
  t["tool"] = std::move(tool);
  for (const Column& c : columns) {
    json v = json::array();
    for (std::size_t s : which)
      v.push_back(value(c.values[s]));
    t[c.name] = std::move(v);
  }
  return t;
}

}  // namespace

std::vector<std::size_t> reportSteps(const RunResult& result, const std::string& summaryJsonText,
                                     std::size_t buckets, std::size_t allUpTo) {
  const std::size_t n = result.sim.steps.size();
  std::vector<std::size_t> keep;
  if (n <= allUpTo) {
    keep.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      keep[i] = i;
    return keep;
  }
  const std::vector<Column> columns = stepColumns(result);
  std::set<std::size_t> chosen;
  namedSteps(json::parse(summaryJsonText), chosen);
  // Where the tool changes.
  for (std::size_t i = 1; i < n; ++i)
    if (result.sim.steps[i].tool != result.sim.steps[i - 1].tool) chosen.insert(i);
  chosen.insert(0);
  chosen.insert(n - 1);
  struct Extreme {
    const char* column;
    bool highest;
  };
  const Extreme extremes[] = {{"mrr", true},           {"mrr", false},
                              {"mrr_exact", true},     {"mrr_exact", false},
                              {"mrr_scheduled", true}, {"feed_scheduled", false},
                              {"acceleration", true},  {"acceleration", false},
                              {"f_peak", true},        {"h_max", true}};
  for (std::size_t b = 0; b < buckets; ++b) {
    const std::size_t from = b * n / buckets, to = (b + 1) * n / buckets;
    for (const Extreme& e : extremes) {
      const Column* c = find(columns, e.column);
      if (!c || from >= to) continue;
      std::size_t best = from;
      for (std::size_t i = from; i < to; ++i) {
        const double v = c->values[i], w = c->values[best];
        if (std::isnan(w) || (e.highest ? v > w : v < w)) best = i;
      }
      chosen.insert(best);
    }
  }
  return {chosen.begin(), chosen.end()};
}

std::string runReportHtml(const RunResult& result, const std::string& summaryJsonText,
                          const std::vector<std::size_t>& kept, const WrittenOutputs& written,
                          const VoxelStock* surface) {
  const Job& job = result.job;
  const UnitSystem sys = job.units;
  json data;
  data["kind"] = "run";
  data["command"] = job.scheduling() ? "schedule" : "simulate";
  data["summary"] = json::parse(summaryJsonText);
  data["warnings"] = runWarnings(result, written);
  auto label = [&](Dimension d) { return std::string(unitLabel(d, sys)); };
  data["units"] = {{"length", label(Dimension::Length)},
                   {"volume", label(Dimension::Volume)},
                   {"mrr", label(Dimension::VolumeRate)},
                   {"feed", label(Dimension::Feed)},
                   {"acceleration", label(Dimension::Acceleration)},
                   {"force", label(Dimension::Force)},
                   {"torque", label(Dimension::Torque)},
                   {"power", label(Dimension::Power)}};
  json files = json::array();
  if (written.steps) files.push_back("steps.csv");
  files.push_back("summary.json");
  if (written.refedProgram)
    files.push_back(std::filesystem::path(job.mainProgram()).filename().string());
  if (written.stockFiles)
    for (const char* f : {"removed.vdb", "stock.vdb", "stock.stl"})
      files.push_back(f);
  for (const std::string& p : written.plots)
    files.push_back(p);
  data["files"] = files;
  json sources = json::array();
  for (const std::string& f : job.path.files)
    sources.push_back(f);
  data["sources"] = sources;

  // Limits drawn on the plots (display units; absent when none).
  json limits = json::object();
  if (job.scheduling()) {
    const ScheduleOptions& o = job.schedule;
    auto limit = [&](const char* name, double v, Dimension d) {
      if (v > 0.0) limits[name] = value(toDisplay(v, d, sys));
    };
    limit("acceleration", o.acceleration, Dimension::Acceleration);
    limit("h_max", o.maxChip, Dimension::Length);
    limit("f_peak", o.maxForce, Dimension::Force);
    limit("torque", o.maxTorque, Dimension::Torque);
    limit("power", o.maxPower, Dimension::Power);
    if (o.mrrTarget && result.plan.targets.size() <= 1)
      limit("mrr", result.plan.targetMrr, Dimension::VolumeRate);
  }
  data["limits"] = limits;

  const std::vector<Column> columns = stepColumns(result);
  data["series"] = table(result, columns, kept);
  data["series_steps"] = {{"kept", kept.size()},
                          {"of", result.sim.steps.size()},
                          {"all_up_to", kAllSteps},
                          {"buckets", kBuckets}};
  std::vector<std::size_t> lineSteps = kept;
  if (surface) {
    std::vector<std::size_t> tableSteps;
    data["surface"] = surfaceJson(result, *surface, tableSteps);
    data["surface_steps"] = table(result, columns, tableSteps);
    lineSteps.insert(lineSteps.end(), tableSteps.begin(), tableSteps.end());
  }
  data["source"] = sourceLines(result, lineSteps);
  const std::string title = "engage " + data["command"].get<std::string>() + ": " +
                            std::filesystem::path(job.program).filename().string();
  data["title"] = title;
  const std::string text = data.dump(-1, ' ', false, json::error_handler_t::replace);
  data = json();  // (its nodes are larger than its text)
  return htmlPage(PageKind::Run, title, text);
}

}  // namespace engage
