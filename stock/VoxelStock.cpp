// How removal works. A step's swept cutter has a signed distance in closed form where the step
// keeps its height; for steps that change height it is minimised over the tip positions. In
// each voxel the cut's surface is the tangent plane of that distance moved by the surface's
// sagitta (curvature from Sweep, averaged over the plane's section). A partial voxel keeps the
// planes that bound its material: inside two planes, or (a corner a flat bottom's rim leaves in
// a face) inside either of two planes and inside an outer third; a new cut is clipped against
// them exactly (CubeClip.h). Near a flat bottom's rim on a step that changes height the voxel
// is sampled in 4^3 sub-cubes, each cut by the swept solid's supporting planes at the voxel's
// corners outside it (Sweep::support, exact for a convex swept solid: an outer polyhedron),
// computed once per corner for the voxels that share it (probeCorner). Where a cut crosses
// the stored planes, the planes kept are a pair offered by NearestPair: the nearest to what the
// cut left that loses none of it (lostShare), else the nearest that holds no air; the fraction
// follows the cut's rest while the same pass goes on (cutCorner). The measurements behind each
// of these choices, and what was tried and dropped, are in docs/voxel-stock.md.

#include "stock/VoxelStock.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "stock/AtomicFile.h"
#include "stock/CubeClip.h"
#include "stock/DexelStock.h"
#include "stock/TriangleMesh.h"
#include "stock/VoxelCut.h"
#include "stock/VoxelGrid.h"
#include "stock/VoxelPlanes.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/ChangeBackground.h>
#include <openvdb/tools/FastSweeping.h>
#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <tbb/parallel_for.h>
#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace engage {
using namespace voxel;

namespace voxel {

void initVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

/// Physical memory of this machine, bytes.
static double physicalMemory() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  double kb = 0.0;
  while (in >> key >> kb) {
    if (key == "MemTotal:") return kb * 1024.0;
    in.ignore(256, '\n');
  }
  return 8e9;
}

/// Bytes of a cut voxel: its fraction in a leaf (4), the removed capture's three grids (12),
/// its leaf's table of planes (2, more for partial voxels), the nodes and the threads' heaps
/// (measured: the peaks of six runs stayed 10-35 % below the bound this gives; docs/accuracy.md).
constexpr double kCutVoxelBytes = 40.0;
/// Bytes of a leaf of a box's partly covered face: its fractions and its node (measured: the
/// faces of a 30 x 20 x 1 mm box at 0.02 and 0.01 mm, 2.3 KB a leaf).
constexpr double kShellLeafBytes = 2.5e3;

double voxelCount(const Box3& box, double h) {
  const Eigen::Vector3d size = box.max - box.min;
  return (size.x() / h + 2) * (size.y() / h + 2) * (size.z() / h + 2);
}

void checkMemory(const Box3& box, double h, const std::vector<Box3>* reach) {
  if (!(std::isfinite(h) && h > 0.0))
    throw ParameterError("voxel size = " + formatNumber(h) + " mm must be positive");
  const double limit = 0.75 * physicalMemory();
  const double bytes = VoxelStock::memoryBound(box, h, reach, limit);
  if (bytes > limit)
    throw ParameterError("voxel size = " + formatNumber(h) + " mm makes " +
                         formatNumber(voxelCount(box, h)) + " voxels for this stock, more than " +
                         formatNumber(limit / 1e9) + " GB (this machine's for it) " +
                         (reach ? "where the program cuts" : "if cut everywhere") +
                         ": choose a larger --voxel");
}

}  // namespace voxel

