#include "engine/run/RunReport.h"

#include "cutters/Error.h"
#include "engine/report/HtmlPage.h"
#include "engine/report/SurfaceSteps.h"
#include "engine/run/StepsTable.h"
#include "engine/units/Quantity.h"
#include "stock/VoxelStock.h"

#include <nlohmann/json.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string_view>

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

/// One column of the plots' table: its value at a step of the run, display units. Computed
/// where read, not held per step (seven to seventeen columns of every step of a long run
/// would be at the run's peak).
struct Column {
  std::string name;
  std::function<double(std::size_t)> at;
};

/// The series along the path, per step of the run, display units.
std::vector<Column> stepColumns(const RunResult& result) {
  const UnitSystem sys = result.job.units;
  const StepRecord* steps = result.sim.steps.data();
  const RunResult* run = &result;
  const bool schedule = result.job.scheduling();
  const bool physics = !result.sim.loads.empty();
  std::vector<Column> c;
  // Each column reads the run through the pointers above (the columns outlive this call).
  auto add = [&](const std::string& name, Dimension d, auto fn) {
    c.push_back({name, [fn, d, sys](std::size_t i) { return toDisplay(fn(i), d, sys); }});
  };
  add("arc", Dimension::Length, [steps](std::size_t i) { return steps[i].arcLength; });
  add("x", Dimension::Length, [steps](std::size_t i) { return steps[i].end.x(); });
  add("y", Dimension::Length, [steps](std::size_t i) { return steps[i].end.y(); });
  add("z", Dimension::Length, [steps](std::size_t i) { return steps[i].end.z(); });
  add("mrr", Dimension::VolumeRate, [steps](std::size_t i) { return steps[i].mrr; });
  add("mrr_exact", Dimension::VolumeRate, [steps](std::size_t i) { return steps[i].mrrExact; });
  add("feed", Dimension::Feed, [steps](std::size_t i) { return steps[i].feed; });
  if (schedule) {
    add("feed_scheduled", Dimension::Feed, [run](std::size_t i) { return run->plan.feed[i]; });
    add("mrr_scheduled", Dimension::VolumeRate,
        [run](std::size_t i) { return run->sim.steps[i].mrr * feedScale(*run, i); });
    add("acceleration", Dimension::Acceleration,
        [run](std::size_t i) { return scheduledAcceleration(*run, i); });
  }
  if (physics) {
    const StepLoad* loads = result.sim.loads.data();
    add("h_max", Dimension::Length, [loads](std::size_t i) { return loads[i].hMax; });
    add("f_peak", Dimension::Force, [loads](std::size_t i) { return loads[i].peak; });
    add("torque", Dimension::Torque, [loads](std::size_t i) { return loads[i].torque; });
    add("power", Dimension::Power, [loads](std::size_t i) { return loads[i].power; });
    if (schedule) {
      auto scaled = [run, loads](std::size_t i) { return scaleLoad(loads[i], feedScale(*run, i)); };
      add("h_max_scheduled", Dimension::Length, [scaled](std::size_t i) { return scaled(i).hMax; });
      add("f_peak_scheduled", Dimension::Force, [scaled](std::size_t i) { return scaled(i).peak; });
      add("torque_scheduled", Dimension::Torque,
          [scaled](std::size_t i) { return scaled(i).torque; });
      add("power_scheduled", Dimension::Power, [scaled](std::size_t i) { return scaled(i).power; });
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
/// Each file is read once, line by line, keeping the lines asked for (a program held whole as
/// a vector of lines takes four times its size in strings).
json sourceLines(const RunResult& result, const std::vector<std::size_t>& steps) {
  const Toolpath& path = result.job.path;
  std::map<int, std::set<int>> wanted;  // file -> its lines
  for (std::size_t s : steps) {
    const StepRecord& r = result.sim.steps[s];
    if (r.line >= 1) wanted[path.moves[r.move].file].insert(r.line);
  }
  json out = json::object();
  for (const auto& [file, lines] : wanted) {
    // A program read from a generated text (a pocket) has no file: its lines stay unnamed.
    std::ifstream in(path.files[static_cast<std::size_t>(file)], std::ios::binary);
    auto next = lines.begin();
    int number = 0;
    for (std::string l; next != lines.end() && std::getline(in, l);) {
      if (++number != *next) continue;
      if (!l.empty() && l.back() == '\r') l.pop_back();
      out[std::to_string(file) + ":" + std::to_string(number)] =
          l.size() > 200 ? l.substr(0, 200) + "..." : l;
      ++next;
    }
  }
  return out;
}

/// The stock's surface for the 3D view, in display units, with per vertex the step that last
/// cut there (an index into the returned table's steps, -1 for faces never cut).
json surfaceJson(const RunResult& result, const TriangleMesh& mesh, double cell,
                 std::vector<std::size_t>& tableSteps) {
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
  // mm to display units (displayFactor is display to internal: 25.4 for inches).
  const float f = static_cast<float>(1.0 / displayFactor(Dimension::Length, result.job.units));
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
  json out = {{"vertices", mesh.points.size()},
              {"triangles", mesh.triangles.size()},
              {"cell", value(toDisplay(cell, Dimension::Length, result.job.units))},
              {"positions", base64(positions.data(), positions.size() * sizeof(float))},
              {"indices", base64(indices.data(), indices.size() * sizeof(std::uint32_t))},
              {"vertex_row", base64(vertexRow.data(), vertexRow.size() * sizeof(std::int32_t))}};
  if (result.partModel) {
    // Each vertex's signed distance from the part (display units), and the colour scale's
    // half range: five times the larger of the tolerance and the allowance.
    std::vector<float> deviation(mesh.points.size());
    const Part& part = *result.partModel;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, mesh.points.size(), 1024),
        [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const auto& p = mesh.points[i];
            deviation[i] = static_cast<float>(part.signedDistance({p[0], p[1], p[2]})) * f;
          }
        });
    out["deviation"] = base64(deviation.data(), deviation.size() * sizeof(float));
    const PartSpec& spec = result.part.spec;
    out["deviation_range"] =
        value(5.0 * std::max({spec.tolerance, spec.allowance, 0.1 * h}) * static_cast<double>(f));
  }
  return out;
}

}  // namespace

