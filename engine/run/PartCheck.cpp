#include "engine/run/PartCheck.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/report/SurfaceSteps.h"
#include "engine/run/Output.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace engage {
namespace {

/// Union-find over sample indices.
class Components {
 public:
  explicit Components(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), std::size_t{0});
  }
  std::size_t find(std::size_t i) {
    while (parent_[i] != i)
      i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void join(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);  // the first sample is the root
  }

 private:
  std::vector<std::size_t> parent_;
};

/// Samples sorted into cubes of side `cube` (a sorted list of keys: millions of samples
/// without a hash map's nodes), for the samples near a point.
class SampleGrid {
 public:
  SampleGrid(const std::vector<PartSample>& samples, const std::vector<char>* only, double cube)
      : cube_(cube) {
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (!only || (*only)[i])
        sorted_.emplace_back(key(cell(samples[i].point)), static_cast<std::uint32_t>(i));
    std::sort(sorted_.begin(), sorted_.end());
  }
  /// Calls fn(j) for every sample in the 27 cubes about p.
  template <typename Fn>
  void near(const Eigen::Vector3f& p, Fn&& fn) const {
    const std::array<int, 3> c = cell(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const std::uint64_t k = key({c[0] + dx, c[1] + dy, c[2] + dz});
          auto it = std::lower_bound(sorted_.begin(), sorted_.end(), std::make_pair(k, 0u));
          for (; it != sorted_.end() && it->first == k; ++it)
            fn(static_cast<std::size_t>(it->second));
        }
  }

 private:
  std::array<int, 3> cell(const Eigen::Vector3f& p) const {
    return {static_cast<int>(std::floor(p.x() / cube_)),
            static_cast<int>(std::floor(p.y() / cube_)),
            static_cast<int>(std::floor(p.z() / cube_))};
  }
  static std::uint64_t key(const std::array<int, 3>& c) {
    auto part = [](int v) { return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1FFFFFu; };
    return part(c[0]) | part(c[1]) << 21 | part(c[2]) << 42;
  }
  double cube_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> sorted_;
};

/// The flagged samples joined where they lie within `reach` of each other; returns per sample
/// its component's root (or -1 when not flagged).
std::vector<long> joinNeighbours(const std::vector<PartSample>& samples,
                                 const std::vector<char>& flagged, double reach) {
  const SampleGrid grid(samples, &flagged, reach);
  Components c(samples.size());
  const float reach2 = static_cast<float>(reach * reach);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!flagged[i]) continue;
    grid.near(samples[i].point, [&](std::size_t j) {
      if (j < i && (samples[j].point - samples[i].point).squaredNorm() <= reach2) c.join(i, j);
    });
  }
  std::vector<long> root(samples.size(), -1);
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (flagged[i]) root[i] = static_cast<long>(c.find(i));
  return root;
}

/// The samples beside a region's edge split again, four times finer, and measured: a region's
/// area (and so its volume) is then counted to a quarter of a sample along its outline. A
/// sample is beside an edge where a neighbour within `reach` is of another kind (gouge,
/// leftover, neither). Skipped where the finer samples would pass half of kMaxPartSamples.
void refineEdges(const Part& part, const Stock& stock, const Box3* holds, const PartSpec& spec,
                 double spacing, double reach, std::vector<PartSample>& samples,
                 std::vector<SampleDeviation>& dev) {
  auto kind = [&](std::size_t i) {
    return dev[i].deviation < -spec.tolerance ? -1 : dev[i].deviation > spec.allowance ? 1 : 0;
  };
  const SampleGrid grid(samples, nullptr, reach);
  const float reach2 = static_cast<float>(reach * reach);
  // From the flagged samples (few, mostly): each with a neighbour of another kind marks both.
  std::vector<char> edge(samples.size(), 0);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const int k = kind(i);
    if (k == 0) continue;
    grid.near(samples[i].point, [&](std::size_t j) {
      if (kind(j) != k && (samples[j].point - samples[i].point).squaredNorm() <= reach2)
        edge[i] = edge[j] = 1;
    });
  }
  std::vector<PartSample> finer;
  std::vector<PartSample> kept;
  std::vector<SampleDeviation> keptDev;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (edge[i]) {
      for (PartSample& p : splitSample(samples[i], 0.25 * spacing))
        finer.push_back(std::move(p));
      if (finer.size() > kMaxPartSamples / 2) return;
    } else {
      kept.push_back(samples[i]);
      keptDev.push_back(dev[i]);
    }
  }
  const std::vector<SampleDeviation> finerDev =
      measureDeviation(part, finer, stock, holds, stopRequested);
  kept.insert(kept.end(), finer.begin(), finer.end());
  keptDev.insert(keptDev.end(), finerDev.begin(), finerDev.end());
  samples = std::move(kept);
  dev = std::move(keptDev);
}