namespace {

/// openvdb::tools::BoxSampler::sample(acc, q), trilinear in index space with the same
/// arithmetic, reading the eight values from one leaf's buffer where they lie in one leaf
/// (about 2 samples in 3) instead of the accessor's eight lookups per sample (576 samples per
/// step for the engagement angle), with the same values.
float sampleTrilinear(const FloatGrid::Accessor& acc, const openvdb::Vec3d& q) {
  const openvdb::Vec3i i = openvdb::tools::local_util::floorVec3(q);
  const Coord ijk(i);
  constexpr int kLast = kLeafDim - 1;
  if ((ijk.x() & kLast) == kLast || (ijk.y() & kLast) == kLast || (ijk.z() & kLast) == kLast)
    return openvdb::tools::BoxSampler::sample(acc, q);
  float data[2][2][2];
  if (const Leaf* leaf = acc.probeConstLeaf(ijk)) {
    const openvdb::Index o = Leaf::coordToOffset(ijk);
    for (openvdb::Index a = 0; a < 2; ++a)
      for (openvdb::Index b = 0; b < 2; ++b)
        for (openvdb::Index c = 0; c < 2; ++c)
          data[a][b][c] = leaf->getValue(o + (a << (2 * Leaf::LOG2DIM)) + (b << Leaf::LOG2DIM) + c);
  } else {  // a tile: one value over the leaf's block
    const float v = acc.getValue(ijk);
    for (auto& plane : data)
      for (auto& row : plane)
        row[0] = row[1] = v;
  }
  return openvdb::tools::BoxSampler::trilinearInterpolation(data, q - i);
}

/// Per-leaf result of a removal, combined in leaf order.
struct LeafResult {
  double volume = 0.0;
  double lateralMoment = 0.0;
  double zMin = 1e300, zMax = -1e300;
  long changed = 0;
  long visited = 0;
  std::vector<std::pair<Coord, float>> lost;  ///< per changed voxel, when capturing
};

/// Half the diagonal of a leaf of voxels of size h, mm.
double leafHalfDiagonal(double h) {
  return 0.5 * std::sqrt(3.0) * kLeafDim * h;
}

/// The leaf-sized blocks of the index box [lo, hi] that hold material and that the sweep may
/// reach: `visit(origin, leaf, distance)` with the block's leaf (null for a material tile) and
/// the sweep's signed distance from the block's centre. Used by the removal and by the
/// material query, so that both see the same blocks.
template <class Accessor, class Visit>
void forBlocksInReach(Accessor& acc, const Sweep& sweep, double h, const Coord& lo, const Coord& hi,
                      Visit&& visit) {
  const double reach = leafHalfDiagonal(h) + h;
  auto floorLeaf = [](int v) { return v & ~(kLeafDim - 1); };
  for (int x = floorLeaf(lo.x()); x <= hi.x(); x += kLeafDim)
    for (int y = floorLeaf(lo.y()); y <= hi.y(); y += kLeafDim)
      for (int z = floorLeaf(lo.z()); z <= hi.z(); z += kLeafDim) {
        const Coord origin(x, y, z);
        const Leaf* leaf = acc.probeConstLeaf(origin);
        if (leaf ? leaf->isEmpty() : (!acc.isValueOn(origin) || acc.getValue(origin) <= 0.0f))
          continue;  // all air
        const double c = 0.5 * (kLeafDim - 1);
        const double dc =
            sweep.signedDistance(Eigen::Vector3d(x * h + c * h, y * h + c * h, z * h + c * h));
        if (dc > reach) continue;  // out of reach
        visit(origin, leaf, dc);
      }
}

}  // namespace