ReportSurface reportSurface(const RunResult& result, const TriangleMesh& mesh, double cell) {
  ReportSurface out;
  out.json = surfaceJson(result, mesh, cell, out.steps).dump();
  return out;
}

namespace {

/// Columns of the given steps as JSON text: step, file, line, tool, and every series (numbers
/// as value() gives them). Written as text: nlohmann::json's nodes for every plotted step
/// would take megabytes.
std::string table(const RunResult& result, const std::vector<Column>& columns,
                  const std::vector<std::size_t>& which) {
  const Toolpath& path = result.job.path;
  std::string t = "{";
  auto column = [&](const std::string& name, auto&& text) {
    t += (t.size() > 1 ? ",\"" : "\"") + name + "\":[";
    for (std::size_t k = 0; k < which.size(); ++k) {
      if (k > 0) t += ',';
      t += text(which[k]);
    }
    t += ']';
  };
  const auto& steps = result.sim.steps;
  column("step", [](std::size_t s) { return std::to_string(s); });
  column("file", [&](std::size_t s) { return std::to_string(path.moves[steps[s].move].file); });
  column("line", [&](std::size_t s) { return std::to_string(steps[s].line); });
  column("tool", [&](std::size_t s) { return std::to_string(steps[s].tool); });
  for (const Column& c : columns)
    column(c.name, [&](std::size_t s) {
      const double v = c.at(s);
      return std::isfinite(v) ? formatNumber(v) : std::string("null");
    });
  return t + "}";
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
      double w = c->at(from);
      for (std::size_t i = from; i < to; ++i) {
        const double v = c->at(i);
        if (std::isnan(w) || (e.highest ? v > w : v < w)) {
          best = i;
          w = v;
        }
      }
      chosen.insert(best);
    }
  }
  return {chosen.begin(), chosen.end()};
}

