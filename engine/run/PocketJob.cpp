#include "engine/run/PocketJob.h"

#include "cutters/Error.h"
#include "engine/cam/Pocket.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/run/Output.h"
#include "engine/units/Quantity.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace engage {

PocketProgram makePocketProgram(const PocketJobOptions& c) {
  const Toolpath boundary = readProgram(c.boundary);
  const UnitSystem sys =
      unitSystemNamed(c.units).value_or(boundary.inch ? UnitSystem::Inch : UnitSystem::Metric);
  auto length = [&](const std::string& text, const char* name) {
    return parseQuantity(text, Dimension::Length, sys, name).value;
  };
  PocketOptions o;
  o.toolRadius = 0.5 * length(c.diameter, "--diameter");
  o.stepover = length(c.stepover, "--stepover");
  o.depth = length(c.depth, "--depth");
  if (!c.stepDown.empty()) o.stepDown = length(c.stepDown, "--step-down");
  o.top = length(c.top, "--top");
  o.safeZ = c.safeZ.empty() ? o.top + (sys == UnitSystem::Inch ? 0.2 * 25.4 : 5.0)
                            : length(c.safeZ, "--safe-z");
  o.feed = parseQuantity(c.feed, Dimension::Feed, sys, "--feed").value;
  o.plungeFeed = c.plungeFeed.empty()
                     ? 0.5 * o.feed
                     : parseQuantity(c.plungeFeed, Dimension::Feed, sys, "--plunge-feed").value;
  if (!c.tolerance.empty()) o.tolerance = length(c.tolerance, "--tolerance");
  o.climb = !c.conventional;
  o.inch = sys == UnitSystem::Inch;
  const std::vector<Loop> loops = boundaryLoops(boundary);
  const std::vector<Ring> rings = pocketRings(loops, o);
  PocketProgram p;
  for (const Ring& r : rings) {
    p.levels = std::max(p.levels, r.level + 1);
    for (const Element& e : r.elements)
      (e.arc ? p.arcs : p.lines) += 1;
    // Sharp corners of neighbouring rings more than r sqrt 2 apart leave material between.
    for (std::size_t i = 0; i < r.elements.size(); ++i) {
      const Element& a = r.elements[i];
      const Element& b = r.elements[(i + 1) % r.elements.size()];
      if (a.arc || b.arc) continue;
      const Eigen::Vector2d u = (a.end - a.start).normalized(), v = (b.end - b.start).normalized();
      if (u.dot(v) < 0.99) p.sharpCorners = true;
    }
  }
  p.rings = rings.size();
  p.cornerWarning = p.sharpCorners && o.stepover > std::sqrt(2.0) * o.toolRadius;
  p.text = writePocketProgram(
      rings, o,
      {"engage pocket " + std::filesystem::path(c.boundary).filename().string() +
           ": contour-parallel, inside out",
       "tool diameter " + formatQuantity(2.0 * o.toolRadius, Dimension::Length, sys) +
           ", stepover " + formatQuantity(o.stepover, Dimension::Length, sys) + ", depth " +
           formatQuantity(o.depth, Dimension::Length, sys) + " from Z " +
           formatQuantity(o.top, Dimension::Length, sys) + ", feed " +
           formatQuantity(o.feed, Dimension::Feed, sys) + ", " +
           (o.climb ? "climb" : "conventional")},
      &p.ringLines);
  return p;
}

std::string writePocketJob(const PocketJobOptions& c) {
  // Everything is made before the file is written.
  const PocketProgram p = makePocketProgram(c);
  const std::filesystem::path parent = std::filesystem::path(c.output).parent_path();
  std::optional<OutputDirectory> folder;
  if (!parent.empty()) folder.emplace(parent);
  writeAtomically(c.output, p.text);
  if (folder) folder->keep();
  char line[512];
  std::snprintf(line, sizeof line, "%zu rings on %d level(s): %zu arcs, %zu lines; wrote %s\n",
                p.rings, p.levels, p.arcs, p.lines, c.output.c_str());
  std::string report = line;
  if (p.cornerWarning)
    report +=
        "warning: stepover above r sqrt 2: the rings' sharp corners leave material between "
        "them\n";
  return report;
}

}  // namespace engage