VoxelStock::VoxelStock(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VoxelStock::VoxelStock(VoxelStock&&) noexcept = default;
VoxelStock& VoxelStock::operator=(VoxelStock&&) noexcept = default;
VoxelStock::~VoxelStock() = default;

VoxelStock VoxelStock::box(const Box3& b, double h, const std::vector<Box3>* reach) {
  for (int a = 0; a < 3; ++a)
    if (!(b.max[a] > b.min[a]))
      throw ParameterError("stock box is empty along " +
                           std::string(1, static_cast<char>('X' + a)) + ": " +
                           formatNumber(b.min[a]) + " to " + formatNumber(b.max[a]) + " mm");
  checkMemory(b, h, reach);
  initVdb();
  auto impl = std::make_unique<Impl>();
  impl->h = h;
  impl->box = b;
  impl->grid = FloatGrid::create(0.0f);
  impl->grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
  impl->grid->setName("stock");
  impl->grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  // Voxel i covers [(i - 1/2) h, (i + 1/2) h]. Fully covered voxels are filled as tiles; the
  // shell of partly covered voxels gets the product of its per-axis covered fractions.
  const Coord lo = impl->index(b.min);
  const Coord hi = impl->index(b.max);
  auto cover = [&](int i, int a) {
    const double v0 = (i - 0.5) * h;
    const double v1 = (i + 0.5) * h;
    return std::max(0.0, std::min(v1, b.max[a]) - std::max(v0, b.min[a])) / h;
  };
  auto full = [&](int i, int a) { return cover(i, a) >= 1.0 - 1e-12; };
  Coord ilo = lo, ihi = hi;
  for (int a = 0; a < 3; ++a) {
    while (ilo[a] <= ihi[a] && !full(ilo[a], a))
      ++ilo[a];
    while (ihi[a] >= ilo[a] && !full(ihi[a], a))
      --ihi[a];
  }
  if (ilo.x() <= ihi.x() && ilo.y() <= ihi.y() && ilo.z() <= ihi.z())
    impl->grid->tree().fill(CoordBBox(ilo, ihi), 1.0f, true);
  auto acc = impl->grid->getAccessor();
  for (int i = lo.x(); i <= hi.x(); ++i)
    for (int j = lo.y(); j <= hi.y(); ++j)
      for (int k = lo.z(); k <= hi.z(); ++k) {
        const bool inner = i >= ilo.x() && i <= ihi.x() && j >= ilo.y() && j <= ihi.y() &&
                           k >= ilo.z() && k <= ihi.z();
        if (inner) {
          k = ihi.z();  // skip the filled interior of this column
          continue;
        }
        const double f = cover(i, 0) * cover(j, 1) * cover(k, 2);
        if (f > 0.0) acc.setValue(Coord(i, j, k), static_cast<float>(f));
      }
  return VoxelStock(std::move(impl));
}

VoxelStock VoxelStock::fromMesh(const std::string& path, double h) {
  const TriangleMesh mesh = readMesh(path);
  if (mesh.triangles.empty()) throw ParameterError("stock mesh '" + path + "' has no faces");
  const std::size_t open = boundaryEdgeCount(mesh);
  if (open > 0)
    throw ParameterError("stock mesh '" + path + "' is not closed: " + std::to_string(open) +
                         " edges belong to one triangle only");
  Box3 b;
  b.min = Eigen::Vector3d::Constant(1e300);
  b.max = Eigen::Vector3d::Constant(-1e300);
  std::vector<openvdb::Vec3s> points;
  for (const auto& p : mesh.points) {
    points.emplace_back(p[0], p[1], p[2]);
    for (int a = 0; a < 3; ++a) {
      b.min[a] = std::min(b.min[a], static_cast<double>(p[static_cast<std::size_t>(a)]));
      b.max[a] = std::max(b.max[a], static_cast<double>(p[static_cast<std::size_t>(a)]));
    }
  }
  checkMemory(b, h);
  initVdb();
  std::vector<openvdb::Vec3I> triangles;
  for (const auto& t : mesh.triangles)
    triangles.emplace_back(t[0], t[1], t[2]);
  const auto xform = openvdb::math::Transform::createLinearTransform(h);
  const auto ls = openvdb::tools::meshToLevelSet<FloatGrid>(*xform, points, triangles, 3.0f);
  // Interior (tiles included) becomes 1; the narrow band gets the fraction of its distance.
  const auto interior = openvdb::tools::sdfInteriorMask(*ls);
  auto impl = std::make_unique<Impl>();
  impl->h = h;
  impl->grid = FloatGrid::create(0.0f);
  impl->grid->setTransform(xform);
  impl->grid->setName("stock");
  impl->grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  impl->grid->setTree(
      std::make_shared<FloatGrid::TreeType>(interior->tree(), 0.0f, 1.0f, openvdb::TopologyCopy()));
  auto acc = impl->grid->getAccessor();
  auto lsAcc = ls->getConstAccessor();
  for (auto it = ls->cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue()) continue;
    const double sdfMm = static_cast<double>(*it);  // meshToLevelSet stores world units
    // The surface in the voxel is the plane of the distance and its gradient (central
    // differences); the material is its exact share of the cube (as for cuts).
    const Coord ijk = it.getCoord();
    Eigen::Vector3d g;
    for (int a = 0; a < 3; ++a) {
      Coord e(0);
      e[a] = 1;
      g[a] = static_cast<double>(lsAcc.getValue(ijk + e) - lsAcc.getValue(ijk - e)) / (2.0 * h);
    }
    const double norm = g.norm();
    const HalfSpace material{norm > 0.0 ? Eigen::Vector3d(g / norm) : Eigen::Vector3d::Zero(),
                             -sdfMm / h};
    const double m = cubeFraction(material);
    if (m <= 0.0) {
      acc.setValueOff(ijk, 0.0f);
      continue;
    }
    acc.setValue(ijk, static_cast<float>(m));
    if (m < 1.0)
      impl->planes[leafKey(ijk)].set(Leaf::coordToOffset(ijk), material, kStockFace, HalfSpace{},
                                     kStockFace, m);
  }
  impl->grid->tree().prune();
  return VoxelStock(std::move(impl));
}