/// The regions of one kind (gouges: deviation < -tolerance; leftovers: > allowance).
std::vector<DeviationRegion> regionsOf(const std::vector<PartSample>& samples,
                                       const std::vector<SampleDeviation>& dev, bool gouge,
                                       double limit, double reach, double smallest,
                                       std::vector<long>* regionOfSample = nullptr) {
  std::vector<char> flagged(samples.size(), 0);
  for (std::size_t i = 0; i < samples.size(); ++i)
    flagged[i] = gouge ? dev[i].deviation < -limit : dev[i].deviation > limit;
  const std::vector<long> root = joinNeighbours(samples, flagged, reach);
  std::map<long, DeviationRegion> byRoot;  // ordered by the first sample: deterministic
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (root[i] < 0) continue;
    DeviationRegion& r = byRoot[root[i]];
    const Eigen::Vector3d p = samples[i].point.cast<double>();
    const double size = std::abs(static_cast<double>(dev[i].deviation));
    if (r.area == 0.0) {
      r.gouge = gouge;
      r.box.min = r.box.max = p;
    }
    r.box.min = r.box.min.cwiseMin(p);
    r.box.max = r.box.max.cwiseMax(p);
    r.area += samples[i].area;
    r.volume += samples[i].area * size;
    if (size > r.extreme) {
      r.extreme = size;
      r.at = p;
    }
  }
  std::vector<std::pair<long, DeviationRegion>> ordered;
  for (auto& entry : byRoot)
    if (entry.second.area >= smallest) ordered.push_back(std::move(entry));
  std::stable_sort(ordered.begin(), ordered.end(),
                   [](const auto& a, const auto& b) { return a.second.volume > b.second.volume; });
  std::unordered_map<long, long> index;
  std::vector<DeviationRegion> out;
  for (auto& [r, region] : ordered) {
    index[r] = static_cast<long>(out.size());
    out.push_back(std::move(region));
  }
  if (regionOfSample) {
    regionOfSample->assign(samples.size(), -1);
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (root[i] >= 0 && index.count(root[i])) (*regionOfSample)[i] = index[root[i]];
  }
  return out;
}

}  // namespace

double PartCheck::deepestGouge() const {
  double d = 0.0;
  for (const DeviationRegion& r : gouges)
    d = std::max(d, r.extreme);
  return d;
}

double PartCheck::thickestLeftover() const {
  double d = 0.0;
  for (const DeviationRegion& r : leftovers)
    d = std::max(d, r.extreme);
  return d;
}

PartCheck checkPart(const Part& part, const PartSpec& spec, const Stock& stock,
                    const Toolpath& path, const std::vector<StepRecord>& steps,
                    const CutterSet& cutters, const Box3* holds) {
  const auto start = std::chrono::steady_clock::now();
  PartCheck c;
  c.spec = spec;
  c.area = part.area();
  c.partVolume = part.volume();
  const double h = stock.resolution();
  // Pieces whose longest edge is a cell's diagonal: right triangles with legs of a cell at most.
  c.spacing = std::sqrt(2.0) * h;
  for (std::size_t n = part.sampleCount(c.spacing); n > kMaxPartSamples;
       n = part.sampleCount(c.spacing))
    c.spacing *= 1.05 * std::sqrt(static_cast<double>(n) / static_cast<double>(kMaxPartSamples));
  std::vector<PartSample> samples = part.samples(c.spacing);
  if (stopRequested()) throw Interrupted();
  std::vector<SampleDeviation> dev = measureDeviation(part, samples, stock, holds, stopRequested);
  if (stopRequested()) throw Interrupted();
  // Pieces of the surface whose centres lie within one and a half samples are neighbours
  // (pieces sharing an edge lie within one).
  const double reach = 1.5 * c.spacing;
  refineEdges(part, stock, holds, spec, c.spacing, reach, samples, dev);
  if (stopRequested()) throw Interrupted();
  c.samples = samples.size();
  for (const SampleDeviation& d : dev)
    if (d.surfaceMet) {
      c.stockPoints.push_back(d.stockPoint);
      c.deviation.push_back(d.deviation);
    }
  std::vector<long> gougeOf;  // per sample, its gouge (-1: none)
  // A region smaller than a cell's face is below what the stock resolves (a voxel stock's
  // reading at a convex edge can be a few hundredths of a cell off over such a patch).
  c.gouges = regionsOf(samples, dev, true, spec.tolerance, reach, h * h, &gougeOf);
  c.leftovers = regionsOf(samples, dev, false, spec.allowance, reach, h * h);
  // Which steps cut each gouge. Where the stock's surface was met, its floor: the steps whose
  // swept surface passes within a quarter of the tolerance of it (at most a quarter of a cell:
  // the stock's surface is read to a fraction of one; a neighbouring pass at the right depth
  // lies a tolerance away). A gouge with no such point (cut through to the part's medial
  // axis), or none found there: the steps whose swept solid holds its samples' middle depth.
  std::vector<std::map<std::size_t, double>> areaByStep(c.gouges.size());
  const double minRemoved = 0.01 * h * h * h;
  auto attribute = [&](bool floors) {
    std::vector<std::array<float, 3>> points;
    std::vector<std::size_t> which;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (gougeOf[i] < 0) continue;
      const auto g = static_cast<std::size_t>(gougeOf[i]);
      if (floors ? !dev[i].surfaceMet : !areaByStep[g].empty()) continue;
      const Eigen::Vector3f p =
          floors ? dev[i].stockPoint
                 : Eigen::Vector3f(samples[i].point + 0.5f * dev[i].deviation * samples[i].normal);
      points.push_back({p.x(), p.y(), p.z()});
      which.push_back(i);
    }
    if (points.empty()) return;
    const double within = std::clamp(0.25 * spec.tolerance, 1e-3 * h, 0.25 * h);
    const std::vector<int> last =
        lastCuttingSteps(points, path, steps, cutters, h, within, minRemoved, !floors);
    for (std::size_t k = 0; k < points.size(); ++k)
      if (last[k] >= 0)
        areaByStep[static_cast<std::size_t>(gougeOf[which[k]])]
                  [static_cast<std::size_t>(last[k])] += samples[which[k]].area;
  };
  attribute(true);
  attribute(false);
  std::vector<DeviationRegion> gouges;
  for (std::size_t g = 0; g < c.gouges.size(); ++g) {
    auto& s = c.gouges[g].steps;
    s.assign(areaByStep[g].begin(), areaByStep[g].end());
    std::stable_sort(s.begin(), s.end(),
                     [](const auto& a, const auto& b) { return a.second > b.second; });
    (s.empty() ? c.missing : gouges).push_back(std::move(c.gouges[g]));
  }
  c.gouges = std::move(gouges);
  c.done = true;
  c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return c;
}

