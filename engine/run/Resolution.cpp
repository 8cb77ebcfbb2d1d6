#include "engine/run/Resolution.h"

#include "cutters/Numbers.h"
#include "engine/sim/ToolPoses.h"
#include "stock/DexelStock.h"
#include "stock/VoxelStock.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace engage {

namespace {

/// The lowest tip height over a move, mm (lines and helices at an end; splines at a point).
double lowestZ(const Move& m) {
  double z = std::min(m.start.z(), m.end.z());
  for (const Eigen::Vector3d& p : m.points)
    z = std::min(z, p.z());
  return z;
}

/// The same for the tip on the part where the move's words are not its terms (the joints of
/// a rotary machine, a tilted work plane's coordinates): through the kinematics, at the ends
/// of the pieces stepPath cuts it into.
double lowestTipZ(const Move& m, const Toolpath& path) {
  if (!path.kinematics.rotary() && path.frames.empty()) return lowestZ(m);
  const StepPath sp = stepPath(m, 0.0, 1.0, path);
  double z = std::min(sp.start.z(), sp.end.z());
  for (const Eigen::Vector3d& p : sp.points)
    z = std::min(z, p.z());
  return z;
}

/// The median of (value, weight) pairs, weighted.
double weightedMedian(std::vector<std::pair<double, double>> v) {
  std::sort(v.begin(), v.end());
  double total = 0.0;
  for (const auto& [value, weight] : v)
    total += weight;
  double sum = 0.0;
  for (const auto& [value, weight] : v)
    if ((sum += weight) >= 0.5 * total) return value;
  return v.back().first;
}

}  // namespace

ProgramEngagement programEngagement(const Toolpath& path, const CutterSet& cutters,
                                    std::optional<double> stockTop) {
  std::map<int, std::vector<std::pair<double, double>>> depths;  // tool -> (depth, length)
  if (stockTop)
    for (const Move& m : path.moves) {
      if (m.kind == MoveKind::Rapid) continue;
      const double depth = *stockTop - lowestTipZ(m, path);
      const double len = moveLength(m);
      if (depth > 0.0 && len > 0.0) depths[m.tool].emplace_back(depth, len);
    }
  ProgramEngagement best;
  for (const auto& [tool, list] : depths) {
    const AptCutter& c = cutters.of(tool);
    ProgramEngagement e;
    e.tool = cutters.byTool.count(tool) ? tool : -1;
    e.nominal = 2.0 * c.radius();
    e.depth = weightedMedian(list);
    e.engaged = 2.0 * c.maxRadiusBelow(e.depth);
    e.known = true;
    if (!best.known || e.engaged < best.engaged) best = e;
  }
  if (best.known) return best;
  // No cut below the top: the smallest cutter, nominal.
  best.nominal = 2.0 * cutters.smallestRadius();
  best.tool = -1;
  for (const auto& [tool, c] : cutters.byTool)
    if (2.0 * c.radius() == best.nominal) {
      best.tool = tool;
      break;
    }
  best.engaged = best.nominal;
  return best;
}

std::vector<Box3> programReach(const Toolpath& path, const CutterSet& cutters, const Box3& stock) {
  // (Rotary kinematics carry the tool anywhere about the part, and a tilted work plane's moves
  // are not in the part's frame: all of it.)
  if (path.kinematics.rotary() || !path.frames.empty()) return {stock};
  std::vector<Box3> reach;
  const double top = stock.max.z();
  for (const Move& m : path.moves) {
    const AptCutter& c = cutters.of(m.tool);
    const double length = moveLength(m);
    const double lowest = lowestZ(m);
    if (lowest >= top) continue;  // nothing of the tool below the top
    // Pieces no longer than the tool is wide (nor shorter than a tenth of its diameter):
    // their boxes stay close to the swept band.
    const double pieceLength = std::max(2.0 * c.maxRadiusBelow(top - lowest), 0.2 * c.radius());
    int n = static_cast<int>(std::ceil(length / pieceLength));
    if (m.kind == MoveKind::Arc)
      n = std::max(n, static_cast<int>(std::ceil(std::abs(arcSweep(m)) / (10.0 * kPi / 180.0))));
    n = std::clamp(n, 1, 1 << 20);
    // How far a piece's path may leave the box of its ends, per axis: an arc's sagitta in its
    // plane; a spline's half piece.
    Eigen::Vector3d bulge = Eigen::Vector3d::Zero();
    if (m.kind == MoveKind::Arc) {
      const double sagitta = arcRadius(m) * (1.0 - std::cos(0.5 * std::abs(arcSweep(m)) / n));
      const PlaneAxes axes = planeAxes(m.plane);
      bulge[axes.a] = bulge[axes.b] = sagitta;
    } else if (m.kind == MoveKind::Spline) {
      bulge.setConstant(0.5 * length / n);
    }
    Eigen::Vector3d a = m.start;
    for (int k = 1; k <= n; ++k) {
      const Eigen::Vector3d b = k == n ? m.end : pointAt(m, static_cast<double>(k) / n);
      const double zLow = std::min(a.z(), b.z()) - bulge.z();
      if (zLow < top) {
        const double r = c.maxRadiusBelow(top - zLow);
        const Eigen::Vector3d widen = bulge + Eigen::Vector3d(r, r, 0.0);
        Box3 piece;
        piece.min = (a.cwiseMin(b) - widen).cwiseMax(stock.min);
        piece.max =
            (a.cwiseMax(b) + widen + Eigen::Vector3d(0.0, 0.0, c.height())).cwiseMin(stock.max);
        if ((piece.min.array() <= piece.max.array()).all()) reach.push_back(piece);
      }
      a = b;
    }
  }
  return reach;
}

