#pragma once
/// \file VoxelPlanes.h
/// The material of a partial voxel of the voxel stock as the planes that bound it (private to
/// stock/: VoxelStock.cpp and VoxelCut.cpp): the voxel is the unit cube [-1/2, 1/2]^3 in voxel
/// sizes about its centre, its material inside two half-spaces, or inside either of two and
/// inside an outer third (CubeClip.h gives the shares). Also the choice of the pair of planes a
/// voxel keeps after a cut (NearestPair) and where the planes of a leaf's voxels are stored.

#include "cutters/AptCutter.h"
#include "stock/CubeClip.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace engage::voxel {

/// Voxels in a leaf of the grid (8 x 8 x 8, OpenVDB's leaf).
constexpr std::uint32_t kLeafVoxels = 512;

/// The material of a partial voxel, as far as planes tell: the unit cube (voxel sizes about
/// its centre) inside two half-spaces, stored as floats, each with the serial number of the
/// removal that made it (kStockFace for the stock's own faces). A voxel whose boundary is
/// one plane has the keep-all half-space second. Where the material is inside either plane
/// (`united`), it may also have to be inside a third, `outer` (the face a floor and wall were
/// cut into: a thin cut's rim leaves face, floor and wall in one voxel); else outer keeps all.
struct VoxelPlanes {
  std::array<float, 12> v{};  // n0, a0, n1, a1, outer's n, a
  std::array<int, 3> made{};
  /// The cube's share inside both, or NaN until needed (kept to save clipping it again).
  float held = std::numeric_limits<float>::quiet_NaN();
  /// The material is inside either plane (the inside corner a flat bottom's rim leaves,
  /// floor and wall) instead of inside both.
  bool united = false;
};
constexpr int kStockFace = -1000000000;
/// Share of a voxel below which two plane estimates are the same: the planes are stored as
/// floats (relative rounding 6e-8), and a voxel must not count as cut by rounding (it would
/// widen the measured engagement to the far side of the tool).
constexpr double kNoise = 1e-6;
/// Largest difference between a voxel's fraction and its planes' share for the planes to be
/// trusted: two planes cannot hold a third surface (a pocket wall's corner at the stock's
/// top), and where they miss one by this much the voxel falls back to the fraction rule.
constexpr double kPlanesAgree = 0.05;
/// Two planes within 15 deg of each other are one surface (cos 15 deg): a cut's face this near
/// a stored plane cuts that surface again, and a wedge needs two faces further apart.
constexpr double kNestedCos = 0.9659258262890683;
/// How near what a cut left a pair of planes must hold it to be taken without looking further
/// (a hundredth of the voxel).
constexpr double kPairNear = 0.01;
/// Share of a voxel a pair of planes may lose of the material a cut left and still count as
/// holding it all (a hundredth of kPairNear: 3e-6 mm^3 in a 0.3 mm voxel).
constexpr double kLostNoise = 1e-4;
/// Share of a voxel a step must take for the voxel to count in the step's axial depth.
constexpr double kEngagedShare = 0.01;

/// The planes of the partial voxels of one leaf: slot[offset] is 0 for none, else one more
/// than the index of the voxel's planes (no table until one voxel has planes). A voxel that
/// turns to air (never visited again) leaves its entry to the next voxel that needs one.
struct LeafPlanes {
  std::vector<std::uint16_t> slot;  ///< kLeafVoxels entries once a voxel has planes
  std::vector<VoxelPlanes> planes;
  std::vector<std::uint16_t> unused;  ///< entries of voxels that turned to air, for reuse

  /// The voxel turned to air: its entry is free for another.
  void release(std::uint32_t offset) {
    if (slot.empty() || slot[offset] == 0) return;
    unused.push_back(slot[offset]);
    slot[offset] = 0;
  }