double VoxelStock::voxelSize() const {
  return impl_->h;
}

double VoxelStock::volume() const {
  // Sum leaf by leaf, then in leaf order, so the value repeats to the last digit.
  double sum = 0.0;
  for (auto it = impl_->grid->cbeginValueOn(); it; ++it)
    sum += static_cast<double>(*it) * static_cast<double>(it.getVoxelCount());
  return sum * impl_->h * impl_->h * impl_->h;
}

double VoxelStock::materialInside(const Sweep& sweep, double top) const {
  const Impl& s = *impl_;
  const double h = s.h;
  Box3 wb = sweep.bounds();
  wb.max.z() = std::min(wb.max.z(), top);
  const Coord lo = s.index(wb.min) - Coord(1);
  const Coord hi = s.index(wb.max) + Coord(1);
  auto acc = s.grid->getConstAccessor();
  double sum = 0.0;
  forBlocksInReach(acc, sweep, h, lo, hi, [&](const Coord& origin, const Leaf* leaf, double) {
    const Coord from = Coord::maxComponent(origin, lo);
    const Coord to = Coord::minComponent(origin + Coord(kLeafDim - 1), hi);
    for (int ix = from.x(); ix <= to.x(); ++ix)
      for (int iy = from.y(); iy <= to.y(); ++iy)
        for (int iz = from.z(); iz <= to.z(); ++iz) {
          const Coord ijk(ix, iy, iz);
          // A leaf's voxel, or a material tile's value.
          const float f =
              leaf ? (leaf->isValueOn(ijk) ? leaf->getValue(ijk) : 0.0f) : acc.getValue(ijk);
          if (f <= 0.0f || (iz - 0.5) * h > top) continue;
          if (sweep.signedDistance(Eigen::Vector3d(ix * h, iy * h, iz * h)) < 0.0)
            sum += static_cast<double>(f);
        }
  });
  return sum * h * h * h;
}

/// A voxel stock's MaterialReader: a voxel all material or none says so; a partial one, the
/// planes that bound its material where they hold its fraction (else, planes never kept, as
/// in a stock read from dexels, the fractions' 0.5 level).
class VoxelReader final : public MaterialReader {
 public:
  explicit VoxelReader(const VoxelStock::Impl& s) : s_(s), acc_(s.grid->getAccessor()) {}

  const std::vector<std::uint8_t>& read(const std::vector<Eigen::Vector3d>& points) override {
    out_.clear();
    for (const Eigen::Vector3d& p : points)
      out_.push_back(inside(p));
    return out_;
  }