CellChoice defaultCell(const Toolpath& path, const CutterSet& cutters,
                       const std::optional<Box3>& box, StockModels models, double fixedStep,
                       bool boxStock) {
  CellChoice choice;
  choice.engagement =
      programEngagement(path, cutters, box ? std::optional<double>(box->max.z()) : std::nullopt);
  const ProgramEngagement& e = choice.engagement;
  const double nominal = e.nominal / 20.0;
  const double fine = std::min(nominal, e.engaged / 20.0);
  choice.limit = e.known && fine < nominal ? CellLimit::Engaged : CellLimit::Nominal;
  choice.cell = choice.limit == CellLimit::Engaged ? fine : nominal;
  if (choice.limit == CellLimit::Nominal) return choice;
  // Coarser only as far as the budgets need: each bound shrinks as the cell grows.
  const std::vector<Box3> reach =
      box && models.voxel && boxStock ? programReach(path, cutters, *box) : std::vector<Box3>{};
  auto memory = [&](double h) {
    if (!box) return 0.0;
    const double dexel = models.dexel ? DexelStock::memoryBound(*box, h) : 0.0;
    const double left = kStockBudgetBytes - dexel;
    return dexel + (models.voxel && left >= 0.0
                        ? VoxelStock::memoryBound(*box, h, boxStock ? &reach : nullptr, left)
                        : 0.0);
  };
  auto steps = [&](double h) { return fixedStep > 0.0 ? 0.0 : stepCount(path, 2.5 * h); };
  auto fits = [&](double h) { return memory(h) <= kStockBudgetBytes && steps(h) <= kStepBudget; };
  if (fits(fine)) return choice;
  double lo = fine, hi = nominal;  // lo does not fit; the cell is the smallest that does
  if (!fits(hi)) {
    choice.cell = nominal;
    choice.limit = memory(fine) > kStockBudgetBytes ? CellLimit::Memory : CellLimit::Steps;
    return choice;
  }
  // Halving the logarithm of their ratio: 24 halvings leave the cell within 1e-6 (relative)
  // of the smallest that fits for ratios up to 1e6.
  for (int i = 0; i < 24; ++i) {
    const double mid = std::sqrt(lo * hi);
    (fits(mid) ? hi : lo) = mid;
  }
  choice.cell = hi;
  choice.limit = memory(lo) > kStockBudgetBytes ? CellLimit::Memory : CellLimit::Steps;
  return choice;
}

std::string describeCell(const CellChoice& choice, UnitSystem units) {
  auto length = [&](double v) { return formatQuantity(v, Dimension::Length, units); };
  const ProgramEngagement& e = choice.engagement;
  const std::string tool = e.tool < 0 ? "the tool" : "tool " + std::to_string(e.tool);
  const std::string engaged = "the " + length(e.engaged) + " " + tool + " engages at " +
                              length(e.depth) + " deep (nominal " + length(e.nominal) + ")";
  switch (choice.limit) {
    case CellLimit::Engaged:
      return length(choice.cell) + ": a twentieth of " + engaged;
    case CellLimit::Memory:
    case CellLimit::Steps: {
      const bool memory = choice.limit == CellLimit::Memory;
      // Even the nominal D/20 may be beyond the budget: then it stays.
      const std::string finest =
          choice.cell >= e.nominal / 20.0
              ? std::string("a twentieth of the nominal diameter (no finer cell keeps ") +
                    (memory ? "the stock within 2 GB)" : "the run within 1000000 steps)")
              : std::string("the finest ") +
                    (memory ? "whose stock fits 2 GB" : "that keeps the run within 1000000 steps");
      return length(choice.cell) + ": " + finest + "; a twentieth of " + engaged + " would be " +
             length(e.engaged / 20.0);
    }
    case CellLimit::Nominal:
      break;
  }
  if (e.known)
    return length(choice.cell) + ": a twentieth of the " + length(e.nominal) + " diameter of " +
           tool + " (it engages all of it at the program's depths)";
  return length(choice.cell) + ": a twentieth of the " + length(e.nominal) + " diameter of " +
         tool + " (no cut below the stock's top known before the run)";
}

}  // namespace engage
