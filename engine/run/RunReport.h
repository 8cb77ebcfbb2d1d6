#pragma once
/// \file RunReport.h
/// report.html of a run: one self-contained page (engine/report/HtmlPage.h) with the run's
/// summary (the figures of summary.json, which it carries whole), its warnings and
/// collisions, plots along the path (measured and analytic MRR, programmed and scheduled feed,
/// acceleration, chip, force, power) with the step, line and values under the pointer, and a
/// 3D view of the final stock coloured by what last cut each place (MRR, force, tool or step).
/// Clicking a plot shows the step in 3D with its line of G-code; clicking the stock shows the
/// step that cut there.
///
/// Size: every step is plotted up to kAllSteps steps; above that the steps are cut into
/// kBuckets runs of consecutive steps and each run keeps its extremes (lowest and highest
/// measured and analytic MRR,
/// highest scheduled MRR, force and acceleration, lowest scheduled feed) besides every peak
/// summary.json names, so no peak is lost. The 3D view is the stock's surface from at most
/// kMaxTriangles triangles (StockView::surface).

#include "engine/run/Pipeline.h"
#include "engine/run/Summary.h"
#include "stock/TriangleMesh.h"

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

namespace engage {

class VoxelStock;

/// Limits of the report's size (see the header comment).
inline constexpr std::size_t kAllSteps = 20000;
inline constexpr std::size_t kBuckets = 4000;
inline constexpr std::size_t kMaxTriangles = 150000;

/// The report's 3D view of the final stock, its heaviest part (the surface meshed, and the
/// step that last cut at each vertex), made apart so that it can be made while the stock files
/// are written.
struct ReportSurface {
  std::string json;                ///< the page's "surface" object, JSON text
  std::vector<std::size_t> steps;  ///< the steps its vertices name (their table), in order
};
/// `mesh`: the final stock's surface (StockView::surface, kMaxTriangles), `cell` its
/// vertices' spacing (mm).
ReportSurface reportSurface(const RunResult& result, const TriangleMesh& mesh, double cell);

/// Write the page to `os`. `summaryJson` is summary.json's text; `steps` the steps its plots
/// show (reportSteps); `written` the files written (named on the page); `surface`, when given,
/// the 3D view.
void writeRunReportHtml(std::ostream& os, const RunResult& result, const std::string& summaryJson,
                        const std::vector<std::size_t>& steps, const WrittenOutputs& written,
                        const ReportSurface* surface);
/// The same page as a string, its 3D view of `surface` (the final stock as voxels) when given.
std::string runReportHtml(const RunResult& result, const std::string& summaryJson,
                          const std::vector<std::size_t>& steps, const WrittenOutputs& written,
                          const VoxelStock* surface);

/// The steps the plots keep (all up to `allUpTo`, else the extremes of each of `buckets`
/// equal runs of steps and the peaks that `summaryJson`, summary.json's text, names), in order.
std::vector<std::size_t> reportSteps(const RunResult& result, const std::string& summaryJson,
                                     std::size_t buckets = kBuckets,
                                     std::size_t allUpTo = kAllSteps);

}  // namespace engage