 private:
  bool inside(const Eigen::Vector3d& p) {
    // Outside the box a stock was made from there is none (a voxel on its shell holding a
    // wall and a cut as its two planes no longer holds the box's face).
    if (s_.box &&
        ((p.array() < s_.box->min.array()).any() || (p.array() > s_.box->max.array()).any()))
      return false;
    const Coord c = s_.index(p);
    const double f = static_cast<double>(acc_.getValue(c));
    if (f >= 1.0 - kNoise || f <= kNoise) return f > 0.5;
    const Eigen::Vector3d centre(c.x() * s_.h, c.y() * s_.h, c.z() * s_.h);
    const auto leaf = s_.planes.find(leafKey(c));
    static const LeafPlanes none;
    StoredMaterial m;
    if (storedMaterial(leaf == s_.planes.end() ? none : leaf->second, Leaf::coordToOffset(c), f,
                       s_.box ? &*s_.box : nullptr, centre, s_.h, m)) {
      if (std::isnan(m.held)) m.held = materialShare(m.q, m.united, nullptr, 0, nullptr, &m.outer);
      if (m.held > 0.0 && std::abs(m.held - f) <= kPlanesAgree) {
        const Eigen::Vector3d u = (p - centre) / s_.h;
        auto in = [&](const HalfSpace& q) { return q.n.dot(u) <= q.a; };
        return m.united ? (in(m.q[0]) || in(m.q[1])) && in(m.outer)
                        : in(m.q[0]) && in(m.q[1]) && in(m.outer);
      }
    }
    return sampleTrilinear(acc_, openvdb::Vec3d(p.x() / s_.h, p.y() / s_.h, p.z() / s_.h)) > 0.5f;
  }

  const VoxelStock::Impl& s_;
  FloatGrid::Accessor acc_;
  std::vector<std::uint8_t> out_;
};

std::unique_ptr<MaterialReader> VoxelStock::materialReader(std::size_t) const {
  return std::make_unique<VoxelReader>(*impl_);
}

double VoxelStock::fraction(int i, int j, int k) const {
  return static_cast<double>(impl_->grid->tree().getValue(Coord(i, j, k)));
}

Box3 VoxelStock::bounds() const {
  CoordBBox bb;
  impl_->grid->tree().evalActiveVoxelBoundingBox(bb);
  Box3 b;
  if (bb.empty()) return b;
  const double h = impl_->h;
  b.min = Eigen::Vector3d(bb.min().x() - 0.5, bb.min().y() - 0.5, bb.min().z() - 0.5) * h;
  b.max = Eigen::Vector3d(bb.max().x() + 0.5, bb.max().y() + 0.5, bb.max().z() + 0.5) * h;
  return b;
}

std::size_t VoxelStock::memoryBytes() const {
  std::size_t bytes = impl_->grid->memUsage();
  for (const auto& [key, leaf] : impl_->planes)
    bytes += sizeof(key) + sizeof(leaf) +
             (leaf.slot.capacity() + leaf.unused.capacity()) * sizeof(std::uint16_t) +
             leaf.planes.capacity() * sizeof(VoxelPlanes);
  if (impl_->removed)
    bytes += impl_->removed->memUsage() + impl_->step->memUsage() + impl_->mrr->memUsage();
  return bytes;
}

void VoxelStock::captureRemoved(bool on) {
  impl_->capture = on;
  if (on && !impl_->removed) {
    impl_->removed = FloatGrid::create(0.0f);
    impl_->removed->setTransform(impl_->grid->transform().copy());
    impl_->removed->setName("removed");
    impl_->removed->setGridClass(openvdb::GRID_FOG_VOLUME);
    impl_->step = Int32Grid::create(-1);
    impl_->step->setTransform(impl_->grid->transform().copy());
    impl_->step->setName("step");
    impl_->mrr = FloatGrid::create(0.0f);
    impl_->mrr->setTransform(impl_->grid->transform().copy());
    impl_->mrr->setName("mrr");
  }
}