std::vector<GougeLine> gougeLines(const DeviationRegion& gouge, const Toolpath& path,
                                  const std::vector<StepRecord>& steps) {
  std::vector<GougeLine> lines;
  std::map<std::pair<int, int>, std::size_t> index;
  for (const auto& [s, area] : gouge.steps) {
    const StepRecord& rec = steps[s];
    const std::pair<int, int> key(path.moves[rec.move].file, rec.line);
    const auto [it, added] = index.emplace(key, lines.size());
    if (added) lines.push_back({key.first, key.second, 0.0, {}});
    lines[it->second].area += area;
    lines[it->second].steps.push_back(s);
  }
  for (GougeLine& l : lines)
    std::sort(l.steps.begin(), l.steps.end());
  std::stable_sort(lines.begin(), lines.end(),
                   [](const GougeLine& a, const GougeLine& b) { return a.area > b.area; });
  return lines;
}

std::string regionTable(const PartCheck& check, bool gouges, const Toolpath& path,
                        const std::vector<StepRecord>& steps, UnitSystem units) {
  const std::string len(unitTag(Dimension::Length, units)), area(unitTag(Dimension::Area, units)),
      vol(unitTag(Dimension::Volume, units));
  auto L = [&](double v) { return formatNumber(toDisplay(v, Dimension::Length, units)); };
  std::string t = "region," + std::string(gouges ? "depth_" : "thickness_") + len + ",area_" +
                  area + ",volume_" + vol + ",x_" + len + ",y_" + len + ",z_" + len + ",x_min_" +
                  len + ",y_min_" + len + ",z_min_" + len + ",x_max_" + len + ",y_max_" + len +
                  ",z_max_" + len;
  t += gouges ? ",lines,steps\n" : "\n";
  const auto& regions = gouges ? check.gouges : check.leftovers;
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const DeviationRegion& r = regions[k];
    t += std::to_string(k + 1) + ',' + L(r.extreme) + ',' +
         formatNumber(toDisplay(r.area, Dimension::Area, units)) + ',' +
         formatNumber(toDisplay(r.volume, Dimension::Volume, units)) + ',' + L(r.at.x()) + ',' +
         L(r.at.y()) + ',' + L(r.at.z()) + ',' + L(r.box.min.x()) + ',' + L(r.box.min.y()) + ',' +
         L(r.box.min.z()) + ',' + L(r.box.max.x()) + ',' + L(r.box.max.y()) + ',' +
         L(r.box.max.z());
    if (gouges) {
      std::string lineList, stepList;
      for (const GougeLine& l : gougeLines(r, path, steps)) {
        const auto file = static_cast<std::size_t>(l.file);
        lineList += (lineList.empty() ? "" : " ") +
                    (file < path.files.size() ? path.files[file] : std::string("program")) + ":" +
                    std::to_string(l.line);
        for (std::size_t s : l.steps)
          stepList += (stepList.empty() ? "" : " ") + std::to_string(s);
      }
      t += "," + csvQuoted(lineList) + "," + csvQuoted(stepList);
    }
    t += '\n';
  }
  return t;
}

}  // namespace engage