void writeRunReportHtml(std::ostream& os, const RunResult& result,
                        const std::string& summaryJsonText, const std::vector<std::size_t>& kept,
                        const WrittenOutputs& written, const ReportSurface* surface) {
  const Job& job = result.job;
  const UnitSystem sys = job.units;
  json data;
  data["kind"] = "run";
  data["command"] = job.scheduling() ? "schedule" : "simulate";
  data["summary"] = json::parse(summaryJsonText);
  data["warnings"] = runWarnings(result, written);
  auto label = [&](Dimension d) { return std::string(unitLabel(d, sys)); };
  data["units"] = {
      {"length", label(Dimension::Length)}, {"volume", label(Dimension::Volume)},
      {"area", label(Dimension::Area)},     {"mrr", label(Dimension::VolumeRate)},
      {"feed", label(Dimension::Feed)},     {"acceleration", label(Dimension::Acceleration)},
      {"force", label(Dimension::Force)},   {"torque", label(Dimension::Torque)},
      {"power", label(Dimension::Power)}};
  json files = json::array();
  if (written.steps) files.push_back("steps.csv");
  files.push_back("summary.json");
  if (written.refedProgram)
    files.push_back(std::filesystem::path(job.mainProgram()).filename().string());
  if (written.stockFiles)
    for (const char* f : {"removed.vdb", "stock.vdb", "stock.stl"})
      files.push_back(f);
  if (written.partTables)
    for (const char* f : {"gouges.csv", "leftovers.csv"})
      files.push_back(f);
  if (written.deviationVdb) files.push_back("deviation.vdb");
  for (const std::string& p : written.plots)
    files.push_back(p);
  data["files"] = files;
  // The source text of the lines that cut the gouges (the first 20 of each of the first 100).
  if (result.part.done) {
    std::vector<std::size_t> gougeSteps;
    for (std::size_t g = 0; g < result.part.gouges.size() && g < 100; ++g) {
      const std::vector<GougeLine> lines =
          gougeLines(result.part.gouges[g], job.path, result.sim.steps);
      for (std::size_t k = 0; k < lines.size() && k < 20; ++k)
        gougeSteps.push_back(lines[k].steps.front());
    }
    data["part_lines"] = sourceLines(result, gougeSteps);
  }
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

  // The step tables and the 3D view go into the text where their marks are (table()).
  const std::vector<Column> columns = stepColumns(result);
  std::vector<std::pair<std::string, std::string_view>> spliced;  // key, JSON text (not copied)
  auto splice = [&](const char* key, std::string_view text) {
    spliced.emplace_back(key, text);
    data[key] = std::string("\x01") + key;  // the mark
  };
  const std::string series = table(result, columns, kept);
  splice("series", series);
  data["series_steps"] = {{"kept", kept.size()},
                          {"of", result.sim.steps.size()},
                          {"all_up_to", kAllSteps},
                          {"buckets", kBuckets}};
  std::vector<std::size_t> lineSteps = kept;
  std::string surfaceSteps;
  if (surface) {
    surfaceSteps = table(result, columns, surface->steps);
    splice("surface", surface->json);
    splice("surface_steps", surfaceSteps);
    lineSteps.insert(lineSteps.end(), surface->steps.begin(), surface->steps.end());
  }
  data["source"] = sourceLines(result, lineSteps);
  const std::string title = "engage " + data["command"].get<std::string>() + ": " +
                            std::filesystem::path(job.program).filename().string();
  data["title"] = title;
  const std::string text = data.dump(-1, ' ', false, json::error_handler_t::replace);
  data = json();  // (its nodes are larger than its text)
  // The text in pieces, each spliced text in place of its mark: `"key":"\u0001key"` is found once,
  // at the top level (in a string value its quotes would be escaped).
  struct Spliced {
    std::size_t where, length;  // the mark's place in the text
    std::string_view text;      // what goes there
    bool operator<(const Spliced& o) const { return where < o.where; }
  };
  std::vector<Spliced> at;
  for (const auto& [key, piece] : spliced) {
    const std::string keyText = json(key).dump() + ":";
    const std::string marked = keyText + json(std::string("\x01") + key).dump();
    const std::size_t where = text.find(marked);
    if (where == std::string::npos) throw Error("report: the mark of '" + key + "' is missing");
    at.push_back({where + keyText.size(), marked.size() - keyText.size(), piece});
  }
  std::sort(at.begin(), at.end());
  std::vector<std::string_view> pieces;
  std::size_t from = 0;
  for (const Spliced& a : at) {
    pieces.emplace_back(text.data() + from, a.where - from);
    pieces.push_back(a.text);
    from = a.where + a.length;
  }
  pieces.emplace_back(text.data() + from, text.size() - from);
  writeHtmlPage(os, PageKind::Run, title, pieces);
}

std::string runReportHtml(const RunResult& result, const std::string& summaryJsonText,
                          const std::vector<std::size_t>& kept, const WrittenOutputs& written,
                          const VoxelStock* surface) {
  std::ostringstream os;
  ReportSurface shown;
  if (surface) {
    double cell = 0.0;
    const TriangleMesh mesh = surface->viewMesh(kMaxTriangles, &cell);
    shown = reportSurface(result, mesh, cell);
  }
  writeRunReportHtml(os, result, summaryJsonText, kept, written, surface ? &shown : nullptr);
  return os.str();
}

}  // namespace engage
