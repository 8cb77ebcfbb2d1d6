#include "engine/report/SurfaceSteps.h"

#include "cutters/Sweep.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace engage {
namespace {

/// The points sorted into cubic bins of side `cell`, for box queries.
class PointBins {
 public:
  PointBins(const std::vector<std::array<float, 3>>& points, double cell)
      : cell_(cell), order_(points.size()) {
    std::vector<std::int64_t> keys(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      keys[i] = key(bin(points[i][0]), bin(points[i][1]), bin(points[i][2]));
      order_[i] = static_cast<std::uint32_t>(i);
    }
    std::stable_sort(order_.begin(), order_.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
    for (std::size_t i = 0; i < order_.size();) {
      std::size_t j = i;
      while (j < order_.size() && keys[order_[j]] == keys[order_[i]])
        ++j;
      ranges_[keys[order_[i]]] = {static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)};
      i = j;
    }
  }

  /// Calls fn(index) for every point in the bins that overlap the box.
  template <typename Fn>
  void inBox(const Box3& b, Fn&& fn) const {
    const int x0 = bin(b.min.x()), x1 = bin(b.max.x());
    const int y0 = bin(b.min.y()), y1 = bin(b.max.y());
    const int z0 = bin(b.min.z()), z1 = bin(b.max.z());
    for (int x = x0; x <= x1; ++x)
      for (int y = y0; y <= y1; ++y)
        for (int z = z0; z <= z1; ++z) {
          const auto it = ranges_.find(key(x, y, z));
          if (it == ranges_.end()) continue;
          for (std::uint32_t k = it->second.first; k < it->second.second; ++k)
            fn(order_[k]);
        }
  }

 private:
  int bin(double v) const { return static_cast<int>(std::floor(v / cell_)); }
  static std::int64_t key(int x, int y, int z) {
    // 21 bits a coordinate: bins of a millimetre or more over +-1 km.
    auto u = [](int v) { return static_cast<std::int64_t>(v + (1 << 20)) & ((1 << 21) - 1); };
    return (u(x) << 42) | (u(y) << 21) | u(z);
  }

  double cell_;
  std::vector<std::uint32_t> order_;
  std::unordered_map<std::int64_t, std::pair<std::uint32_t, std::uint32_t>> ranges_;
};

}  // namespace

std::vector<int> lastCuttingSteps(const std::vector<std::array<float, 3>>& points,
                                  const Toolpath& path, const std::vector<StepRecord>& steps,
                                  const CutterSet& cutters, double resolution, double tolerance,
                                  double minRemoved) {
  std::vector<std::atomic<int>> best(points.size());
  for (auto& b : best)
    b.store(-1, std::memory_order_relaxed);
  // Bins about four tolerances wide (at least a millimetre): a step's box meets few of them.
  const PointBins bins(points, std::max(4.0 * tolerance, 1.0));
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, steps.size(), 64),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const StepRecord& s = steps[i];
          if (!(s.removed > minRemoved)) continue;
          const Move& m = path.moves[s.move];
          const Sweep sweep(cutters.of(m.tool), stepPath(m, s.t0, s.t1), resolution);
          Box3 box = sweep.bounds();
          box.min -= Eigen::Vector3d::Constant(tolerance);
          box.max += Eigen::Vector3d::Constant(tolerance);
          const int step = static_cast<int>(i);
          bins.inBox(box, [&](std::uint32_t k) {
            const auto& q = points[k];
            const Eigen::Vector3d p(q[0], q[1], q[2]);
            if ((p.array() < box.min.array()).any() || (p.array() > box.max.array()).any()) return;
            if (std::abs(sweep.signedDistance(p)) > tolerance) return;
            int seen = best[k].load(std::memory_order_relaxed);
            while (seen < step && !best[k].compare_exchange_weak(seen, step)) {
            }
          });
        }
      });
  std::vector<int> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    out[i] = best[i].load();
  return out;
}

}  // namespace engage