  int get(std::uint32_t offset, HalfSpace out[2], int made[2], double& held, bool& united,
          HalfSpace* outer = nullptr, int* madeOuter = nullptr) const {
    if (slot.empty()) return 0;
    const std::uint16_t k = slot[offset];
    if (k == 0) return 0;
    const VoxelPlanes& p = planes[k - 1u];
    auto plane = [&](std::size_t i) {
      return HalfSpace{Eigen::Vector3d(p.v[4 * i], p.v[4 * i + 1], p.v[4 * i + 2]), p.v[4 * i + 3]};
    };
    for (std::size_t i = 0; i < 2; ++i) {
      out[i] = plane(i);
      made[i] = p.made[i];
    }
    held = static_cast<double>(p.held);
    united = p.united;
    if (outer) *outer = plane(2);
    if (madeOuter) *madeOuter = p.made[2];
    return 2;
  }
  /// `outer` only with `united` (else it keeps all).
  void set(std::uint32_t offset, const HalfSpace& first, int madeFirst, const HalfSpace& second,
           int madeSecond, double held, bool united = false, const HalfSpace& outer = HalfSpace{},
           int madeOuter = kStockFace) {
    if (slot.empty()) slot.assign(kLeafVoxels, 0);
    if (slot[offset] == 0) {
      if (unused.empty()) {
        planes.emplace_back();
        slot[offset] = static_cast<std::uint16_t>(planes.size());
      } else {
        slot[offset] = unused.back();
        unused.pop_back();
      }
    }
    VoxelPlanes& p = planes[slot[offset] - 1u];
    const HalfSpace* all[3] = {&first, &second, &outer};
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < 3; ++j)
        p.v[4 * i + j] = static_cast<float>(all[i]->n[static_cast<Eigen::Index>(j)]);
      p.v[4 * i + 3] = static_cast<float>(all[i]->a);
    }
    p.made = {madeFirst, madeSecond, madeOuter};
    p.held = static_cast<float>(held);
    p.united = united;
  }
};

/// A partial voxel's material as its planes tell: inside both planes q (or with `united`
/// inside either, and inside `outer`), which hold the share `held` of the cube (NaN until
/// clipped).
struct StoredMaterial {
  HalfSpace q[2];
  int made[2] = {kStockFace, kStockFace};
  double held = std::numeric_limits<double>::quiet_NaN();
  bool united = false;
  HalfSpace outer;
  int madeOuter = kStockFace;
};

/// The faces of box b that cross the voxel at p (size h) as its planes: the two that cut the
/// most (all but edge and corner voxels have one or two; a missing one keeps all).
void boxFaces(const Box3& b, const Eigen::Vector3d& p, double h, HalfSpace out[2]);

/// Share of the cube inside the material of planes q (inside both, or with `united` inside
/// either, and inside `outer` if given) and inside all of `extra`; with `centroid`, that
/// part's centroid.
double materialShare(const HalfSpace q[2], bool united, const HalfSpace* extra, int count,
                     Eigen::Vector3d* centroid = nullptr, const HalfSpace* outer = nullptr);

/// Share of the cube that an inside corner `old` (united) keeps outside a cut (inside both of
/// its `faces` faces) and that `kept` does not hold: the material that keeping those planes
/// would lose. (At most eight planes in any term.)
double lostShare(const StoredMaterial& old, const HalfSpace cut[2], int faces,
                 const StoredMaterial& kept);

/// The half-space {x : n . (x - p) + distance <= 0} of Sweep::localFaces (world units about
/// the voxel's centre p) in the voxel's unit-cube coordinates (voxel size h); a zero normal
/// stays zero.
HalfSpace voxelPlane(const Eigen::Vector3d& n, double distance, double h);

/// The stored material of the voxel at p (size h) that holds `before`: its planes, or for a
/// voxel of the stock box's shell not cut before, the box's faces. False for a voxel all
/// material (or, from dexels, a fraction without planes).
bool storedMaterial(const LeafPlanes& planes, std::uint32_t offset, double before, const Box3* box,
                    const Eigen::Vector3d& p, double h, StoredMaterial& m);

