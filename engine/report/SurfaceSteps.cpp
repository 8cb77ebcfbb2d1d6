#include "engine/report/SurfaceSteps.h"

#include "cutters/Sweep.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>

namespace engage {
namespace {

/// The points sorted into square columns of side `cell` over their XY bounds, each column's
/// points by height, for box queries. (Not cubic bins: a step's box is as tall as the cutter,
/// and most cubic bins it meets are empty.)
class PointBins {
 public:
  PointBins(const std::vector<std::array<float, 3>>& points, double cell) : cell_(cell) {
    if (points.empty()) return;
    double x0 = points[0][0], y0 = points[0][1], x1 = x0, y1 = y0;
    for (const auto& p : points) {
      x0 = std::min<double>(x0, p[0]);
      x1 = std::max<double>(x1, p[0]);
      y0 = std::min<double>(y0, p[1]);
      y1 = std::max<double>(y1, p[1]);
    }
    x0_ = x0;
    y0_ = y0;
    nx_ = static_cast<int>(std::floor((x1 - x0) / cell_)) + 1;
    ny_ = static_cast<int>(std::floor((y1 - y0) / cell_)) + 1;
    std::vector<std::uint32_t> column(points.size());
    start_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) + 1, 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
      column[i] = static_cast<std::uint32_t>(
          index(bin(points[i][0], x0_, nx_), bin(points[i][1], y0_, ny_)));
      ++start_[column[i] + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c)
      start_[c] += start_[c - 1];
    order_.resize(points.size());
    std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < points.size(); ++i)
      order_[next[column[i]]++] = static_cast<std::uint32_t>(i);
    z_.resize(points.size());
    for (std::size_t c = 0; c + 1 < start_.size(); ++c) {
      const auto first = order_.begin() + start_[c], last = order_.begin() + start_[c + 1];
      std::sort(first, last, [&](std::uint32_t a, std::uint32_t b) {
        return std::make_pair(points[a][2], a) < std::make_pair(points[b][2], b);
      });
    }
    for (std::size_t k = 0; k < order_.size(); ++k)
      z_[k] = points[order_[k]][2];
  }

  /// Calls fn(index) for every point in the columns that overlap the box, at its heights.
  template <typename Fn>
  void inBox(const Box3& b, Fn&& fn) const {
    if (order_.empty()) return;
    const int xa = std::max(0, bin(b.min.x(), x0_, nx_)),
              xb = std::min(nx_ - 1, bin(b.max.x(), x0_, nx_));
    const int ya = std::max(0, bin(b.min.y(), y0_, ny_)),
              yb = std::min(ny_ - 1, bin(b.max.y(), y0_, ny_));
    if (b.max.x() < x0_ || b.max.y() < y0_) return;
    for (int y = ya; y <= yb; ++y)
      for (int x = xa; x <= xb; ++x) {
        const std::size_t c = index(x, y);
        const auto first = z_.begin() + start_[c], last = z_.begin() + start_[c + 1];
        for (auto it = std::lower_bound(first, last, static_cast<float>(b.min.z()));
             it != last && *it <= b.max.z(); ++it)
          fn(order_[static_cast<std::size_t>(it - z_.begin())]);
      }
  }

 private:
  /// The column of coordinate v (clamped to [-1, n]: outside the points' bounds).
  int bin(double v, double origin, int n) const {
    const double k = std::floor((v - origin) / cell_);
    return static_cast<int>(std::clamp(k, -1.0, static_cast<double>(n)));
  }
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(x);
  }

  double cell_;
  double x0_ = 0.0, y0_ = 0.0;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> start_;  // column c's points: order_[start_[c] .. start_[c + 1])
  std::vector<std::uint32_t> order_;  // point indices, column by column, each by height
  std::vector<float> z_;              // their heights
};

}  // namespace

std::vector<int> lastCuttingSteps(const std::vector<std::array<float, 3>>& points,
                                  const Toolpath& path, const std::vector<StepRecord>& steps,
                                  const CutterSet& cutters, double resolution, double tolerance,
                                  double minRemoved, bool orInside) {
  std::vector<std::atomic<int>> best(points.size());
  for (auto& b : best)
    b.store(-1, std::memory_order_relaxed);
  // Bins about four tolerances wide (at least a millimetre): a step's box meets few of them.
  const PointBins bins(points, std::max(4.0 * tolerance, 1.0));
  // The steps in blocks, the last block first (each block's steps in parallel): a point that
  // a later step already cut is not measured again (in step order every step would measure
  // every point in its box).
  constexpr std::size_t kBlock = 4096;
  for (std::size_t end = steps.size(); end > 0;) {
    const std::size_t begin = end > kBlock ? end - kBlock : 0;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(begin, end, 64),
        [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const StepRecord& s = steps[i];
            if (!(s.removed > minRemoved)) continue;
            const Move& m = path.moves[s.move];
            const Sweep sweep(cutters.of(m.tool), stepPath(m, s.t0, s.t1, path), resolution);
            Box3 box = sweep.bounds();
            box.min -= Eigen::Vector3d::Constant(tolerance);
            box.max += Eigen::Vector3d::Constant(tolerance);
            const int step = static_cast<int>(i);
            bins.inBox(box, [&](std::uint32_t k) {
              if (best[k].load(std::memory_order_relaxed) > step) return;  // cut later
              const auto& q = points[k];
              const Eigen::Vector3d p(q[0], q[1], q[2]);
              if ((p.array() < box.min.array()).any() || (p.array() > box.max.array()).any())
                return;
              const double d = sweep.signedDistance(p);
              if (d > tolerance || (!orInside && d < -tolerance)) return;
              int seen = best[k].load(std::memory_order_relaxed);
              while (seen < step && !best[k].compare_exchange_weak(seen, step)) {
              }
            });
          }
        });
    end = begin;
  }
  std::vector<int> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    out[i] = best[i].load();
  return out;
}

}  // namespace engage