// One function: the per-leaf loop (run side by side over the leaves the step reaches) and the
// merge of the leaves' results in leaf order share the step's set-up.
Removal VoxelStock::remove(const Sweep& sweep, int stepIndex, double dtSeconds) {
  Impl& s = *impl_;
  const double h = s.h;
  const int serial = s.removals++;
  // This removal's number in the process (rim corners' probes are cached under it).
  static std::atomic<std::uint64_t> removalsInProcess{0};
  const std::uint64_t sweepId = ++removalsInProcess;
  const Box3 wb = sweep.bounds();
  const Coord lo = s.index(wb.min) - Coord(1);
  const Coord hi = s.index(wb.max) + Coord(1);
  // Leaves the step may touch: existing leaves, and material tiles split only where reached.
  const double halfDiagonal = leafHalfDiagonal(h);
  std::vector<Leaf*> leaves;
  std::vector<LeafPlanes*> leafPlanes;
  std::vector<double> centreDistance;
  auto acc = s.grid->getAccessor();
  forBlocksInReach(acc, sweep, h, lo, hi, [&](const Coord& origin, const Leaf*, double dc) {
    // The leaf itself (a material tile split into one here, serially).
    leaves.push_back(acc.touchLeaf(origin));
    leafPlanes.push_back(&s.planes[leafKey(origin)]);  // (node addresses are stable)
    centreDistance.push_back(dc);
  });

  // Feed direction at the step's end, for the width and the engagement angle; heights and
  // sides in the tool's frame (a tilted tool's).
  const StepPath& path = sweep.path();
  const Eigen::Vector3d end = path.end;
  const bool tilted = path.tilted();
  const Eigen::Matrix3d toTool = path.toolToPart().transpose();
  const Eigen::Vector2d u = path.feedDirectionAtEnd();
  const Eigen::Vector2d n(-u.y(), u.x());
  const AptCutter& cutter = sweep.cutter();
  const double voxelVolume = h * h * h;

  std::vector<LeafResult> results(leaves.size());
  auto work = [&](std::size_t li) {
    Leaf& leaf = *leaves[li];
    LeafPlanes& planes = *leafPlanes[li];
    LeafResult& r = results[li];
    const bool allInside = centreDistance[li] < -(halfDiagonal + 0.5 * h);
    // Only the part of the leaf inside the step's (index) bounds can change.
    const Coord o = leaf.origin();
    const Coord from = Coord::maxComponent(o, lo);
    const Coord to = Coord::minComponent(o + Coord(kLeafDim - 1), hi);
    for (int ix = from.x(); ix <= to.x(); ++ix)
      for (int iy = from.y(); iy <= to.y(); ++iy)
        for (int iz = from.z(); iz <= to.z(); ++iz) {
          const Coord ijk(ix, iy, iz);
          const openvdb::Index offset = Leaf::coordToOffset(ijk);
          if (!leaf.isValueOn(offset)) continue;  // air
          const float before = leaf.getValue(offset);
          if (before <= 0.0f) continue;
          const Eigen::Vector3d p(ijk.x() * h, ijk.y() * h, ijk.z() * h);
          float after = 0.0f;
          if (!allInside) {
            ++r.visited;
            after = static_cast<float>(remaining(sweep, p, h, before, planes, offset, serial,
                                                 s.box ? &*s.box : nullptr, sweepId));
          }
          if (!(after < before)) continue;
          const double lost = static_cast<double>(before - after);
          r.volume += lost * voxelVolume;
          ++r.changed;
          leaf.setValueOnly(offset, std::max(after, 0.0f));
          if (after <= 0.0f) {  // air: skipped from now on
            leaf.setValueOff(offset);
            planes.release(offset);
          }
          if (s.capture) r.lost.emplace_back(ijk, before - std::max(after, 0.0f));
          // The removed material's height relative to the tip at the step's end. A voxel stands for
          // material up to (lost fraction - 1/2) h beyond its centre, which places a boundary
          // crossing it at the right sub-voxel height (exactly for axis-aligned boundaries).
          // Slivers of a hundredth of a voxel (a wall a later pass runs along again, its
          // planes' round-off) count in the volume but do not deepen the cut.
          const Eigen::Vector3d rel = tilted ? Eigen::Vector3d(toTool * (p - end)) : p - end;
          const double side = rel.head<2>().dot(n);
          r.lateralMoment += lost * voxelVolume * side;
          if (lost < kEngagedShare) continue;
          const double reach = (lost - 0.5) * h;
          r.zMin = std::min(r.zMin, rel.z() - reach);
          r.zMax = std::max(r.zMax, rel.z() + reach);
        }
  };
  if (leaves.size() >= 8)
    tbb::parallel_for(std::size_t(0), leaves.size(), work);
  else
    for (std::size_t li = 0; li < leaves.size(); ++li)
      work(li);

  Removal out;
  double zMin = 1e300, zMax = -1e300;
  for (const LeafResult& r : results) {
    out.volume += r.volume;
    out.lateral += r.lateralMoment;
    out.voxelsChanged += r.changed;
    out.voxelsVisited += r.visited;
    zMin = std::min(zMin, r.zMin);
    zMax = std::max(zMax, r.zMax);
  }
  if (out.voxelsChanged > 0) {
    out.lateral /= out.volume;
    if (zMax >= zMin) {  // (only slivers: no width, no depth)
      out.axialDepth = std::max(0.0, std::min(zMax - std::max(zMin, 0.0), cutter.height()));
      out.top = std::max(0.0, std::min(zMax, cutter.height()));
    }
  }

  if (s.capture && out.voxelsChanged > 0) {
    // The capture grids allocate leaves: fill them serially, in leaf order.
    const double mrrValue = dtSeconds > 0.0 ? out.volume / (dtSeconds / 60.0) : 0.0;
    auto racc = s.removed->getAccessor();
    auto sacc = s.step->getAccessor();
    auto macc = s.mrr->getAccessor();
    for (const LeafResult& r : results)
      for (const auto& [ijk, lost] : r.lost) {
        racc.setValue(ijk, racc.getValue(ijk) + lost);
        if (sacc.getValue(ijk) < 0) {
          sacc.setValue(ijk, stepIndex);
          macc.setValue(ijk, static_cast<float>(mrrValue));
        }
      }
  }
  return out;
}