/// Of the pairs of planes offered (each with the serial of the removal that made each plane,
/// and whether the material is inside both or inside either, then also inside `outer`), the
/// one whose material's share of the cube is nearest `left`, what a cut left; the first
/// offered wins a tie. keepingAll() then prefers the nearest that loses no material.
class NearestPair {
 public:
  explicit NearestPair(double left) : left_(left) {}
  void offer(const HalfSpace& a, int madeA, const HalfSpace& b, int madeB, bool united,
             const HalfSpace& outer = HalfSpace{}, int madeOuter = kStockFace) {
    const HalfSpace pair[2] = {a, b};
    StoredMaterial c;
    c.held =
        united ? materialShare(pair, true, nullptr, 0, nullptr, &outer) : cubeFraction(pair, 2);
    c.q[0] = a;
    c.q[1] = b;
    c.made[0] = madeA;
    c.made[1] = madeB;
    c.united = united;
    c.outer = united ? outer : HalfSpace{};
    c.madeOuter = madeOuter;
    if (!any() || std::abs(c.held - left_) < std::abs(best_.held - left_)) best_ = c;
    if (count_ < static_cast<int>(offered_.size()))
      offered_[static_cast<std::size_t>(count_++)] = c;
  }
  /// Of the pairs offered (the first kMostOffered: cutCorner offers at most seven), the nearest
  /// that loses at most `tolerance` of the cube (lost(pair): the material the pair would not
  /// hold); false, keeping the nearest, when none does.
  template <typename Lost>
  bool keepingAll(Lost&& lost, double tolerance) {
    std::array<int, kMostOffered> order{};
    for (int i = 0; i < count_; ++i)
      order[static_cast<std::size_t>(i)] = i;
    auto distance = [&](int i) {
      return std::abs(offered_[static_cast<std::size_t>(i)].held - left_);
    };
    std::stable_sort(order.begin(), order.begin() + count_,
                     [&](int x, int y) { return distance(x) < distance(y); });
    for (int i = 0; i < count_; ++i) {
      const StoredMaterial& c =
          offered_[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])];
      if (lost(c) <= tolerance) {
        best_ = c;
        return true;
      }
    }
    return false;
  }
  /// Whether an offered pair holds what the cut left to within `tolerance`.
  bool within(double tolerance) const { return any() && std::abs(best_.held - left_) <= tolerance; }
  /// Whether any pair was offered.
  bool any() const { return count_ > 0; }
  /// Stores the chosen pair as the voxel's planes.
  void store(LeafPlanes& planes, std::uint32_t offset) const {
    planes.set(offset, best_.q[0], best_.made[0], best_.q[1], best_.made[1], best_.held,
               best_.united, best_.outer, best_.madeOuter);
  }

 private:
  static constexpr int kMostOffered = 8;
  double left_;
  StoredMaterial best_;  // the nearest pair, its share of the cube as `held`
  std::array<StoredMaterial, kMostOffered> offered_;
  int count_ = 0;
};

/// Stores as the voxel's planes what the cut (inside `faces` half-spaces) leaves of a voxel it
/// alone bounds, within `outer` (keep-all: the whole voxel), holding `share` of the cube (the
/// caller's: 1 - the cut's share without an outer plane): a wedge's floor-or-wall corner
/// exactly, else the one plane kept() gives.
template <typename Kept>
void keepRestOfCut(LeafPlanes& planes, std::uint32_t offset, const HalfSpace cut[2], int faces,
                   Kept&& kept, int serial, double share, const HalfSpace& outer = HalfSpace{},
                   int madeOuter = kStockFace) {
  if (faces == 2)
    planes.set(offset, cut[0].complement(), serial, cut[1].complement(), serial, share, true, outer,
               madeOuter);
  else if (outer.n.squaredNorm() == 0.0)
    planes.set(offset, kept(), serial, HalfSpace{}, kStockFace, share);
  else
    planes.set(offset, outer, madeOuter, kept(), serial, share);
}

}  // namespace engage::voxel
