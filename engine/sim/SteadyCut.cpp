#include "engine/sim/SteadyCut.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/sim/Simulation.h"
#include "stock/VoxelStock.h"

#include <algorithm>
#include <cmath>

namespace engage {
namespace {

Move rapid(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Move m;
  m.kind = MoveKind::Rapid;
  m.start = a;
  m.end = b;
  return m;
}

Move line(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double feed) {
  Move m = rapid(a, b);
  m.kind = MoveKind::Line;
  m.feed = feed;
  return m;
}

}  // namespace

SteadyCut measureSteadyCut(const AptCutter& cutter, double stepover, double depth,
                           const PathShape& path, double feed, double voxel) {
  const double D = 2.0 * cutter.radius();
  if (!(stepover > 0.0 && depth > 0.0 && feed > 0.0 && voxel >= 0.0))
    throw ParameterError("steady cut: stepover, depth and feed must be positive");
  // The model's own check of the path (too tight an arc has no steady state).
  EngagementModel(cutter, stepover, depth).centroidSpeedRatio(path);
  if (voxel == 0.0) voxel = D / 40.0;

  // The passes run counter-clockwise about the origin (or along +x), over 6 D; the middle
  // 2 D is measured. The previous pass is one stepover away on the side away from the stock.
  const bool straight = path.side == PathSide::Straight;
  const double rho = straight ? 0.0 : path.radius;
  const double away = path.side == PathSide::Convex ? stepover : -stepover;
  const double half = 3.0 * D, measured = D;
  const double z = -depth, above = cutter.height() + 1.0;
  const double reach = cutter.maxRadius() + stepover + 2.0 * voxel;

  Toolpath tp;
  tp.files.push_back("steady cut");
  Eigen::Vector3d at(0.0, 0.0, above);
  auto pass = [&](double offset, double extra) {
    if (straight) {
      const Eigen::Vector3d a(-half - extra, offset, z), b(half + extra, offset, z);
      tp.moves.push_back(rapid(at, {a.x(), a.y(), above}));
      tp.moves.push_back(line({a.x(), a.y(), above}, a, feed));
      tp.moves.push_back(line(a, b, feed));
      at = b;
    } else {
      const double r = rho + offset;
      const double phi = std::min((half + extra) / r, 0.95 * kPi);
      const Eigen::Vector3d a(r * std::cos(-phi), r * std::sin(-phi), z);
      const Eigen::Vector3d b(r * std::cos(phi), r * std::sin(phi), z);
      tp.moves.push_back(rapid(at, {a.x(), a.y(), above}));
      tp.moves.push_back(line({a.x(), a.y(), above}, a, feed));
      Move arc = line(a, b, feed);
      arc.kind = MoveKind::Arc;
      arc.center = {0.0, 0.0, z};
      arc.turns = 1;
      tp.moves.push_back(arc);
      at = b;
    }
    tp.moves.push_back(rapid(at, {at.x(), at.y(), above}));
    at.z() = above;
  };
  pass(straight ? -away : away, D);  // the previous pass reaches past the measured one
  const std::size_t measuredMove = tp.moves.size() + 2;  // after its rapid and plunge
  pass(0.0, 0.0);

  // The stock: the region the measured pass sweeps, with the stock's side and the previous
  // pass's band, from below the tip to the top at z = 0.
  Box3 box;
  box.min = Eigen::Vector3d(1e300, 1e300, z - 2.0 * voxel);
  box.max = Eigen::Vector3d(-1e300, -1e300, 0.0);
  for (int i = 0; i <= 64; ++i) {
    const double t = -1.0 + 2.0 * i / 64.0;
    for (double dr : {-reach, reach}) {
      Eigen::Vector2d p;
      if (straight) {
        p = {t * half, dr};
      } else {
        const double phi = std::min(half / rho, 0.95 * kPi) * t;
        p = (rho + dr) * Eigen::Vector2d(std::cos(phi), std::sin(phi));
      }
      box.min.head<2>() = box.min.head<2>().cwiseMin(p);
      box.max.head<2>() = box.max.head<2>().cwiseMax(p);
    }
  }
  VoxelStock stock = VoxelStock::box(box, voxel);
  SimulationOptions so;
  const SimulationResult r = simulate(tp, cutter, stock, so);

  SteadyCut out;
  double removed = 0.0, dt = 0.0;
  for (const StepRecord& s : r.steps) {
    if (s.move != measuredMove) continue;
    const double along = straight ? s.end.x() : rho * std::atan2(s.end.y(), s.end.x());
    if (std::abs(along) > measured) continue;
    removed += s.removed;
    dt += s.dt;
    ++out.steps;
  }
  if (out.steps == 0 || dt <= 0.0) throw Error("steady cut: no step in the measured window");
  out.mrr = removed / (dt / 60.0);  // dt in s
  return out;
}

}  // namespace engage