double VoxelStock::memoryBound(const Box3& box, double h, const std::vector<Box3>* reach,
                               double stopAbove) {
  if (!reach) return voxelCount(box, h) * kCutVoxelBytes;
  auto index = [h](double v) { return static_cast<long>(std::floor(v / h + 0.5)); };
  auto block = [](long i) { return i >= 0 ? i / kLeafDim : -((-i + kLeafDim - 1) / kLeafDim); };
  std::array<long, 3> lo{}, hi{}, b0{}, nb{};
  std::array<double, 3> nbd{};
  for (int a = 0; a < 3; ++a) {  // the voxels the box covers (a face between voxels: not beyond)
    lo[a] = index(box.min[a]);
    hi[a] = static_cast<long>(std::ceil(box.max[a] / h - 0.5));
    b0[a] = block(lo[a]);
    nb[a] = block(hi[a]) - b0[a] + 1;
    nbd[a] = static_cast<double>(nb[a]);
  }
  // The leaves of the partly covered faces (box() sets their voxels one by one).
  double bytes = 0.0;
  for (int a = 0; a < 3; ++a)
    for (const double face : {box.min[a], box.max[a]}) {
      const double offGrid = std::abs(face / h + 0.5 - std::round(face / h + 0.5));
      if (offGrid > 1e-9) bytes += kShellLeafBytes * nbd[(a + 1) % 3] * nbd[(a + 2) % 3];
    }
  // The leaves the cuts reach (a voxel beyond each box: a step changes the voxels it touches).
  const double blockBytes = kLeafVoxels * kCutVoxelBytes;
  const double blocks = nbd[0] * nbd[1] * nbd[2];
  std::vector<bool> dense(blocks <= double(1u << 28) ? static_cast<std::size_t>(blocks) : 0);
  std::unordered_set<long> sparse;
  auto mark = [&](long key) {
    if (!dense.empty()) {
      if (dense[static_cast<std::size_t>(key)]) return false;
      dense[static_cast<std::size_t>(key)] = true;
      return true;
    }
    return sparse.insert(key).second;
  };
  for (const Box3& r : *reach) {
    std::array<long, 3> j0{}, j1{};
    bool empty = false;
    for (int a = 0; a < 3; ++a) {
      j0[a] = block(std::max(lo[a], index(r.min[a]) - 1)) - b0[a];
      j1[a] = block(std::min(hi[a], index(r.max[a]) + 1)) - b0[a];
      empty = empty || j1[a] < j0[a] || r.max[a] < r.min[a];
    }
    if (empty) continue;
    for (long x = j0[0]; x <= j1[0]; ++x)
      for (long y = j0[1]; y <= j1[1]; ++y)
        for (long z = j0[2]; z <= j1[2]; ++z)
          if (mark((x * nb[1] + y) * nb[2] + z) && (bytes += blockBytes) > stopAbove) return bytes;
  }
  return bytes;
}

}  // namespace engage
