// How removal works, and what was tried (figures at D/20 unless said; the README keeps only
// the current accuracy and speed).
//
// A step's swept cutter has a signed distance in closed form where the step keeps its height;
// for steps that change height it is minimised over the tip positions. In each voxel the
// surface is the tangent plane of that distance moved by the surface's sagitta (curvature from
// Sweep, averaged over the plane's section: plain tangent planes took 0.73 % too much of a
// ball's first plunge step and 0.7 % of the finishing raster at 0.2 mm). A partial voxel keeps
// the planes that bound its material (one or two, or a corner within a face: three, below),
// and a new cut is clipped against them (CubeClip.h) instead of the fraction rule
// min(fraction, 1 - cut), which was 0.8 % off per step on a side cut and 1.5 % on arcs;
// keeping planes costs 48 bytes per partial voxel (68 with the outer plane below; the example
// batch 1.1-1.4x the memory, the raster's grid 2x, its loop 1.5-2x slower). Tried against the
// fraction rule and dropped: a plane reconstructed from the neighbours' fractions (+0.5 % mean on
// slots), a 4^3 occupancy lattice per partial voxel (lattice and fraction disagree by up to an
// eighth of a voxel along a wall), the minimum per octant (a re-cut floor ratchets down). Near a
// flat bottom's rim on steps that change height the voxel samples 4^3 sub-cubes, each cutting the
// stored material sub-cube by sub-cube: one plane gave 1.85 % on a 5 deg ramp and 2.2 % on a helix,
// 2^3 sub-cubes 0.72 % / 0.78 %, 3^3 would be 1.8x faster on a helix but leave a ramp 0.62 % off;
// 8^3 before the curvature correction took a bore from 0.53 % to 0.45 % at 5x the cost. Before the
// sub-cube cut, the nested rule (keep the smaller material) saw the rim's cut as one plane and left
// +0.35 mm^3 of a 188.5 mm^3 ramp's floor (worst step at any grid placement 0.57 %, now 0.37 %).
// Not the cause, measured: the depth inside the union of tool positions (an exact support-function
// depth moved the excess only to +0.29). Also tried for that floor: probing outward along the
// gradient (ramp totals +0.2 %), the probe point's own normal (a 2 deg ramp 0.85 %), an exact
// footprint-and-floor wedge (0.84 %), an exact-sign 16^3 lattice and 8^3 rim sub-cubes (unchanged).
// On a straight step (a convex swept solid) the rim's voxel is now cut by the swept solid's
// supporting planes normal to the swept distance's gradient at the voxel's corners outside it
// (Sweep::support, exact): an outer polyhedron, exact for the rim's edge. The sub-cubes' own
// tangent planes each held a little more than the solid (a tangent plane of a convex solid
// bounds it) and a ramp took that at every step: +18.7 % on a 0.05 mm deep ramp from the top
// face, +4.4 % 0.2 mm deep (now -1.3 %, +1.3 %; tests/stock/ReferenceCuts.cpp), and the 3D
// contours of flat end mills run 1.6x faster (tiger, flower_mold), 2.1x with each corner's
// probe computed once per step for the up to eight voxels that share it (probeCorner). Tried on the
// way: the closest instance's own tangent plane at the corners (it is found to 2 % of the step, and
// where the rim's envelope is the surface its flat bottom's plane cuts into the instances
// beside it: a 5 deg ramp -0.3 %), the same normal offset to the exact support (the bottom's
// normal then bounds the whole step: +14.6 %), and excluding the last step's swept solid from
// the sub-cubes' cut (+15 %; a 5 deg ramp then -0.18 %: each step had been taking what the
// last one's sub-cubes left).
// What a flat bottom's rim leaves of a face (face, floor and wall) needs three planes: a voxel
// whose material is inside either of two planes (floor or wall) may also be bounded by an
// outer one (the face). With two planes the first 0.05 mm peck into a top face took -5.8 %
// (clipping the wedge exactly but keeping two planes mended it and made the next peck -5.5 %,
// skims -25 %); with three every peck takes +0.1 %, a 0.01 mm skim of the top face -0.1 %
// (was -4.2 %), a floor re-cut 0.02 mm deeper -0.05 % (was -1.9 %). Two rules went with it,
// both measured on data/gcode/thin at D/20: a wedge nested in the last step's cut keeps its
// own corner within the other plane (one plane leaving its share, at 45 deg, cut a wall that
// a side skim grazed above the rim: +1.7 %), and a corner cut again by the same pass takes the
// fraction down to the cut's rest where the planes already hold it (the first step of a pass
// across a corner stores the nearest pair, which can claim more than was cut; the fraction
// then never followed: a slot's floor re-cut -1.9 %). The ramps from a face were still -1.4 /
// +1.3 %: their rim's wedge was the two most cutting hull planes, and corners under the flat
// bottom give its plane two or three times, so the wedge was two floors and the rest kept no
// wall; now the second is the more cutting (with the first) of the most cutting and the widest
// plane at 15 deg or more to the first: +0.2 / +0.3 % (the widest alone: a total 0.13 %, the
// best of all pairs the same as these two at six clips more per voxel). Tried before that, for
// the ratio by which nested floor steps carry a rim step's excess: the smaller of fraction and
// planes, and the planes' change subtracted; neither helped. A wedge across two old planes
// may take only a sliver of them (the front of a pass entering a voxel of floor and side
// face): keeping them as they are is offered (the nearest pair had been the two floors, the
// face dropped and the floor never cut: the slot re-cut leaving the stock -0.9 -> -0.1 %).
// A voxel whose wall and floor the front of the next, deeper pass crosses holds four planes'
// material for that step; no pair is near it, and the nearest dropped the wall (the slot
// re-cut 0.1 mm deeper +0.6 %): the pair that holds no air is kept and the fraction follows
// the cut's rest (cutCorner), -0.06 %; D/10's worst move 4.0 -> 0.79 %, D/40's 1.04 -> 0.09 %.
// Cost of the third plane and the wedge: the voxel loop of flat end mills' 3D contours
// 13-25 % longer (CAMotics' tiger 8.19 -> 10.27 s, flower_mold 9.10 -> 10.32 s, one core; the
// ball raster +1 %; their removed volumes now within 0.002 and 0.018 % of the dexels', were
// -0.19 and +0.063 %): cube clipping went from 39 to 47 % of the samples (perf), the rim's
// candidate pairs with an outer plane and its united materials clipped with theirs. Not the
// cause, measured: keeping the old floor under a wedge instead of dropping it (no change).
// Offering the rarer pairs only when no pair was within 1e-4 of the share left did not
// measurably help.
// A pass that skims again, 0.01 mm lower, a floor an earlier pass cut into a face meets in its
// rim's voxels face, old floor, wall and its own front: four surfaces. The nearest pair was
// often one that dropped the wall (the two floors within the face, or the new corner within
// the old floor), so the face's material beside the track, which no step of the pass reaches,
// was lost to the pair and taken from the fraction by the pass's next step: the re-skim took
// +0.14 to +0.33 % (data/gcode/thin/skims_ramps.ngc line 28 +0.55 % against the exact
// reference). Now the nearest pair that loses none of what the cut left is kept (lostShare,
// exact by inclusion-exclusion), and the pass's next step takes the planes' air at the rest of
// its cut instead of scaling: the re-skim +0.007 %, that line +0.03 %, no move of data/gcode/thin
// worse by more than 0.02 % at D/10 to D/40. Tried: refusing only the pairs that put an old
// plane in place of the outer one (the two floors within the face still dropped the wall: the
// re-skim -0.14 to -0.19 %), the next step's min(fraction, rest) also where the planes lack
// material (a 0.2 mm ramp from the face +0.21 -> +0.57 %), the lossless pair only within 1 %
// of the share left (else the pair holding no air, as before: the re-skims -0.1 to -0.14 %),
// and the same choice across a flat bottom's rim in a voxel of one or two planes (where a
// skim enters through the stock's side face: the first pass +0.1 % instead of -0.005 %; the
// entry's voxel there, face, side face, floor and the pass's front, still takes a tenth of a
// voxel too much on the second pass).

#include "stock/VoxelStock.h"

#include "stock/DexelStock.h"

#include "cutters/Error.h"

#include "stock/AtomicFile.h"
#include "stock/CubeClip.h"
#include "stock/TriangleMesh.h"

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
#include <vector>

namespace engage {
namespace {

using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::FloatGrid;
using openvdb::Int32Grid;
using Leaf = FloatGrid::TreeType::LeafNodeType;
constexpr int kLeafDim = static_cast<int>(Leaf::DIM);  // 8
constexpr double kPi = 3.14159265358979323846;
/// Angular bins for the engagement angle (5 degrees each).
constexpr int kAngleBins = 72;

void initVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

/// OpenVDB's io::File writes through a stream it never checks after opening: on a full disk it
/// leaves a short file and reports nothing. The same seekable layout (Archive::write with grid
/// offsets, as io::File writes it) goes here through a stream of ours, checked after every
/// stage, into PATH.part, renamed into place when complete.
class CheckedArchive : public openvdb::io::Archive {
 public:
  void writeTo(std::ostream& os, const openvdb::GridPtrVec& grids) const {
    write(os, grids, /*seekable=*/true);
  }
};

void writeVdb(const std::string& path, const openvdb::GridPtrVec& grids) {
  writeFileAtomically(path, [&](std::ostream& os) { CheckedArchive().writeTo(os, grids); });
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// Physical memory of this machine, bytes.
double physicalMemory() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  double kb = 0.0;
  while (in >> key >> kb) {
    if (key == "MemTotal:") return kb * 1024.0;
    in.ignore(256, '\n');
  }
  return 8e9;
}

/// Refuse, before allocating, a grid whose voxels could not all be held: a fully cut stock
/// stores every voxel in leaves (4 bytes), the removed capture three more grids (12 bytes),
/// and each leaf a table of its voxels' planes (2 bytes per voxel, more for partial voxels).
double voxelCount(const Box3& box, double h) {
  const Eigen::Vector3d size = box.max - box.min;
  return (size.x() / h + 2) * (size.y() / h + 2) * (size.z() / h + 2);
}

void checkMemory(const Box3& box, double h) {
  if (!(std::isfinite(h) && h > 0.0))
    throw ParameterError("voxel size = " + num(h) + " mm must be positive");
  const double voxels = voxelCount(box, h);
  const double bytes = VoxelStock::memoryBound(box, h);
  const double limit = 0.75 * physicalMemory();
  if (bytes > limit)
    throw ParameterError("voxel size = " + num(h) + " mm makes " + num(voxels) +
                         " voxels for this stock, up to " + num(bytes / 1e9) +
                         " GB, more than this machine's " + num(limit / 1e9) +
                         " GB for it: choose a larger --voxel");
}

/// openvdb::tools::BoxSampler::sample(acc, q), trilinear in index space with the same
/// arithmetic, reading the eight values from one leaf's buffer where they lie in one leaf
/// (about 2 samples in 3): the accessor's eight lookups per sample, 576 samples per step for
/// the engagement angle, took 8 % of a finishing raster's instructions; this saves 1.2 % of
/// them (14.63 -> 14.45 billion at 0.2 mm), with the same values.
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
  double sMin = 1e300, sMax = -1e300;
  long changed = 0;
  long visited = 0;
  std::vector<std::pair<Coord, float>> lost;  ///< per changed voxel, when capturing
};

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
/// Share of a voxel a step must take for the voxel to count in the step's width and depth.
constexpr double kEngagedShare = 0.01;

/// The planes of the partial voxels of one leaf: slot[offset] is 0 for none, else one more
/// than the index of the voxel's planes (no table until one voxel has planes). A voxel that
/// turns to air (never visited again) leaves its entry to the next voxel that needs one.
struct LeafPlanes {
  std::vector<std::uint16_t> slot;  ///< Leaf::SIZE entries once a voxel has planes
  std::vector<VoxelPlanes> planes;
  std::vector<std::uint16_t> unused;  ///< entries of voxels that turned to air, for reuse

  /// The voxel turned to air: its entry is free for another.
  void release(openvdb::Index offset) {
    if (slot.empty() || slot[offset] == 0) return;
    unused.push_back(slot[offset]);
    slot[offset] = 0;
  }

  int get(openvdb::Index offset, HalfSpace out[2], int made[2], double& held, bool& united,
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
  void set(openvdb::Index offset, const HalfSpace& first, int madeFirst, const HalfSpace& second,
           int madeSecond, double held, bool united = false, const HalfSpace& outer = HalfSpace{},
           int madeOuter = kStockFace) {
    if (slot.empty()) slot.assign(Leaf::SIZE, 0);
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

/// The key of the leaf holding voxel ijk (its coordinates divided by the leaf's 8, floored).
std::uint64_t leafKey(const Coord& origin) {
  auto part = [](int v) { return static_cast<std::uint64_t>(v >> 3) & 0x1FFFFFu; };
  return part(origin.x()) | part(origin.y()) << 21 | part(origin.z()) << 42;
}

/// The faces of box b that cross the voxel at p (size h) as its planes: the two that cut the
/// most (all but edge and corner voxels have one or two; a missing one keeps all).
void boxFaces(const Box3& b, const Eigen::Vector3d& p, double h, HalfSpace out[2]) {
  out[0] = out[1] = HalfSpace{};
  auto consider = [&](const HalfSpace& f) {  // keep the two with the least offset
    if (out[0].n.squaredNorm() == 0.0 || f.a < out[0].a) {
      out[1] = out[0];
      out[0] = f;
    } else if (out[1].n.squaredNorm() == 0.0 || f.a < out[1].a) {
      out[1] = f;
    }
  };
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(a);
    if (b.max[a] < p[a] + 0.5 * h) consider({e, (b.max[a] - p[a]) / h});
    if (b.min[a] > p[a] - 0.5 * h) consider({-e, (p[a] - b.min[a]) / h});
  }
}

/// The plane with outward normal n that leaves `share` of the unit cube inside: the share
/// grows with the offset; regula falsi (Illinois) to 1e-9 of the share.
HalfSpace planeLeaving(const Eigen::Vector3d& n, double share) {
  double lo = -0.5 * n.lpNorm<1>(), hi = -lo;
  double flo = -share, fhi = 1.0 - share;
  double a = 0.0;
  int side = 0;
  for (int i = 0; i < 60; ++i) {
    a = (lo * fhi - hi * flo) / (fhi - flo);
    const double f = cubeFraction(HalfSpace{n, a}) - share;
    if (std::abs(f) < 1e-9) break;
    if (f < 0.0) {
      lo = a;
      flo = f;
      if (side == -1) fhi /= 2.0;
      side = -1;
    } else {
      hi = a;
      fhi = f;
      if (side == 1) flo /= 2.0;
      side = 1;
    }
  }
  return HalfSpace{n, a};
}

/// Share of the cube inside the material of planes q (inside both, or with `united` inside
/// either, and inside `outer` if given) and inside all of `extra`; with `centroid`, that
/// part's centroid.
double materialShare(const HalfSpace q[2], bool united, const HalfSpace* extra, int count,
                     Eigen::Vector3d* centroid = nullptr, const HalfSpace* outer = nullptr) {
  std::array<HalfSpace, 9> all;        // (count <= 6)
  auto with = [&](int from, int to) {  // q[from .. to), outer and the extra planes
    int n = 0;
    for (int i = from; i < to; ++i)
      all[static_cast<std::size_t>(n++)] = q[i];
    if (outer && outer->n.squaredNorm() > 0.0) all[static_cast<std::size_t>(n++)] = *outer;
    for (int k = 0; k < count; ++k)
      all[static_cast<std::size_t>(n++)] = extra[k];
    return n;
  };
  if (!united) return cubeFraction(all.data(), with(0, 2), centroid);
  // Inclusion-exclusion: |A u B| = |A| + |B| - |A n B|, and the same for the moments.
  Eigen::Vector3d ca, cb, cab;
  const double va = cubeFraction(all.data(), with(0, 1), &ca);
  const double vb = cubeFraction(all.data(), with(1, 2), &cb);
  const double vab = cubeFraction(all.data(), with(0, 2), &cab);
  const double v = va + vb - vab;
  if (centroid)
    *centroid =
        v > 0.0 ? Eigen::Vector3d((va * ca + vb * cb - vab * cab) / v) : Eigen::Vector3d::Zero();
  return v;
}

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

/// Share of the cube inside all `fixed` half-spaces and, for each clause, inside either of its
/// two sides (a side: inside all of its one or two half-spaces), by inclusion-exclusion clause
/// by clause: |X n (A u B)| = |X n A| + |X n B| - |X n A n B|.
struct Side {
  HalfSpace p[2];
  int n = 1;
};
struct Clause {
  Side a, b;
};
double clausesShare(std::array<HalfSpace, 9>& fixed, int n, const Clause* clauses, int count) {
  if (count == 0) return cubeFraction(fixed.data(), n);
  auto with = [&](const Side& x, const Side* y) {
    int m = n;
    for (int k = 0; k < x.n; ++k)
      fixed[static_cast<std::size_t>(m++)] = x.p[k];
    for (int k = 0; y && k < y->n; ++k)
      fixed[static_cast<std::size_t>(m++)] = y->p[k];
    return clausesShare(fixed, m, clauses + 1, count - 1);
  };
  return with(clauses[0].a, nullptr) + with(clauses[0].b, nullptr) -
         with(clauses[0].a, &clauses[0].b);
}

/// Share of the cube that an inside corner `old` (united) keeps outside a cut (inside both of
/// its `faces` faces) and that `kept` does not hold: the material that keeping those planes
/// would lose. (At most eight planes in any term.)
double lostShare(const StoredMaterial& old, const HalfSpace cut[2], int faces,
                 const StoredMaterial& kept) {
  std::array<HalfSpace, 9> fixed;
  int n = 0;
  Clause clauses[3];
  int count = 0;
  fixed[static_cast<std::size_t>(n++)] = old.outer;
  clauses[count++] = Clause{Side{{old.q[0], {}}, 1}, Side{{old.q[1], {}}, 1}};
  if (faces == 2)
    clauses[count++] =
        Clause{Side{{cut[0].complement(), {}}, 1}, Side{{cut[1].complement(), {}}, 1}};
  else
    fixed[static_cast<std::size_t>(n++)] = cut[0].complement();
  const Side neither{{kept.q[0].complement(), kept.q[1].complement()}, 2};
  if (!kept.united)
    clauses[count++] =
        Clause{Side{{kept.q[0].complement(), {}}, 1}, Side{{kept.q[1].complement(), {}}, 1}};
  else if (kept.outer.n.squaredNorm() > 0.0)
    clauses[count++] = Clause{Side{{kept.outer.complement(), {}}, 1}, neither};
  else
    for (const HalfSpace& p : neither.p)
      fixed[static_cast<std::size_t>(n++)] = p;
  return clausesShare(fixed, n, clauses, count);
}

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
  void store(LeafPlanes& planes, openvdb::Index offset) const {
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
void keepRestOfCut(LeafPlanes& planes, openvdb::Index offset, const HalfSpace cut[2], int faces,
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

/// remaining() for a voxel whose material m is inside either of its planes (an inside
/// corner: the floor and wall a flat bottom's rim left), within its outer plane.
template <typename Kept>
double cutCorner(const Sweep& sweep, const Eigen::Vector3d& p, double h, double before,
                 LeafPlanes& planes, openvdb::Index offset, int serial, StoredMaterial& m,
                 const HalfSpace cut[2], int faces, double cutShare, Kept&& kept) {
  const HalfSpace* q = m.q;
  int* made = m.made;
  double& held = m.held;
  if (std::isnan(held)) held = materialShare(q, true, nullptr, 0, nullptr, &m.outer);
  const bool nested = made[0] >= serial - 1 || made[1] >= serial - 1;
  // Planes this pass left that hold more than the fraction kept some of the air its last step
  // cut (the pair that loses no material, below): what this step leaves within the outer plane
  // is the material, however far the two differ.
  const bool heldAir = nested && held > before;
  if (!(held > 0.0 && std::abs(held - before) <= kPlanesAgree) && !heldAir) {
    // The planes hold less than the fraction (a pass's front crossing the corner, the planes
    // already its rest, below): the fraction follows the cut's rest while the pass goes on,
    // so the planes stay this pass's.
    if (nested && held > 0.0 && held < before) {
      made[0] = made[1] = serial;
      planes.set(offset, q[0], made[0], q[1], made[1], held, true, m.outer, m.madeOuter);
    }
    return std::min(before, 1.0 - cutShare);
  }
  if (nested) {
    // The same pass's next step: nested, as for one plane (see remaining()).
    double restShare = 1.0 - cutShare;
    if (m.outer.n.squaredNorm() > 0.0) {
      const HalfSpace rest[2] = {cut[0].complement(), cut[1].complement()};
      const HalfSpace restOne[2] = {m.outer, kept()};
      restShare = faces == 2 ? materialShare(rest, true, nullptr, 0, nullptr, &m.outer)
                             : cubeFraction(restOne, 2);
    }
    if (restShare >= held - kNoise) {
      made[0] = made[1] = serial;
      planes.set(offset, q[0], made[0], q[1], made[1], held, true, m.outer, m.madeOuter);
      return std::min(before, restShare);
    }
    keepRestOfCut(planes, offset, cut, faces, kept, serial, restShare, m.outer, m.madeOuter);
    // (Scaled by the fraction over what the planes hold where they hold less: they lack
    // material the fraction still counts. Where they hold air, scaling took the air's share a
    // second time from the material.)
    return heldAir ? std::min(before, restShare) : before * restShare / held;
  }
  // Another pass across the corner: what the cut takes of floor or wall, exactly.
  Eigen::Vector3d centroid;
  const double taken = materialShare(q, true, cut, faces, &centroid, &m.outer);
  if (!(taken > kNoise)) return before;
  if (sweep.signedDistance(p + h * centroid) > 0.0) return before;  // a tangent-plane gap
  const double left = held - taken;
  // What is left is floor or wall, less the cut: as the corner of one old plane and one of
  // the cut's faces, the pair whose share is nearest, within the outer plane; or the cut's
  // own rest (its face, or its corner) within the outer plane, or its corner within one old
  // plane. (Without the face alone, a wall cut back past a corner's floor and wall kept a
  // plane it had cut away: a side skim past an earlier one's rim +0.2 %.)
  NearestPair best(left);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < faces; ++j)
      best.offer(q[i], made[i], cut[j].complement(), serial, true, m.outer, m.madeOuter);
  if (faces == 1) best.offer(m.outer, m.madeOuter, cut[0].complement(), serial, false);
  if (faces == 2) {
    best.offer(cut[0].complement(), serial, cut[1].complement(), serial, true, m.outer,
               m.madeOuter);
    for (int i = 0; i < 2; ++i)
      best.offer(cut[0].complement(), serial, cut[1].complement(), serial, true, q[i], made[i]);
  }
  // Of those, the nearest that holds all the material the cut left: a pair that drops some
  // (the old wall the rim ran along, when a pass skims again a floor it cut into a face) loses
  // it for good, as what this pass's later steps leave is taken within the pair's planes (see
  // the file's header).
  const bool keepsAll = best.keepingAll(
      [&](const StoredMaterial& pair) { return lostShare(m, cut, faces, pair); }, kLostNoise);
  if (faces == 2 && !keepsAll && !best.within(kPairNear)) {
    // No pair holds what is left: the front of a deeper pass crossing floor and wall leaves
    // four planes' material for a step (the old wall and floor less the new floor behind the
    // front). Keep the pair that holds none of the air, the old plane the cut misses with
    // the cut's face that has only old material below it (the corner once the front has
    // passed): the fraction follows the cut's rest until then (above). The nearest pair
    // (the two floors) had dropped the wall, which the next pass cut into again: the slot
    // re-cut 0.1 mm deeper at 23.2 deg +0.6 %, now -0.06 %.
    NearestPair inside(left);
    for (int i = 0; i < 2; ++i) {
      const HalfSpace meets[4] = {q[i], cut[0], cut[1], m.outer};
      if (cubeFraction(meets, 4) > kNoise) continue;  // the cut takes some of q[i]'s side
      for (int j = 0; j < 2; ++j) {
        const HalfSpace face = cut[j].complement(), below[2] = {m.outer, face};
        if (cubeFraction(below, 2) - materialShare(q, true, &face, 1, nullptr, &m.outer) > kNoise)
          continue;  // air below the face
        inside.offer(q[i], made[i], face, serial, true, m.outer, m.madeOuter);
      }
    }
    if (inside.any()) {
      inside.store(planes, offset);
      return before * std::max(0.0, left) / held;
    }
  }
  best.store(planes, offset);
  return before * std::max(0.0, left) / held;
}

/// The half-space {x : n . (x - p) + distance <= 0} of Sweep::localFaces (world units about
/// the voxel's centre p) in the voxel's unit-cube coordinates (voxel size h); a zero normal
/// stays zero.
HalfSpace voxelPlane(const Eigen::Vector3d& n, double distance, double h) {
  const double norm = n.norm();
  return HalfSpace{norm > 0.0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero(), -distance / h};
}

/// The stored material of the voxel at p (size h) that holds `before`: its planes, or for a
/// voxel of the stock box's shell not cut before, the box's faces. False for a voxel all
/// material (or, from dexels, a fraction without planes).
bool storedMaterial(const LeafPlanes& planes, openvdb::Index offset, double before, const Box3* box,
                    const Eigen::Vector3d& p, double h, StoredMaterial& m) {
  if (!(before < 1.0)) return false;
  if (planes.get(offset, m.q, m.made, m.held, m.united, &m.outer, &m.madeOuter) != 0) return true;
  if (!box) return false;
  boxFaces(*box, p, h, m.q);
  return true;
}

/// The swept distance at a voxel corner (mm) and its unit gradient there (zero inside the
/// solid, or where the distance has none this far out): central differences of the swept
/// distance itself, which outside a convex solid is smooth and points from the surface's
/// closest point (the closest instance's own gradient, found to 2 % of the step, can be its
/// flat bottom's where the surface is the rim's envelope).
struct CornerProbe {
  double d = 0.0;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
};

/// The probe of corner `corner` (its index: the corner at (corner - 1/2) h, the low corner of
/// the voxel of that index) for the removal numbered `sweepId`. A corner is shared by up to
/// eight voxels of the rim: each thread keeps this removal's probes (the same numbers
/// whichever voxel or thread asks first: the corner's position is computed from its index).
const CornerProbe& probeCorner(const Sweep& sweep, const Coord& corner, double h,
                               std::uint64_t sweepId) {
  struct Cache {
    std::uint64_t id = 0;
    std::unordered_map<std::uint64_t, CornerProbe> probes;
  };
  static thread_local Cache cache;
  if (cache.id != sweepId) {
    cache.id = sweepId;
    cache.probes.clear();
  }
  auto field = [](int v) {
    return static_cast<std::uint64_t>(static_cast<std::uint32_t>(v) & 0x1fffffu);
  };
  const std::uint64_t key = field(corner.x()) << 42 | field(corner.y()) << 21 | field(corner.z());
  auto [it, added] = cache.probes.try_emplace(key);
  if (!added) return it->second;
  CornerProbe& probe = it->second;
  const Eigen::Vector3d x((corner.x() - 0.5) * h, (corner.y() - 0.5) * h, (corner.z() - 0.5) * h);
  probe.d = sweep.signedDistance(x);
  if (probe.d <= 0.0) return probe;
  const double e = h / 8.0;
  const Eigen::Vector3d g(sweep.signedDistance(x + Eigen::Vector3d(e, 0, 0)) -
                              sweep.signedDistance(x - Eigen::Vector3d(e, 0, 0)),
                          sweep.signedDistance(x + Eigen::Vector3d(0, e, 0)) -
                              sweep.signedDistance(x - Eigen::Vector3d(0, e, 0)),
                          sweep.signedDistance(x + Eigen::Vector3d(0, 0, e)) -
                              sweep.signedDistance(x - Eigen::Vector3d(0, 0, e)));
  const double gn = g.norm();
  if (gn > 0.0) probe.n = g / gn;
  return probe;
}

/// remaining() near the rim of a flat bottom on a step that changes height, where the swept
/// solid has an edge along the envelope that no pair of planes follows (Sweep::localFaces
/// says so). A straight step's swept solid is convex: the cut is the intersection of its
/// supporting planes normal to the swept distance's gradient at the voxel's corners outside
/// it, the six that cut most; the voxel keeps the pair of planes (an old one and a face of
/// the cut, or the cut's inside corner) nearest what is left. Other steps (helix pieces): the
/// voxel is split into 4 x 4 x 4 sub-cubes, each with the plane of the signed
/// distance at its centre, and the cut takes, sub-cube by sub-cube, the material inside it
/// (of a partial voxel, the material its planes hold). (One plane for the voxel left a 5 deg
/// ramp's worst step 1.85 % off and a helical bore's 2.2 %; 2 x 2 x 2 sub-cubes 0.72 % and
/// 0.78 %; 4 x 4 x 4 0.43 % and 0.45 %, at 2.6 times the cost of 2 x 2 x 2 on a helix. Taking
/// the sub-cubes' share by the rule for one plane, nested in the last step's when that step
/// made the voxel's plane, took nothing where each step's rim, behind a descending flat end
/// mill, dips below the last step's floor across a corner of the voxel: a ramp's floor kept
/// 0.03 of a voxel too much, its worst step 0.57 % off for some placements on the grid at
/// D / h = 20, now 0.37 %; 3 x 3 x 3 sub-cubes would make a helix's steps 1.8 times as fast
/// but leave that ramp 0.62 % off.) The voxel keeps the plane normal to the centre's gradient `n`
/// that leaves its share, and the old plane that goes with it best. Out of line: its
/// sub-cubes' planes would weigh on the common path's frame.
[[gnu::noinline]] double rimRemaining(const Sweep& sweep, const Eigen::Vector3d& p, double h,
                                      double before, LeafPlanes& planes, openvdb::Index offset,
                                      int serial, const Box3* box, const Eigen::Vector3d& n,
                                      double d, std::uint64_t sweepId) {
  constexpr int kSide = 4, kCount = kSide * kSide * kSide;
  auto centre = [&](int c) {  // of sub-cube c, in voxel sizes from the voxel's centre
    return Eigen::Vector3d((c / (kSide * kSide) + 0.5) / kSide - 0.5,
                           (c / kSide % kSide + 0.5) / kSide - 0.5,
                           (c % kSide + 0.5) / kSide - 0.5);
  };
  std::array<HalfSpace, kCount> sub;  // in each sub-cube's own unit-cube coordinates
  // A convex swept solid (a straight step): its supporting planes normal to the gradients of
  // its distance at the voxel's corners outside it, at most six, the most cutting first.
  std::array<HalfSpace, 8> hull;
  int hullPlanes = 0;
  bool sampled = !sweep.convexLine();
  double cutShare = 0.0;
  if (!sampled) {
    int inside = 0;
    std::array<std::pair<double, HalfSpace>, 8> found;
    const Coord voxel(static_cast<int>(std::lround(p.x() / h)),
                      static_cast<int>(std::lround(p.y() / h)),
                      static_cast<int>(std::lround(p.z() / h)));
    for (int c = 0; c < 8; ++c) {
      const CornerProbe& probe =
          probeCorner(sweep, voxel + Coord(c & 1, (c >> 1) & 1, (c >> 2) & 1), h, sweepId);
      if (probe.d <= 0.0) {
        ++inside;
        continue;
      }
      if (probe.n.squaredNorm() == 0.0) {  // (no gradient this far out: sample instead)
        sampled = true;
        break;
      }
      // The plane normal to the gradient that touches the swept solid, exactly (support()):
      // the closest instance is found to 2 % of the step, and its own tangent plane can cut
      // into the instances beside it.
      const Eigen::Vector3d& un = probe.n;
      const HalfSpace plane{un, (sweep.support(un) - un.dot(p)) / h};
      const double share = cubeFraction(plane);
      if (share >= 1.0 - kNoise) continue;  // keeps the whole cube
      found[static_cast<std::size_t>(hullPlanes++)] = {share, plane};
    }
    if (inside == 8) return 0.0;  // the cube is inside the convex solid
    if (!sampled) {
      for (int k = 1; k < hullPlanes; ++k)  // (insertion sort: at most eight)
        for (int j = k; j > 0 && found[static_cast<std::size_t>(j)].first <
                                     found[static_cast<std::size_t>(j - 1)].first;
             --j)
          std::swap(found[static_cast<std::size_t>(j)], found[static_cast<std::size_t>(j - 1)]);
      // The wedge (the first two) of two faces: the most cutting plane and the most cutting
      // one at 15 deg or more to it (corners under a flat bottom give its plane several times:
      // a wedge of two floors kept no wall, and a ramp's front cut from the top face took
      // +1.3 %).
      int first = 0, widest = 0;  // the most cutting and the widest at 15 deg or more
      double leastCos = kNestedCos;
      for (int k = 1; k < hullPlanes; ++k) {
        const double cos = found[static_cast<std::size_t>(k)].second.n.dot(found[0].second.n);
        if (cos >= kNestedCos) continue;
        if (first == 0) first = k;
        if (cos < leastCos) leastCos = cos, widest = k;
      }
      int second = first;
      if (widest != first) {
        auto pairShare = [&](int k) {
          const HalfSpace pair[2] = {found[0].second, found[static_cast<std::size_t>(k)].second};
          return cubeFraction(pair, 2);
        };
        if (pairShare(widest) < pairShare(first)) second = widest;
      }
      for (int j = second; j > 1; --j)
        std::swap(found[static_cast<std::size_t>(j)], found[static_cast<std::size_t>(j - 1)]);
      hullPlanes = std::min(hullPlanes, 6);
      for (int k = 0; k < hullPlanes; ++k)
        hull[static_cast<std::size_t>(k)] = found[static_cast<std::size_t>(k)].second;
      sampled = hullPlanes == 0;
      if (!sampled) cutShare = cubeFraction(hull.data(), hullPlanes);
    }
  }
  if (sampled) {
    cutShare = 0.0;
    for (int c = 0; c < kCount; ++c) {
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      const double dk = sweep.signedDistance(p + h * centre(c), &g);
      const double gn = g.norm();
      sub[c] =
          HalfSpace{gn > 0.0 ? Eigen::Vector3d(g / gn) : Eigen::Vector3d::Zero(), -dk * kSide / h};
      cutShare += cubeFraction(sub[c]) / kCount;
    }
  }
  if (cutShare <= kNoise) return before;
  if (cutShare >= 1.0 - kNoise) return 0.0;
  const HalfSpace centrePlane = voxelPlane(n, d, h);
  std::optional<HalfSpace> keptPlane;
  auto kept = [&]() -> const HalfSpace& {
    if (!keptPlane) keptPlane = planeLeaving(-centrePlane.n, 1.0 - cutShare);
    return *keptPlane;
  };
  // The convex cut's two most cutting planes: a wedge whose inside corner the voxel can keep.
  const int wedge = sampled ? 0 : std::min(hullPlanes, 2);
  StoredMaterial m;
  if (!storedMaterial(planes, offset, before, box, p, h, m)) {  // all material
    const double after = std::min(before, 1.0 - cutShare);
    if (after > 0.0 && after < before) {
      if (wedge == 2)
        keepRestOfCut(planes, offset, hull.data(), 2, kept, serial, 1.0 - cutShare);
      else
        keepRestOfCut(planes, offset, &centrePlane, 1, kept, serial, 1.0 - cutShare);
    }
    return after;
  }
  if (std::isnan(m.held)) m.held = materialShare(m.q, m.united, nullptr, 0, nullptr, &m.outer);
  if (!(m.held > 0.0 && std::abs(m.held - before) <= kPlanesAgree))
    return std::min(before, 1.0 - cutShare);
  double taken = 0.0;
  if (!sampled) taken = materialShare(m.q, m.united, hull.data(), hullPlanes, nullptr, &m.outer);
  for (int c = 0; c < kCount && sampled; ++c) {
    auto local = [&](const HalfSpace& q) {  // a stored plane in sub-cube c's coordinates
      return q.n.squaredNorm() == 0.0 ? q : HalfSpace{q.n, kSide * (q.a - q.n.dot(centre(c)))};
    };
    const HalfSpace q[2] = {local(m.q[0]), local(m.q[1])}, outer = local(m.outer);
    taken += materialShare(q, m.united, &sub[c], 1, nullptr, &outer) / kCount;
  }
  if (!(taken > kNoise)) return before;
  const double left = std::max(0.0, m.held - taken);
  // Keep the pair of planes whose material's share is nearest what is left: an old plane and
  // the plane leaving the cut's share, an old plane and a face of a convex cut's wedge, or the
  // wedge's own inside corner, alone or within an old plane (a thin cut into a face leaves
  // face, floor and wall), or with an inside corner stored, its corner with a face of the
  // wedge within its outer plane.
  NearestPair best(left);
  for (int i = 0; i < 2; ++i) {
    if (m.q[i].n.squaredNorm() == 0.0) continue;
    best.offer(m.q[i], m.made[i], kept(), serial, false);
    for (int j = 0; j < wedge; ++j)
      best.offer(m.q[i], m.made[i], hull[static_cast<std::size_t>(j)].complement(), serial, false);
  }
  if (wedge == 2) {
    const HalfSpace rest[2] = {hull[0].complement(), hull[1].complement()};
    best.offer(rest[0], serial, rest[1], serial, true);
    if (m.united && m.outer.n.squaredNorm() > 0.0) {
      // (Offered without an outer plane too, they made flower_mold's voxel loop 3-6 % longer
      // and the thin cuts no better: D/20's worst move 0.66 % against 0.60 %.)
      best.offer(rest[0], serial, rest[1], serial, true, m.outer, m.madeOuter);
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
          best.offer(m.q[i], m.made[i], rest[j], serial, true, m.outer, m.madeOuter);
    }
    for (int i = 0; i < 2 && !m.united; ++i)
      if (m.q[i].n.squaredNorm() > 0.0)
        best.offer(rest[0], serial, rest[1], serial, true, m.q[i], m.made[i]);
  }
  if (best.any())
    best.store(planes, offset);
  else
    planes.set(offset, HalfSpace{}, kStockFace, kept(), serial, 1.0 - cutShare);
  return before * left / m.held;
}

/// The material fraction left in the voxel at p (size h) that held `before` once the swept
/// solid is removed; updates the voxel's planes. `serial` numbers this removal.
///
/// The swept solid in the voxel is the half-space of the tangent plane of its signed
/// distance, or near a sharp edge of the cutter (a flat bottom's rim) the wedge between the
/// two faces (Sweep::localFaces), and it takes its exact share of the material (polyhedral
/// clipping, stock/CubeClip.h); near a flat bottom's rim on a step that changes height,
/// sub-cube by sub-cube (rimRemaining()). A voxel that is all material keeps the rest and, as one
/// plane, the cut's boundary. A partial voxel holds the material between up to two earlier
/// planes (a stock face, the previous pass's wall, the last cut): the cut takes the share of
/// that material inside it, and the voxel keeps the cut's plane and the earlier plane that
/// bounds the rest more tightly. Where two surfaces cross one voxel (the front of a side cut
/// meeting the previous pass's wall, a helix turn meeting the last turn's floor) a fraction
/// alone cannot say how much of the material the cut reaches: min(before, 1 - cut) assumed
/// all or none of it, which cost 0.8 % per step on a side cut and 2 % on a helix at
/// D / h = 20 (see the README's table).
double remaining(const Sweep& sweep, const Eigen::Vector3d& p, double h, double before,
                 LeafPlanes& planes, openvdb::Index offset, int serial, const Box3* box,
                 std::uint64_t sweepId) {
  constexpr double kHalfDiagonal = 0.8660254037844386;  // sqrt(3) / 2
  Eigen::Vector3d n[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  double dist[2] = {0.0, 0.0};
  int faces = 1;
  Eigen::Matrix3d curvature;
  const double d = sweep.localFaces(p, kHalfDiagonal * h, n, dist, faces, &curvature);
  if (d >= kHalfDiagonal * h) return before;
  if (d <= -kHalfDiagonal * h) return 0.0;
  HalfSpace cut[2];  // the swept solid in the voxel: inside both (the second may keep all)
  if (faces == 0)
    return rimRemaining(sweep, p, h, before, planes, offset, serial, box, n[0], d, sweepId);
  for (int j = 0; j < faces; ++j)
    cut[j] = voxelPlane(n[j], dist[j], h);
  if (faces == 1 && cut[0].n.squaredNorm() > 0.0 && !curvature.isZero()) {
    // A curved surface leaves its tangent plane by the sagitta u^T K u / 2 (K its curvature,
    // Sweep::signedDistance): the plane moved by the sagitta's mean over its section of the
    // voxel holds the surface's share to second order. (The tangent plane alone took 0.73 %
    // too much on a ball's first plunge step at D / h = 20, its tip a sphere of 10 voxels'
    // radius entering fresh material; now 0.002 %. The mean over a unit square instead,
    // h trace(K) / 24, would save the section's cost, 8 % of the raster's instructions, but
    // is half the sagitta on a wall at 45 deg to the grid: a flat ramp's worst step 0.51 %
    // instead of 0.42 %.)
    cut[0].a -= std::clamp(0.5 * h * sectionMeanSquare(cut[0], curvature), -0.25, 0.25);
  }
  const double cutShare = cubeFraction(cut, 2);
  if (cutShare <= kNoise) return before;
  if (cutShare >= 1.0 - kNoise) return 0.0;
  // What the cut leaves, as one plane: the face's other side, or across a sharp edge the
  // plane normal to the faces' mean normal that leaves the same share.
  // Searched for only where used: a wedge that cuts a whole voxel keeps its two faces.
  std::optional<HalfSpace> keptPlane;
  auto kept = [&]() -> const HalfSpace& {
    if (!keptPlane)
      keptPlane = faces == 1 ? cut[0].complement()
                             : planeLeaving(-(cut[0].n + cut[1].n).normalized(), 1.0 - cutShare);
    return *keptPlane;
  };
  StoredMaterial stored;
  if (!storedMaterial(planes, offset, before, box, p, h, stored)) {  // all material
    const double after = std::min(before, 1.0 - cutShare);
    if (after > 0.0 && after < before)
      keepRestOfCut(planes, offset, cut, faces, kept, serial, 1.0 - cutShare);
    return after;
  }
  HalfSpace* q = stored.q;
  int* made = stored.made;
  double& held = stored.held;
  const bool united = stored.united;
  if (united)
    return cutCorner(sweep, p, h, before, planes, offset, serial, stored, cut, faces, cutShare,
                     kept);
  // The planes' share of the cube, clipped only where needed (NaN until then).
  auto heldKnown = [&] {
    if (std::isnan(held)) held = cubeFraction(q, 2);
    return held > 0.0 && std::abs(held - before) <= kPlanesAgree;
  };
  // A plane the last removal made or refreshed is this pass's surface, cut again by the
  // next step: nested, the smaller of the material it leaves and the material the new cut
  // leaves (as one plane each) is the material (the fraction rule, min(before, 1 - cut),
  // within the voxel's other plane). Clipping by both would take, every step, the sliver
  // between two tangent planes of one convex swept surface (measured: +0.1 % per step on a
  // ball side cut, +0.5 % with a flat one).
  for (int i = 0; i < 2; ++i) {
    if (!(made[i] >= serial - 1) || q[i].n.squaredNorm() == 0.0) continue;
    // (The new plane leaving no less of the cube than the stored one is the common case,
    // decided without clipping.)
    const bool deeper = 1.0 - cutShare < cubeFraction(q[i]) - kNoise;
    if (deeper && !heldKnown()) return std::min(before, 1.0 - cutShare);
    // (Across a flat bottom's rim, the wedge's own rest within the other plane: one plane
    // leaving its share cut a wall grazed above the rim at 45 deg.)
    const HalfSpace alt[2] = {q[1 - i], deeper && faces == 1 ? kept() : HalfSpace{}};
    const HalfSpace rest[2] = {cut[0].complement(), cut[1].complement()};
    const double other = !deeper      ? held
                         : faces == 1 ? cubeFraction(alt, 2)
                                      : materialShare(rest, true, nullptr, 0, nullptr, &q[1 - i]);
    if (deeper && other < held - kNoise) {
      if (faces == 1)
        planes.set(offset, q[1 - i], made[1 - i], kept(), serial, other);
      else
        planes.set(offset, rest[0], serial, rest[1], serial, other, true, q[1 - i], made[1 - i]);
      return before * other / held;
    }
    made[i] = serial;
    planes.set(offset, q[0], made[0], q[1], made[1], held);
    return before;
  }
  // A face of the cut within 15 deg of a stored plane is that surface cut again (a finishing
  // pass over a floor): where the stored plane bounds the material more tightly the cut
  // (inside the face) takes nothing, else the face replaces it.
  HalfSpace m[2] = {q[0], q[1]};
  for (int i = 0; i < 2; ++i) {
    if (q[i].n.squaredNorm() == 0.0) continue;  // the keep-all half-space
    for (int j = 0; j < faces; ++j) {
      if (!(-cut[j].n.dot(q[i].n) > kNestedCos)) continue;
      const HalfSpace alt[2] = {q[1 - i], cut[j].complement()};
      if (cubeFraction(cut[j].complement()) >= cubeFraction(q[i]) - kNoise) return before;
      if (!heldKnown()) return std::min(before, 1.0 - cutShare);
      if (cubeFraction(alt, 2) >= held - kNoise) return before;
      if (faces == 1) m[i] = HalfSpace{};  // (a wedge's rest is kept within the plane)
      break;
    }
  }
  if (!heldKnown()) return std::min(before, 1.0 - cutShare);
  const HalfSpace all[4] = {m[0], m[1], cut[0], cut[1]};
  Eigen::Vector3d centroid;
  const bool dropped =
      m[0].n.squaredNorm() != q[0].n.squaredNorm() || m[1].n.squaredNorm() != q[1].n.squaredNorm();
  const double left = (dropped ? cubeFraction(m, 2) : held) - cubeFraction(all, 4, &centroid);
  if (!(left < held - kNoise)) return before;
  // What the planes take must lie in the swept solid: a piece outside it is the gap between
  // two planes tangent to one convex surface (the tool's cylinder at the end of a pass, met
  // again by the retract, against the wall an earlier step left), not material cut.
  if (sweep.signedDistance(p + h * centroid) > 0.0) return before;
  if (faces == 2) {
    // Across a flat bottom's rim: what is left is the old material less a wedge. Keep the
    // two planes whose material's share is nearest: an old plane and one face of the cut
    // (a floor the rim ran along), or the wedge's own inside corner, alone or within an old
    // plane (a thin cut into a face leaves face, floor and wall).
    NearestPair best(left);
    best.offer(cut[0].complement(), serial, cut[1].complement(), serial, true);
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2 && m[i].n.squaredNorm() > 0.0; ++j)
        best.offer(m[i], made[i], cut[j].complement(), serial, false);
    best.offer(m[0], made[0], m[1], made[1], false);
    for (int i = 0; i < 2; ++i)
      if (m[i].n.squaredNorm() > 0.0)
        best.offer(cut[0].complement(), serial, cut[1].complement(), serial, true, m[i], made[i]);
    best.store(planes, offset);
    return before * std::max(0.0, left) / held;
  }
  // Keep the cut's plane and the earlier plane that bounds the rest more tightly (by
  // each pair's share: choosing by each plane alone dropped a wall that a later pass met
  // again, and that pass cut into it).
  const HalfSpace first[2] = {m[0], kept()}, second[2] = {m[1], kept()};
  const double with0 = m[0].n.squaredNorm() > 0.0 ? cubeFraction(first, 2) : 2.0;
  const double with1 = m[1].n.squaredNorm() > 0.0 ? cubeFraction(second, 2) : 2.0;
  const int keep = with0 <= with1 ? 0 : 1;
  planes.set(offset, m[keep], made[keep], kept(), serial,
             std::min(with0, with1) <= 1.0 ? std::min(with0, with1) : 1.0 - cutShare);
  // The planes' material and the fraction can differ (a third surface, curvature): the
  // planes' share applies to the fraction.
  return before * std::max(0.0, left) / held;
}

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

namespace {

/// The 0.5 iso-surface of a fraction grid as a triangle mesh with outward normals; OpenVDB's
/// `adaptivity` (0: none) merges cells where the surface is nearly flat.
TriangleMesh isoSurface(const FloatGrid& grid, double adaptivity) {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(grid, points, triangles, quads, 0.5, adaptivity);
  for (const auto& q : quads) {
    triangles.emplace_back(q[0], q[1], q[2]);
    triangles.emplace_back(q[0], q[2], q[3]);
  }
  // Orientation: a closed mesh with outward normals has positive signed volume.
  double signedVolume = 0.0;
  for (const auto& t : triangles) {
    const openvdb::Vec3d a = points[t[0]], b = points[t[1]], c = points[t[2]];
    signedVolume += a.dot(b.cross(c)) / 6.0;
  }
  const bool flip = signedVolume < 0.0;
  TriangleMesh mesh;
  mesh.points.reserve(points.size());
  for (const auto& p : points)
    mesh.points.push_back({p[0], p[1], p[2]});
  mesh.triangles.reserve(triangles.size());
  for (const auto& t : triangles)
    mesh.triangles.push_back(flip ? std::array<unsigned, 3>{t[0], t[2], t[1]}
                                  : std::array<unsigned, 3>{t[0], t[1], t[2]});
  return mesh;
}

}  // namespace

struct VoxelStock::Impl {
  double h = 1.0;
  FloatGrid::Ptr grid;
  bool capture = false;
  FloatGrid::Ptr removed;
  Int32Grid::Ptr step;
  FloatGrid::Ptr mrr;
  /// Planes of the partial voxels, per leaf (by leafKey of its origin).
  std::unordered_map<std::uint64_t, LeafPlanes> planes;
  /// The box the stock was made from, if it was: its shell voxels' planes are its faces.
  std::optional<Box3> box;
  /// Removals so far: the serial number of the planes a removal makes.
  int removals = 0;
  /// The fractions' 0.5 iso-surface as last meshed, after `surfaceAt` removals: stock.vdb's
  /// level set and stock.stl share it (meshing took 0.12 s of each on CAMotics' heart). Made
  /// once when the files are written side by side (a run's outputs, on several cores).
  std::shared_ptr<const TriangleMesh> surface;
  int surfaceAt = -1;
  std::mutex surfaceMutex;

  std::shared_ptr<const TriangleMesh> surfaceMesh() {
    const std::lock_guard<std::mutex> lock(surfaceMutex);
    if (!surface || surfaceAt != removals) {
      surface = std::make_shared<const TriangleMesh>(isoSurface(*grid, 0.0));
      surfaceAt = removals;
    }
    return surface;
  }

  Coord index(const Eigen::Vector3d& p) const {
    return Coord(static_cast<int>(std::floor(p.x() / h + 0.5)),
                 static_cast<int>(std::floor(p.y() / h + 0.5)),
                 static_cast<int>(std::floor(p.z() / h + 0.5)));
  }
};

VoxelStock::VoxelStock(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VoxelStock::VoxelStock(VoxelStock&&) noexcept = default;
VoxelStock& VoxelStock::operator=(VoxelStock&&) noexcept = default;
VoxelStock::~VoxelStock() = default;

namespace {

/// How a dexel stock's columns lie on voxel columns of the same spacing h: dexel column (i, j)
/// covers [x0 + i h, x0 + (i + 1) h] (and likewise in y), voxel c covers [(c - 1/2) h,
/// (c + 1/2) h], so each dexel column overlaps four voxel columns and each voxel column
/// (cx + a, cy + b) the dexel columns a - 1 .. a, b - 1 .. b.
struct ColumnFootprint {
  int cx = 0, cy = 0;         // the first voxel column of dexel column (0, 0); the others + 1
  double wx = 0.0, wy = 0.0;  // the share of a dexel column in its first voxel column's x (y)

  explicit ColumnFootprint(const DexelStock& d) {
    const double h = d.resolution();
    auto first = [&](double a0, int& c0, double& w0) {  // the voxels over [a0, a0 + h]
      c0 = static_cast<int>(std::floor(a0 / h + 0.5));
      w0 = ((c0 + 0.5) * h - a0) / h;
    };
    first(d.originX(), cx, wx);
    first(d.originY(), cy, wy);
  }
  /// The share of a dexel column in the voxel column (a, b) of its four, a and b 0 or 1.
  double share(int a, int b) const { return (a ? 1.0 - wx : wx) * (b ? 1.0 - wy : wy); }
  /// fn(i, j, share) for each dexel column of `d` that voxel column (cx + a, cy + b) overlaps,
  /// with the share of that dexel column in it, where it is above 0.
  template <typename Fn>
  void columnsOf(const DexelStock& d, int a, int b, Fn&& fn) const {
    for (int di = 0; di < 2; ++di)
      for (int dj = 0; dj < 2; ++dj) {
        const int i = a - di, j = b - dj;
        if (i < 0 || i >= d.raysX() || j < 0 || j >= d.raysY()) continue;
        const double s = share(di, dj);
        if (s > 0.0) fn(i, j, s);
      }
  }
};

}  // namespace

VoxelStock VoxelStock::fromDexels(const DexelStock& d) {
  initVdb();
  auto impl = std::make_unique<Impl>();
  const double h = d.resolution();
  impl->h = h;
  impl->grid = FloatGrid::create(0.0f);
  impl->grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
  impl->grid->setName("stock");
  impl->grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  // Each voxel gets the material of the columns it overlaps: volume share x the interval's
  // share x the column's weight. Voxel column by voxel column, its four dexel columns' material
  // per height summed in an array (as writeRemovedVdb merges their losses); the voxels below 1
  // written one by one, and the run of full ones each 8 x 8 block of voxel columns shares as
  // one box (tiles where it covers whole leaves), the rest of each run one by one. Each voxel
  // added into the grid from each of its columns one at a time (169 million reads and writes
  // for the finishing benchmark at 0.1 mm) took 1.08 of the run's 11.3 s.
  const ColumnFootprint corner(d);
  const int nx = d.raysX(), ny = d.raysY();
  const int ax = nx + 1, by = ny + 1;  // voxel columns (corner.cx + a, corner.cy + b)
  struct FullRun {
    int k0 = 1, k1 = 0;  // [k0, k1] all 1; empty when k0 > k1
  };
  std::vector<FullRun> full(static_cast<std::size_t>(ax) * static_cast<std::size_t>(by));
  auto acc = impl->grid->getAccessor();
  std::vector<double> merged;
  for (int b = 0; b < by; ++b)
    for (int a = 0; a < ax; ++a) {
      struct Part {
        int i, j;
        double share;
      } parts[4];
      int count = 0;
      int kLow = std::numeric_limits<int>::max(), kHigh = std::numeric_limits<int>::min();
      corner.columnsOf(d, a, b, [&](int i, int j, double inVoxel) {
        const double share = inVoxel * d.weight(i, j);
        const auto& ray = d.ray(i, j);
        if (!(share > 0.0) || ray.empty()) return;
        parts[count++] = {i, j, share};
        kLow = std::min(kLow, static_cast<int>(std::floor(ray.front().z0 / h + 0.5)));
        kHigh = std::max(kHigh, static_cast<int>(std::floor(ray.back().z1 / h + 0.5)));
      });
      if (count == 0) continue;
      merged.assign(static_cast<std::size_t>(kHigh - kLow + 1), 0.0);
      for (int p = 0; p < count; ++p)
        for (const DexelStock::Interval& iv : d.ray(parts[p].i, parts[p].j))
          DexelStock::voxelHeights(h, iv.z0, iv.z1, [&](int k, double z) {
            merged[static_cast<std::size_t>(k - kLow)] += z * iv.f * parts[p].share;
          });
      FullRun& run = full[static_cast<std::size_t>(b) * static_cast<std::size_t>(ax) +
                          static_cast<std::size_t>(a)];
      for (int k = kLow; k <= kHigh; ++k) {
        const auto v =
            static_cast<float>(std::min(1.0, merged[static_cast<std::size_t>(k - kLow)]));
        if (v == 1.0f && (run.k0 > run.k1 || run.k1 == k - 1)) {
          if (run.k0 > run.k1) run.k0 = k;
          run.k1 = k;  // (a column's first run of full voxels; later ones go one by one)
        } else if (v > 0.0f) {
          acc.setValue(Coord(corner.cx + a, corner.cy + b, k), v);
        }
      }
    }
  for (int b0 = 0; b0 < by; b0 += 8)
    for (int a0 = 0; a0 < ax; a0 += 8) {
      // The heights every column of the block is full at, as one box.
      int k0 = std::numeric_limits<int>::min(), k1 = std::numeric_limits<int>::max();
      for (int b = b0; b < std::min(by, b0 + 8); ++b)
        for (int a = a0; a < std::min(ax, a0 + 8); ++a) {
          const FullRun& run = full[static_cast<std::size_t>(b) * static_cast<std::size_t>(ax) +
                                    static_cast<std::size_t>(a)];
          k0 = std::max(k0, run.k0);
          k1 = std::min(k1, run.k1);
        }
      if (k0 <= k1)
        impl->grid->tree().fill(CoordBBox(Coord(corner.cx + a0, corner.cy + b0, k0),
                                          Coord(corner.cx + std::min(ax, a0 + 8) - 1,
                                                corner.cy + std::min(by, b0 + 8) - 1, k1)),
                                1.0f, true);
      acc.clear();  // (the box may have replaced nodes the accessor holds)
      for (int b = b0; b < std::min(by, b0 + 8); ++b)
        for (int a = a0; a < std::min(ax, a0 + 8); ++a) {
          const FullRun& run = full[static_cast<std::size_t>(b) * static_cast<std::size_t>(ax) +
                                    static_cast<std::size_t>(a)];
          for (int k = run.k0; k <= run.k1; ++k)
            if (k < k0 || k > k1) acc.setValue(Coord(corner.cx + a, corner.cy + b, k), 1.0f);
        }
    }
  impl->grid->tree().prune();
  return VoxelStock(std::move(impl));
}

void VoxelStock::writeRemovedVdb(const DexelStock& d, const std::string& path) {
  initVdb();
  const double h = d.resolution();
  auto make = [&](auto grid, const char* name) {
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setName(name);
    return grid;
  };
  FloatGrid::Ptr removed = make(FloatGrid::create(0.0f), "removed");
  removed->setGridClass(openvdb::GRID_FOG_VOLUME);
  Int32Grid::Ptr step = make(Int32Grid::create(-1), "step");
  FloatGrid::Ptr mrr = make(FloatGrid::create(0.0f), "mrr");
  auto racc = removed->getAccessor();
  auto sacc = step->getAccessor();
  auto macc = mrr->getAccessor();
  const std::vector<double>& stepMrr = d.stepMrr();
  // Each voxel column's four dexel columns' losses (per voxel height) merged, then its voxels
  // written, once each. Spread one entry of a per-step log at a time into the grids, cameo's
  // log had taken 0.82 s; summed per dexel column and each added into four voxels' grid
  // values, 0.56 s; merged, the whole run 0.1 s shorter (cameo 6.58 -> 6.48 s, bear 4.39 ->
  // 4.26 s, medians of three alternating runs, one core).
  struct Height {
    double removed = 0.0;
    int step = std::numeric_limits<int>::max();  // the first step to reach it
  };
  const ColumnFootprint corner(d);
  const int nx = d.raysX(), ny = d.raysY();
  std::vector<Height> merged;
  for (int b = 0; b <= ny; ++b)
    for (int a = 0; a <= nx; ++a) {
      struct Part {
        const DexelStock::LostColumn* column;
        double share;
      } parts[4];
      int count = 0;
      int kLow = std::numeric_limits<int>::max(), kHigh = std::numeric_limits<int>::min();
      corner.columnsOf(d, a, b, [&](int i, int j, double share) {
        const DexelStock::LostColumn* c = d.removedColumn(i, j);
        if (!c || c->cells.empty()) return;
        parts[count++] = {c, share};
        kHigh = std::max(kHigh, c->top);
        kLow = std::min(kLow, c->top - static_cast<int>(c->cells.size()) + 1);
      });
      if (count == 0) continue;
      merged.assign(static_cast<std::size_t>(kHigh - kLow + 1), Height{});
      for (int p = 0; p < count; ++p) {
        const DexelStock::LostColumn& c = *parts[p].column;
        for (std::size_t n = 0; n < c.cells.size(); ++n) {
          const DexelStock::Lost& from = c.cells[n];
          if (from.step < 0) continue;
          Height& to = merged[static_cast<std::size_t>(c.top - kLow) - n];
          to.removed += static_cast<double>(from.share) * parts[p].share;
          to.step = std::min(to.step, static_cast<int>(from.step));
        }
      }
      for (int k = kLow; k <= kHigh; ++k) {
        const Height& at = merged[static_cast<std::size_t>(k - kLow)];
        if (at.step == std::numeric_limits<int>::max()) continue;
        const Coord c(corner.cx + a, corner.cy + b, k);
        racc.setValue(c, static_cast<float>(std::min(1.0, at.removed)));
        sacc.setValue(c, at.step);
        const auto s = static_cast<std::size_t>(at.step);
        macc.setValue(c, static_cast<float>(s < stepMrr.size() ? stepMrr[s] : 0.0));
      }
    }
  writeVdb(path, openvdb::GridPtrVec{removed, step, mrr});
}

VoxelStock VoxelStock::box(const Box3& b, double h) {
  for (int a = 0; a < 3; ++a)
    if (!(b.max[a] > b.min[a]))
      throw ParameterError("stock box is empty along " +
                           std::string(1, static_cast<char>('X' + a)) + ": " + num(b.min[a]) +
                           " to " + num(b.max[a]) + " mm");
  checkMemory(b, h);
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

namespace {

/// The outward normal of the material at voxel c from its neighbours' fractions (central
/// differences), zero where they do not change.
Eigen::Vector3d fractionNormal(const FloatGrid::ConstAccessor& acc, const Coord& c) {
  Eigen::Vector3d g;
  for (int a = 0; a < 3; ++a) {
    Coord e(0);
    e[a] = 1;
    g[a] = static_cast<double>(acc.getValue(c - e)) - static_cast<double>(acc.getValue(c + e));
  }
  const double n = g.norm();
  return n > 1e-9 ? Eigen::Vector3d(g / n) : Eigen::Vector3d::Zero();
}

/// stock.vdb keeps each partial voxel's planes (so that a later run goes on from them as this
/// one would), in two Vec3s grids "planes_0" and "planes_1": a plane {u : n . u <= a} (u in
/// voxel sizes from the voxel's centre) as n (a + 2) (a lies within +-0.87 where a plane cuts
/// the cube), none as 0, and the first as n (a + 6) when the material is inside either plane
/// instead of both; a third, "planes_2", holds such a voxel's outer plane (0 where it has none).
openvdb::Vec3s encodePlane(const HalfSpace& q, bool united) {
  if (q.n.squaredNorm() == 0.0) return openvdb::Vec3s(0.0f);
  const double r = std::clamp(q.a, -1.9, 1.9) + (united ? 6.0 : 2.0);
  return openvdb::Vec3s(static_cast<float>(q.n.x() * r), static_cast<float>(q.n.y() * r),
                        static_cast<float>(q.n.z() * r));
}

HalfSpace decodePlane(const openvdb::Vec3s& v, bool* united = nullptr) {
  const double r = static_cast<double>(v.length());
  if (united) *united = r > 4.0;
  if (!(r > 0.5)) return HalfSpace{};
  const Eigen::Vector3d n(static_cast<double>(v.x()) / r, static_cast<double>(v.y()) / r,
                          static_cast<double>(v.z()) / r);
  return HalfSpace{n, r - (r > 4.0 ? 6.0 : 2.0)};
}

/// The grids of a stock.vdb that a run starts from.
struct StockFile {
  FloatGrid::Ptr fractions;
  /// The partial voxels' planes (both null for a file written without them), and their outer
  /// planes (null for a file written before they were kept).
  openvdb::Vec3SGrid::Ptr planes[3];
};

/// Grid "stock" of stock.vdb at `path`, checked: fractions 0 to 1 on a uniform grid whose
/// index axes are the world's (a translation allowed); and its planes, if it has them.
StockFile readStockGrid(const std::string& path) {
  initVdb();
  openvdb::Vec3SGrid::Ptr planes[3];
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw Error("cannot read stock '" + path +
                "': " + (std::filesystem::exists(path, ec) ? "not a file" : "no such file"));
  openvdb::GridBase::Ptr base;
  std::string names;
  try {
    openvdb::io::File file(path);
    file.open(false);
    for (auto it = file.beginName(); it != file.endName(); ++it)
      names += (names.empty() ? "" : ", ") + it.gridName();
    if (file.hasGrid("stock")) base = file.readGrid("stock");
    if (base && file.hasGrid("planes_0") && file.hasGrid("planes_1"))
      for (int i = 0; i < 3; ++i)
        if (i < 2 || file.hasGrid("planes_2"))
          planes[i] = openvdb::gridPtrCast<openvdb::Vec3SGrid>(
              file.readGrid("planes_" + std::to_string(i)));
    file.close();
  } catch (const openvdb::Exception& e) {
    throw Error("cannot read stock '" + path + "' as an OpenVDB file: " + e.what());
  }
  if (!base)
    throw ParameterError("stock '" + path +
                         "' has no grid named 'stock' (the material fractions an engage run "
                         "writes in stock.vdb); its grids: " +
                         (names.empty() ? std::string("none") : names));
  FloatGrid::Ptr grid = openvdb::gridPtrCast<FloatGrid>(base);
  if (!grid)
    throw ParameterError("grid 'stock' of '" + path + "' holds " + base->valueType() +
                         " values, not float material fractions");
  const openvdb::math::Transform& xf = grid->transform();
  const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0.0));
  const double h0 = xf.voxelSize()[0];
  bool axes = xf.isLinear() && std::isfinite(h0) && h0 > 0.0;
  for (int a = 0; a < 3 && axes; ++a) {
    openvdb::Vec3d e(0.0);
    e[a] = 1.0;
    const openvdb::Vec3d d = xf.indexToWorld(e) - o;
    for (int b = 0; b < 3; ++b)
      axes = axes && std::abs(d[b] - (a == b ? h0 : 0.0)) <= 1e-9 * h0;
  }
  if (!axes)
    throw ParameterError("grid 'stock' of '" + path +
                         "' is not on cubic voxels along the world's axes (rotated, sheared or "
                         "of unequal sizes)");
  if (std::abs(grid->background()) > 1e-6f)
    throw ParameterError("grid 'stock' of '" + path + "' has background " +
                         num(grid->background()) + ", not 0 (air): not material fractions");
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    const float v = *it;
    if (!(v >= -1e-6f && v <= 1.0f + 1e-6f)) {
      const Coord c = it.getCoord();
      throw ParameterError("grid 'stock' of '" + path + "' holds " + num(v) + " at voxel (" +
                           std::to_string(c.x()) + ", " + std::to_string(c.y()) + ", " +
                           std::to_string(c.z()) + "): not a material fraction (0 to 1)");
    }
  }
  StockFile f;
  f.fractions = grid;
  // Planes on another grid than the fractions' are not used.
  if (planes[0] && planes[1] && planes[0]->transform() == xf && planes[1]->transform() == xf) {
    f.planes[0] = planes[0];
    f.planes[1] = planes[1];
    if (planes[2] && planes[2]->transform() == xf) f.planes[2] = planes[2];
  }
  return f;
}

/// The accessors of a stock file's planes grids (none for a file without them; the outer
/// planes' only where the file has them).
std::vector<openvdb::Vec3SGrid::ConstAccessor> planeAccessors(const StockFile& file) {
  std::vector<openvdb::Vec3SGrid::ConstAccessor> out;
  for (int i = 0; i < 3 && file.planes[0]; ++i)
    if (file.planes[i]) out.push_back(file.planes[i]->getConstAccessor());
  return out;
}

/// The planes of voxel c of a stock file (`planes` its planeAccessors(), empty for none): from
/// its planes grids, q[2] the outer plane of united ones (else keep-all), else (a file without
/// them) the plane across the fractions' gradient that holds fraction m. Returns how many (0:
/// none).
int filePlanes(const FloatGrid::ConstAccessor& acc,
               const std::vector<openvdb::Vec3SGrid::ConstAccessor>& planes, const Coord& c,
               double m, HalfSpace q[3], bool& united) {
  united = false;
  q[2] = HalfSpace{};
  if (!planes.empty()) {
    q[0] = decodePlane(planes[0].getValue(c), &united);
    q[1] = decodePlane(planes[1].getValue(c));
    if (united && planes.size() > 2) q[2] = decodePlane(planes[2].getValue(c));
    if (q[0].n.squaredNorm() > 0.0 || q[1].n.squaredNorm() > 0.0) return 2;
  }
  const Eigen::Vector3d n = fractionNormal(acc, c);
  if (n.squaredNorm() == 0.0) return 0;
  q[0] = planeLeaving(n, m);
  q[1] = HalfSpace{};
  return 1;
}

/// Tiles of a value below 1 become voxels: the removal takes tiles for whole material.
void partialTilesToVoxels(FloatGrid& g) {
  std::vector<std::pair<CoordBBox, float>> tiles;
  for (auto it = g.cbeginValueOn(); it; ++it)
    if (!it.isVoxelValue() && *it < 1.0f) tiles.emplace_back(it.getBoundingBox(), *it);
  auto acc = g.getAccessor();
  for (const auto& [box, v] : tiles)
    for (auto c = box.begin(); c; ++c)
      acc.setValue(*c, v);
}

/// Voxel c of a stock file's shell of an axis-aligned box (a stock box's faces, edges and
/// corners that no cut touched): its material is a box at
/// one corner of the voxel, [lo, hi] in the voxel's unit cube, each axis's cover the fraction
/// m over that of its face neighbour on the material's side (1 along a face, where both
/// neighbours hold m), the other neighbour empty along each covered axis. False where the
/// fractions are not such a box (the covers' product not m): a cut's surface. Two planes
/// cannot hold a corner's three faces: the plane across the fractions' gradient (a file
/// without planes: a dexel run's) or two of the faces (a box's file) put up to half an old
/// voxel of a corner's material above the top face when resampled, where a finishing
/// program's first rapid from the stock's top corner then met it (0.014 mm^3 from a 0.3 mm
/// stock at 0.17 mm: a collision, exit 5).
bool shellBox(const FloatGrid::ConstAccessor& acc, const Coord& c, double m, double lo[3],
              double hi[3]) {
  double product = 1.0;
  for (int a = 0; a < 3; ++a) {
    Coord e(0, 0, 0);
    e[a] = 1;
    const double fm = static_cast<double>(acc.getValue(c - e));
    const double fp = static_cast<double>(acc.getValue(c + e));
    const double inner = std::max(fm, fp);
    if (!(inner > 0.0)) return false;
    const double cover = std::min(1.0, m / inner);
    if (cover < 1.0 - 1e-6 && std::min(fm, fp) != 0.0) return false;
    lo[a] = fp >= fm ? 0.5 - cover : -0.5;
    hi[a] = fp >= fm ? 0.5 : -0.5 + cover;
    product *= cover;
  }
  return std::abs(product - m) <= 1e-5 * m;
}

/// A fraction within this of 0 or 1 after resampling is taken as 0 or 1 (float sums of
/// shares), so regions of material stay tiles and are not partial voxels by rounding.
constexpr double kResampleSnap = 1e-6;

/// Whether `grid` has voxels of size h centred at multiples of h.
bool onGrid(const FloatGrid& grid, double h) {
  const double h0 = grid.transform().voxelSize()[0];
  const openvdb::Vec3d o = grid.transform().indexToWorld(openvdb::Vec3d(0.0));
  bool same = std::abs(h0 - h) <= 1e-9 * h;
  for (int a = 0; a < 3; ++a)
    same = same && std::abs(o[a]) <= 1e-9 * h;
  return same;
}

/// The fractions of the file's grid on voxels of size h centred at multiples of h: a copy
/// when the grid is already so, else resampled by overlap. Each old voxel gives each new voxel
/// it overlaps the material inside their common box: all of it for a voxel of material; for a
/// partial voxel the part inside its planes (filePlanes: the file's, else the plane across its
/// fractions' gradient), clipped exactly (CubeClip.h) and scaled to its fraction. So the
/// volume is kept, and a face between two old voxels stays there: spreading a partial voxel's
/// material evenly put a top face's half-full voxels' material above the face, where rapids
/// then met it.
FloatGrid::Ptr resampledFractions(const StockFile& file, double h) {
  const FloatGrid& grid = *file.fractions;
  const double h0 = grid.transform().voxelSize()[0];
  const openvdb::Vec3d o = grid.transform().indexToWorld(openvdb::Vec3d(0.0));
  auto make = [&] {
    FloatGrid::Ptr g = FloatGrid::create(0.0f);
    g->setTransform(openvdb::math::Transform::createLinearTransform(h));
    g->setName("stock");
    g->setGridClass(openvdb::GRID_FOG_VOLUME);
    return g;
  };
  const CoordBBox bb = grid.evalActiveVoxelBoundingBox();
  if (bb.empty()) return make();
  Box3 world;
  for (int a = 0; a < 3; ++a) {
    world.min[a] = o[a] + (bb.min()[a] - 0.5) * h0;
    world.max[a] = o[a] + (bb.max()[a] + 0.5) * h0;
  }
  checkMemory(world, h);
  if (onGrid(grid, h)) {
    FloatGrid::Ptr g = make();
    g->setTree(grid.tree().copy());
    partialTilesToVoxels(*g);
    return g;
  }
  // The new voxels over the old grid's bounds, dense (x fastest), summed in doubles.
  int lo[3], dim[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<int>(std::floor(world.min[a] / h + 0.5));
    dim[a] = static_cast<int>(std::floor(world.max[a] / h + 0.5)) - lo[a] + 1;
  }
  std::vector<double> sum(static_cast<std::size_t>(dim[0]) * static_cast<std::size_t>(dim[1]) *
                          static_cast<std::size_t>(dim[2]));
  const double scale = (h0 / h) * (h0 / h) * (h0 / h);  // an old voxel in new voxels
  // Layer by layer of new voxels (each summed by one thread, in one order: the same result for
  // any thread count), from the old voxels that overlap it.
  tbb::parallel_for(0, dim[2], [&](int layer) {
    auto acc = grid.getConstAccessor();
    const std::vector<openvdb::Vec3SGrid::ConstAccessor> planes = planeAccessors(file);
    const int z = lo[2] + layer;
    const int k0 =
        std::max(bb.min().z(), static_cast<int>(std::floor(((z - 0.5) * h - o[2]) / h0 + 0.5)));
    const int k1 =
        std::min(bb.max().z(), static_cast<int>(std::floor(((z + 0.5) * h - o[2]) / h0 + 0.5)));
    for (int k = k0; k <= k1; ++k)
      for (int j = bb.min().y(); j <= bb.max().y(); ++j)
        for (int i = bb.min().x(); i <= bb.max().x(); ++i) {
          const Coord c(i, j, k);
          const double m = static_cast<double>(acc.getValue(c));
          if (!(m > 0.0)) continue;
          const Eigen::Vector3d centre(o[0] + i * h0, o[1] + j * h0, o[2] + k * h0);
          // A partial voxel's material: inside its planes (both, or either when united, and
          // its outer one), scaled to its fraction (the planes hold it to within kPlanesAgree).
          HalfSpace q[3];
          bool united = false;
          const int count = m < 1.0 ? filePlanes(acc, planes, c, m, q, united) : 0;
          // A box's shell voxel is its box (its file planes, if any, two of a corner's three
          // faces).
          double boxLo[3], boxHi[3];
          const bool boxed = m < 1.0 && shellBox(acc, c, m, boxLo, boxHi);
          auto inside = [&](const HalfSpace* clip, int clips) {
            return materialShare(q, united, clip, clips, nullptr, &q[2]);
          };
          double factor = 0.0;
          if (count > 0) {
            const double held = inside(nullptr, 0);
            if (held > 0.0 && std::abs(held - m) <= kPlanesAgree) factor = m / held;
          }
          int first[2], last[2];
          for (int a = 0; a < 2; ++a) {
            first[a] = static_cast<int>(std::floor((centre[a] - 0.5 * h0) / h + 0.5));
            last[a] = static_cast<int>(std::floor((centre[a] + 0.5 * h0) / h + 0.5));
          }
          for (int y = first[1]; y <= last[1]; ++y)
            for (int x = first[0]; x <= last[0]; ++x) {
              const int n[3] = {x, y, z};
              // The new voxel's box in the old voxel's unit cube.
              double u0[3], u1[3], box = 1.0;
              for (int a = 0; a < 3; ++a) {
                u0[a] = std::max(-0.5, ((n[a] - 0.5) * h - centre[a]) / h0);
                u1[a] = std::min(0.5, ((n[a] + 0.5) * h - centre[a]) / h0);
                box *= std::max(0.0, u1[a] - u0[a]);
              }
              if (!(box > 0.0)) continue;
              double share = m * box;
              if (boxed) {
                double held = 1.0, part = 1.0;
                for (int a = 0; a < 3; ++a) {
                  held *= boxHi[a] - boxLo[a];
                  part *= std::max(0.0, std::min(u1[a], boxHi[a]) - std::max(u0[a], boxLo[a]));
                }
                share = part * m / held;
              } else if (factor > 0.0) {
                HalfSpace clip[6];
                int clips = 0;
                for (int a = 0; a < 3; ++a) {
                  const Eigen::Vector3d e = Eigen::Vector3d::Unit(a);
                  if (u0[a] > -0.5) clip[clips++] = HalfSpace{-e, -u0[a]};
                  if (u1[a] < 0.5) clip[clips++] = HalfSpace{e, u1[a]};
                }
                share = inside(clip, clips) * factor;
              }
              sum[(static_cast<std::size_t>(layer) * static_cast<std::size_t>(dim[1]) +
                   static_cast<std::size_t>(y - lo[1])) *
                      static_cast<std::size_t>(dim[0]) +
                  static_cast<std::size_t>(x - lo[0])] += share * scale;
            }
        }
  });
  FloatGrid::Ptr g = make();
  auto acc = g->getAccessor();
  for (int z = 0; z < dim[2]; ++z)
    for (int y = 0; y < dim[1]; ++y)
      for (int x = 0; x < dim[0]; ++x) {
        double v = sum[(static_cast<std::size_t>(z) * static_cast<std::size_t>(dim[1]) +
                        static_cast<std::size_t>(y)) *
                           static_cast<std::size_t>(dim[0]) +
                       static_cast<std::size_t>(x)];
        if (v < kResampleSnap) continue;
        if (v > 1.0 - kResampleSnap) v = 1.0;
        acc.setValue(Coord(lo[0] + x, lo[1] + y, lo[2] + z), static_cast<float>(v));
      }
  g->tree().prune();
  partialTilesToVoxels(*g);
  return g;
}

}  // namespace

VoxelStock VoxelStock::fromVdb(const std::string& path, double h) {
  const StockFile file = readStockGrid(path);
  auto impl = std::make_unique<Impl>();
  impl->h = h;
  impl->grid = resampledFractions(file, h);
  if (impl->grid->activeVoxelCount() == 0)
    throw ParameterError("stock '" + path + "' holds no material");
  // Each partial voxel: on the file's own grid, the planes the file keeps. Resampled, the
  // planes of the old partial voxel that overlaps it most, moved into its frame, where they
  // hold its fraction (to kPlanesAgree: a flat face stays flat across the new grid); else
  // the plane across the fractions' gradient that holds its fraction. (The gradient plane
  // alone, at the stock box's edges, put material above its top face, which a rapid from
  // the top then met.)
  const bool same = onGrid(*file.fractions, h);
  const std::vector<openvdb::Vec3SGrid::ConstAccessor> planes = planeAccessors(file);
  const FloatGrid::ConstAccessor oldAcc = file.fractions->getConstAccessor();
  const double h0 = file.fractions->transform().voxelSize()[0];
  const openvdb::Vec3d o = file.fractions->transform().indexToWorld(openvdb::Vec3d(0.0));
  auto acc = impl->grid->getConstAccessor();
  for (auto it = impl->grid->cbeginValueOn(); it; ++it) {
    const double m = static_cast<double>(*it);
    if (!it.isVoxelValue() || !(m < 1.0)) continue;
    const Coord c = it.getCoord();
    HalfSpace q[3];
    bool united = false;
    int count = 0;
    if (same) {
      count = filePlanes(acc, planes, c, m, q, united);
    } else {
      // The old partial voxel with the largest overlap.
      const Eigen::Vector3d centre(c.x() * h, c.y() * h, c.z() * h);
      Coord lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = static_cast<int>(std::floor((centre[a] - 0.5 * h - o[a]) / h0 + 0.5));
        hi[a] = static_cast<int>(std::floor((centre[a] + 0.5 * h - o[a]) / h0 + 0.5));
      }
      double best = 0.0;
      for (auto oc = CoordBBox(lo, hi).begin(); oc; ++oc) {
        const double mo = static_cast<double>(oldAcc.getValue(*oc));
        if (!(mo > 0.0 && mo < 1.0)) continue;
        const Eigen::Vector3d oldCentre(o[0] + (*oc).x() * h0, o[1] + (*oc).y() * h0,
                                        o[2] + (*oc).z() * h0);
        double overlap = 1.0;
        for (int a = 0; a < 3; ++a)
          overlap *= std::max(0.0, std::min(centre[a] + 0.5 * h, oldCentre[a] + 0.5 * h0) -
                                       std::max(centre[a] - 0.5 * h, oldCentre[a] - 0.5 * h0));
        if (!(overlap > best)) continue;
        HalfSpace oq[3];
        bool ou = false;
        if (filePlanes(oldAcc, planes, *oc, mo, oq, ou) == 0) continue;
        // n . (x - old centre) <= a h0, with x = centre + u h.
        HalfSpace moved[3];
        for (int i = 0; i < 3; ++i)
          moved[i] = oq[i].n.squaredNorm() == 0.0
                         ? oq[i]
                         : HalfSpace{oq[i].n, (oq[i].a * h0 - oq[i].n.dot(centre - oldCentre)) / h};
        const double held = materialShare(moved, ou, nullptr, 0, nullptr, &moved[2]);
        if (!(held > 0.0 && std::abs(held - m) <= kPlanesAgree)) continue;
        best = overlap;
        for (int i = 0; i < 3; ++i)
          q[i] = moved[i];
        united = ou;
        count = 2;
      }
      if (count == 0) count = filePlanes(acc, {}, c, m, q, united);
    }
    if (count == 0) continue;  // (the fraction rule for this one)
    impl->planes[leafKey(c)].set(Leaf::coordToOffset(c), q[0], kStockFace, q[1], kStockFace,
                                 std::numeric_limits<double>::quiet_NaN(), united,
                                 united ? q[2] : HalfSpace{});
  }
  return VoxelStock(std::move(impl));
}

DexelStock VoxelStock::dexelsFromVdb(const std::string& path, double h) {
  const FloatGrid::Ptr grid = resampledFractions(readStockGrid(path), h);
  const CoordBBox bb = grid->evalActiveVoxelBoundingBox();
  if (bb.empty()) throw ParameterError("stock '" + path + "' holds no material");
  const int nx = bb.dim().x(), ny = bb.dim().y();
  std::vector<std::vector<DexelStock::Interval>> rays(static_cast<std::size_t>(nx) *
                                                      static_cast<std::size_t>(ny));
  tbb::parallel_for(0, ny, [&](int j) {
    auto acc = grid->getConstAccessor();
    for (int i = 0; i < nx; ++i) {
      auto& ray = rays[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                       static_cast<std::size_t>(i)];
      for (int k = bb.min().z(); k <= bb.max().z(); ++k) {
        const Coord c(bb.min().x() + i, bb.min().y() + j, k);
        const double m = static_cast<double>(acc.getValue(c));
        if (!(m > 0.0)) continue;
        double z0 = (k - 0.5) * h, z1 = (k + 0.5) * h, f = 1.0;
        if (m < 1.0) {
          // The column's top voxel (none above it, material below) holds a top face: a piece
          // of the column as wide as the voxel below holds it (all of it under a floor, a
          // wall's share at a wall's top edge or corner), as high as that leaves the material;
          // a bottom voxel the same upside down. So no material rises above a top face: a
          // corner's voxel taken as a wall's share of the voxel's full height put material
          // above the face, which a rapid then met. Else a floor or a top (fractions changing
          // mostly along z) is a shorter piece of the column, on the side of the material,
          // and a wall keeps the piece at its share.
          const double below = static_cast<double>(acc.getValue(c.offsetBy(0, 0, -1)));
          const double above = static_cast<double>(acc.getValue(c.offsetBy(0, 0, 1)));
          const Eigen::Vector3d n = fractionNormal(acc, c);
          if ((below > 0.0) != (above > 0.0)) {
            f = std::clamp(std::max(below, above), m, 1.0);
            if (below > 0.0)
              z1 = z0 + m / f * h;
            else
              z0 = z1 - m / f * h;
          } else if (std::abs(n.z()) >= n.head<2>().norm() && n.z() != 0.0) {
            if (n.z() > 0.0)
              z1 = z0 + m * h;
            else
              z0 = z1 - m * h;
          } else {
            f = m;
          }
        }
        if (!ray.empty() && std::abs(ray.back().z1 - z0) <= 1e-12 * h &&
            std::abs(ray.back().f - f) <= 1e-9)
          ray.back().z1 = z1;
        else
          ray.push_back({z0, z1, f});
      }
    }
  });
  return DexelStock::fromColumns((bb.min().x() - 0.5) * h, (bb.min().y() - 0.5) * h, h, nx, ny,
                                 std::move(rays));
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

std::vector<double> VoxelStock::materialAt(const std::vector<Eigen::Vector3d>& points) const {
  const Impl& s = *impl_;
  auto acc = s.grid->getAccessor();
  std::vector<double> out;
  out.reserve(points.size());
  for (const Eigen::Vector3d& p : points)
    out.push_back(static_cast<double>(
        sampleTrilinear(acc, openvdb::Vec3d(p.x() / s.h, p.y() / s.h, p.z() / s.h))));
  return out;
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

  // Feed direction at the step's end, for the width and the engagement angle.
  const StepPath& path = sweep.path();
  const Eigen::Vector3d end = path.end;
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
          // Engagement geometry relative to the tip at the step's end. A voxel stands for
          // material up to (lost fraction - 1/2) h beyond its centre, which places a boundary
          // crossing it at the right sub-voxel height (exactly for axis-aligned boundaries).
          // Slivers of a hundredth of a voxel (a wall a later pass runs along again, its
          // planes' round-off) count in the volume but do not widen the engagement.
          const Eigen::Vector3d rel = p - end;
          const double side = rel.head<2>().dot(n);
          r.lateralMoment += lost * voxelVolume * side;
          if (lost < kEngagedShare) continue;
          const double reach = (lost - 0.5) * h;
          r.zMin = std::min(r.zMin, rel.z() - reach);
          r.zMax = std::max(r.zMax, rel.z() + reach);
          r.sMin = std::min(r.sMin, side - reach);
          r.sMax = std::max(r.sMax, side + reach);
        }
  };
  if (leaves.size() >= 8)
    tbb::parallel_for(std::size_t(0), leaves.size(), work);
  else
    for (std::size_t li = 0; li < leaves.size(); ++li)
      work(li);

  Removal out;
  double zMin = 1e300, zMax = -1e300, sMin = 1e300, sMax = -1e300;
  for (const LeafResult& r : results) {
    out.volume += r.volume;
    out.lateral += r.lateralMoment;
    out.voxelsChanged += r.changed;
    out.voxelsVisited += r.visited;
    zMin = std::min(zMin, r.zMin);
    zMax = std::max(zMax, r.zMax);
    sMin = std::min(sMin, r.sMin);
    sMax = std::max(sMax, r.sMax);
  }
  if (out.voxelsChanged > 0) {
    out.lateral /= out.volume;
    if (zMax >= zMin) {  // (only slivers: no width, no depth)
      out.axialDepth = std::max(0.0, std::min(zMax - std::max(zMin, 0.0), cutter.height()));
      out.radialWidth = sMax - sMin;
      out.top = std::max(0.0, std::min(zMax, cutter.height()));
    }
    // Engagement angle: the part of the periphery, at mid depth, with material just outside
    // the cutter after the cut (the arc of the edge that is cutting).
    const double zMid = std::clamp(0.5 * out.axialDepth, 0.0, cutter.height());
    // Just outside the periphery; the fraction is interpolated trilinearly so that a wall
    // tangent to the cutter (a slot's side) reads as about 0.5 and does not count.
    const double reach = cutter.radiusAt(zMid) + 0.05 * h;
    int engaged = 0;
    for (int b = 0; b < kAngleBins; ++b) {
      const double theta = (b + 0.5) * 2.0 * kPi / kAngleBins;
      const Eigen::Vector2d dir = std::cos(theta) * u + std::sin(theta) * n;
      const Eigen::Vector3d q(end.x() + reach * dir.x(), end.y() + reach * dir.y(), end.z() + zMid);
      const openvdb::Vec3d iq(q.x() / h, q.y() / h, q.z() / h);
      if (sampleTrilinear(acc, iq) > 0.5f) ++engaged;
    }
    out.engagementRad = 2.0 * kPi * engaged / kAngleBins;
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

namespace {

/// The narrow band of surfaceLevelSet under construction, in leaf-sized blocks: per voxel its
/// distance to the surface (mm, unsigned), the patch of surface that distance is to, and its
/// state (0: on the surface; 1 to kFar - 1: the last layer of the propagation that handed it
/// on; kFar: reached, beyond the band; kNotSurface: looked at for layer 0, not on the surface;
/// kUnset).
class BandBlocks {
 public:
  static constexpr std::uint8_t kUnset = 255, kNotSurface = 254, kFar = 253;
  struct Block {
    Coord origin;
    std::array<float, Leaf::SIZE> d;
    std::array<std::uint32_t, Leaf::SIZE> patch;
    std::array<std::uint8_t, Leaf::SIZE> layer;
    /// The blocks around this one (index 13: itself), -1 where not yet looked up.
    std::array<std::int32_t, 27> around;
  };

  /// The block of the leaf that holds voxel c, made if new.
  std::int32_t at(const Coord& c) {
    const Coord origin(c.x() & ~7, c.y() & ~7, c.z() & ~7);
    const auto [it, made] =
        index_.try_emplace(leafKey(origin), static_cast<std::int32_t>(blocks_.size()));
    if (made) {
      auto b = std::make_unique<Block>();
      b->origin = origin;
      b->layer.fill(kUnset);
      b->around.fill(-1);
      b->around[13] = it->second;
      blocks_.push_back(std::move(b));
    }
    return it->second;
  }
  /// The block next to block i in direction (dx, dy, dz), each -1, 0 or 1, made if new.
  std::int32_t next(std::int32_t i, int dx, int dy, int dz) {
    const int k = (dx + 1) * 9 + (dy + 1) * 3 + (dz + 1);
    std::int32_t& found = blocks_[static_cast<std::size_t>(i)]->around[static_cast<std::size_t>(k)];
    if (found < 0)
      found = at(blocks_[static_cast<std::size_t>(i)]->origin.offsetBy(8 * dx, 8 * dy, 8 * dz));
    return found;
  }
  Block& operator[](std::int32_t i) { return *blocks_[static_cast<std::size_t>(i)]; }
  std::size_t size() const { return blocks_.size(); }

 private:
  std::vector<std::unique_ptr<Block>> blocks_;
  std::unordered_map<std::uint64_t, std::int32_t> index_;
};

/// The stock's surface as a narrow-band level set (negative inside, within `halfWidth` voxels
/// of it) of the fractions' 0.5 iso-surface, by patches of surface carried out from it.
/// Layer 0, the voxels with a face neighbour on the other side of 1/2 (looked for at the
/// corners of the cells that the surface's mesh points, `points`, lie in): the plane normal to the
/// fractions' gradient through the crossings on those edges (the fractions interpolated linearly
/// along each; the crossings weighted by how square their edge is to the plane) gives the voxel's
/// distance, and its foot and normal make a patch, a disc of radius 0.35 h. Then layer by
/// layer, each voxel handed on in the last layer hands its patch to those of its 26
/// neighbours not behind it as seen from the patch (to all 26: CAMotics' heart as dexels
/// 0.09 s longer, 1.98 against 1.89 s, the bowl below no better); each
/// keeps the nearest patch it is handed and, when that is new or nearer and within the band,
/// hands it on in the next layer (a voxel of an earlier layer can get a nearer patch from
/// farther round: one 2 h under a top face beside a bowl's wall had its from the wall, 0.76
/// mm where the face is 0.6 mm away). The sign is the fractions' side of 1/2, so the level
/// set's zero crossings are between the voxels the fractions' are. One block per leaf, found
/// through its neighbours, keeps the propagation to array reads.
///
/// Against the exact distance to a ball's bowl in a block (tests/stock/VoxelStock.cpp, 55,000
/// band voxels at 0.3 mm, 3 h from its rim and more), worst 0.18 h and mean 0.0088 h from
/// voxels, 0.20 h and 0.0095 h from dexels. The patch's radius was chosen on that bowl (worst
/// error): points alone 0.42 h, radius 0.25 h 0.26 h, 0.5 h 0.24 h, 0.75 h 0.44 h (discs reaching
/// over the rim). Handing to the 6 face neighbours only: 0.47 h worst, the layers 0.25 s against
/// 0.40 s; 18 (faces and edges): 0.27 h, 0.33 s. Before it, OpenVDB's fast sweeping (sdfToSdf) of a
/// first guess (1/2 - fraction) h over the mesh's voxels dilated by 3: worst 0.37 h (voxels) and
/// 0.40 h (dexels), mean 0.013 and 0.014 h on the same bowl, and 1.53 s against 0.66 s now of a
/// dexel run of CAMotics' heart at 0.253 mm (2.1 million band voxels, one core). Each voxel's own
/// patch in its block instead of an index into the patches: as fast, 50 MB more at the run's peak.
/// Earlier still: meshing and re-voxelising (levelSetRebuild) 5 of the 9 s of a 17k-move run;
/// meshToLevelSet on the same mesh 4.4 s; each band voxel's nearest triangle propagated from the
/// voxels at the triangles' corners 2.8 s, less exact near the surface (too few seeds: voxels a
/// twentieth of a cell from it read half a cell).
FloatGrid::Ptr surfaceLevelSet(const FloatGrid& grid, double h, int halfWidth,
                               const std::vector<std::array<float, 3>>& points) {
  const float width = static_cast<float>(halfWidth * h);
  const auto hf = static_cast<float>(h);
  // The distance from v (relative to a patch's centre) to the patch, a disc of radius 0.35 h
  // square to n (n zero: its centre alone).
  const float radius = 0.35f * hf;
  auto patchDistance = [radius](const openvdb::Vec3s& v, const openvdb::Vec3s& n) {
    if (n.x() == 0.0f && n.y() == 0.0f && n.z() == 0.0f) return v.length();
    const float a = n.dot(v);
    const float lateral2 = v.lengthSqr() - a * a;
    if (lateral2 <= radius * radius) return std::abs(a);
    const float beyond = std::sqrt(lateral2) - radius;
    return std::sqrt(a * a + beyond * beyond);
  };
  BandBlocks band;
  using Front = std::vector<std::pair<std::int32_t, std::uint32_t>>;
  // The surface's patches, one for each voxel of layer 0: its foot and normal.
  struct Patch {
    openvdb::Vec3s point, normal;
  };
  std::vector<Patch> patches;
  Front front;
  auto f = grid.getConstAccessor();
  constexpr std::uint8_t kNotSurface = BandBlocks::kNotSurface, kFar = BandBlocks::kFar;
  // Layer 0: the voxels at the corners of each cell a mesh point lies in, where a face
  // neighbour is on the other side.
  for (const auto& p : points) {
    const Coord cell =
        Coord::floor(grid.transform().worldToIndex(openvdb::Vec3d(p[0], p[1], p[2])));
    for (int corner = 0; corner < 8; ++corner) {
      const Coord c = cell.offsetBy(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
      const std::int32_t bi = band.at(c);
      BandBlocks::Block& block = band[bi];
      const auto o = static_cast<std::uint32_t>(Leaf::coordToOffset(c));
      if (block.layer[o] != BandBlocks::kUnset) continue;
      const double m = static_cast<double>(f.getValue(c));
      const bool inside = m >= 0.5;
      double side[3][2];
      Eigen::Vector3d g;
      for (int a = 0; a < 3; ++a) {
        Coord e(0);
        e[a] = 1;
        side[a][0] = static_cast<double>(f.getValue(c - e));
        side[a][1] = static_cast<double>(f.getValue(c + e));
        g[a] = side[a][0] - side[a][1];
      }
      const Eigen::Vector3d x(c.x() * h, c.y() * h, c.z() * h);
      // The crossings: along axis a towards s = -1 or +1, at t h with t from the linear
      // interpolation of the fractions.
      double weighted = 0.0, weights = 0.0, nearest = std::numeric_limits<double>::infinity();
      Eigen::Vector3d nearestPoint = x;
      const double gn = g.norm();
      const Eigen::Vector3d n = gn > 1e-9 ? Eigen::Vector3d(g / gn) : Eigen::Vector3d::Zero();
      for (int a = 0; a < 3; ++a)
        for (int s = 0; s < 2; ++s) {
          const double other = side[a][s];
          if ((other >= 0.5) == inside) continue;
          const double t = (m - 0.5) / (m - other);
          Eigen::Vector3d crossing = x;
          crossing[a] += (s == 0 ? -t : t) * h;
          const double w = std::abs(n[a]);
          weighted += w * n.dot(x - crossing);
          weights += w;
          if (t * h < nearest) {
            nearest = t * h;
            nearestPoint = crossing;
          }
        }
      if (!(nearest < std::numeric_limits<double>::infinity())) {
        block.layer[o] = kNotSurface;
        continue;
      }
      // Where the gradient is square to every crossing edge, the nearest crossing.
      const bool planar = weights > 1e-3;
      const double d = planar ? weighted / weights : 0.0;
      const Eigen::Vector3d foot = planar ? Eigen::Vector3d(x - d * n) : nearestPoint;
      block.layer[o] = 0;
      block.d[o] = static_cast<float>(planar ? std::abs(d) : nearest);
      block.patch[o] = static_cast<std::uint32_t>(patches.size());
      patches.push_back({openvdb::Vec3s(static_cast<float>(foot.x()), static_cast<float>(foot.y()),
                                        static_cast<float>(foot.z())),
                         planar
                             ? openvdb::Vec3s(static_cast<float>(n.x()), static_cast<float>(n.y()),
                                              static_cast<float>(n.z()))
                             : openvdb::Vec3s(0.0f)});
      front.emplace_back(bi, o);
    }
  }
  // The layers out from the surface, until none hands on a patch within the band.
  Front next;
  // The 26 neighbours: their steps in voxels, in the block's offsets and in mm.
  struct Neighbour {
    int dx, dy, dz, offset;
    openvdb::Vec3s step;
  };
  std::vector<Neighbour> around;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if ((dx | dy | dz) != 0)
          around.push_back({dx, dy, dz, dx * 64 + dy * 8 + dz,
                            openvdb::Vec3s(static_cast<float>(dx), static_cast<float>(dy),
                                           static_cast<float>(dz)) *
                                hf});
  for (int k = 1; !front.empty() && k < kFar; ++k) {
    next.clear();
    const auto layer = static_cast<std::uint8_t>(k);
    for (const auto& [bi, o] : front) {
      const std::uint32_t from = band[bi].patch[o];
      const openvdb::Vec3s p = patches[from].point, n = patches[from].normal;
      const Coord local = Leaf::offsetToLocalCoord(o);
      const Coord c = band[bi].origin + local;
      const openvdb::Vec3s fromPoint =
          openvdb::Vec3s(static_cast<float>(c.x()), static_cast<float>(c.y()),
                         static_cast<float>(c.z())) *
              hf -
          p;
      // Inside its block (all but the outer shell of voxels), the neighbours are in it.
      const bool inner = local.x() > 0 && local.x() < 7 && local.y() > 0 && local.y() < 7 &&
                         local.z() > 0 && local.z() < 7;
      for (const Neighbour& e : around) {
        if (fromPoint.dot(e.step) < 0.0f) continue;  // behind, seen from the patch
        std::int32_t ui = bi;
        std::uint32_t uo = o + static_cast<std::uint32_t>(e.offset);
        if (!inner) {
          const int lx = local.x() + e.dx, ly = local.y() + e.dy, lz = local.z() + e.dz;
          const int bx = lx < 0 ? -1 : (lx > 7 ? 1 : 0), by = ly < 0 ? -1 : (ly > 7 ? 1 : 0),
                    bz = lz < 0 ? -1 : (lz > 7 ? 1 : 0);
          if ((bx | by | bz) != 0) ui = band.next(bi, bx, by, bz);
          uo = static_cast<std::uint32_t>(((lx & 7) << 6) | ((ly & 7) << 3) | (lz & 7));
        }
        BandBlocks::Block& u = band[ui];
        std::uint8_t& state = u.layer[uo];
        if (state == 0) continue;
        const float d = patchDistance(fromPoint + e.step, n);
        const bool reached = state < kNotSurface;
        if (reached && !(d < u.d[uo])) continue;
        u.d[uo] = d;
        u.patch[uo] = from;
        // New, or nearer than it was (also in an earlier layer): on in the next layer.
        if (d < width && state != layer) {
          state = layer;
          next.emplace_back(ui, uo);
        } else if (!reached) {
          state = kFar;
        }
      }
    }
    front.swap(next);
  }
  // The level set: each block's voxels within the band, signed by the fractions' side.
  FloatGrid::Ptr surface = FloatGrid::create(width);
  surface->setTransform(grid.transform().copy());
  for (std::size_t i = 0; i < band.size(); ++i) {
    const BandBlocks::Block& b = band[static_cast<std::int32_t>(i)];
    auto leaf = std::make_unique<Leaf>(b.origin, width);
    bool any = false;
    for (std::uint32_t o = 0; o < Leaf::SIZE; ++o) {
      if (b.layer[o] >= kNotSurface || !(b.d[o] < width)) continue;
      const bool inside = f.getValue(b.origin + Leaf::offsetToLocalCoord(o)) >= 0.5f;
      leaf->setValueOn(o, inside ? -b.d[o] : b.d[o]);
      any = true;
    }
    if (any) surface->tree().addLeaf(leaf.release());
  }
  openvdb::tools::signedFloodFill(surface->tree());
  openvdb::tools::pruneLevelSet(surface->tree());
  surface->setName("surface");
  surface->setGridClass(openvdb::GRID_LEVEL_SET);
  return surface;
}

}  // namespace

std::vector<std::pair<Eigen::Vector3d, double>> VoxelStock::surfaceBand() const {
  const double h = impl_->h;
  const FloatGrid::Ptr surface = surfaceLevelSet(*impl_->grid, h, 3, impl_->surfaceMesh()->points);
  std::vector<std::pair<Eigen::Vector3d, double>> out;
  out.reserve(surface->activeVoxelCount());
  for (auto it = surface->cbeginValueOn(); it; ++it)
    if (it.isVoxelValue()) {
      const Coord c = it.getCoord();
      out.emplace_back(Eigen::Vector3d(c.x() * h, c.y() * h, c.z() * h), static_cast<double>(*it));
    }
  return out;
}

void VoxelStock::writeStockVdb(const std::string& path) const {
  const FloatGrid& grid = *impl_->grid;
  const double h = impl_->h;
  const FloatGrid::Ptr surface = surfaceLevelSet(grid, h, 3, impl_->surfaceMesh()->points);
  // The partial voxels' planes (or the stock box's faces), for a run that goes on from here.
  openvdb::Vec3SGrid::Ptr planes[3];
  for (int i = 0; i < 3; ++i) {
    planes[i] = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    planes[i]->setTransform(grid.transform().copy());
    planes[i]->setName("planes_" + std::to_string(i));
    planes[i]->setGridClass(openvdb::GRID_UNKNOWN);
  }
  {
    auto p0 = planes[0]->getAccessor();
    auto p1 = planes[1]->getAccessor();
    auto p2 = planes[2]->getAccessor();
    for (auto it = grid.cbeginValueOn(); it; ++it) {
      const double m = static_cast<double>(*it);
      if (!it.isVoxelValue() || !(m < 1.0)) continue;
      const Coord c = it.getCoord();
      const auto found = impl_->planes.find(leafKey(c));
      HalfSpace q[2], outer;
      int made[2];
      double held = 0.0;
      bool united = false;
      if (found == impl_->planes.end() ||
          found->second.get(Leaf::coordToOffset(c), q, made, held, united, &outer) == 0) {
        if (!impl_->box) continue;
        boxFaces(*impl_->box, Eigen::Vector3d(c.x() * h, c.y() * h, c.z() * h), h, q);
      }
      p0.setValue(c, encodePlane(q[0], united));
      p1.setValue(c, encodePlane(q[1], false));
      if (outer.n.squaredNorm() > 0.0) p2.setValue(c, encodePlane(outer, false));
    }
  }
  writeVdb(path, openvdb::GridPtrVec{impl_->grid, surface, planes[0], planes[1], planes[2]});
}

void VoxelStock::writeRemovedVdb(const std::string& path) const {
  if (!impl_->removed) throw Error("removed.vdb needs captureRemoved(true) before the removals");
  writeVdb(path, openvdb::GridPtrVec{impl_->removed, impl_->step, impl_->mrr});
}

namespace {

/// The fractions averaged over blocks of factor^3 voxels (factor 2, 4 or 8: a divisor of a
/// leaf's 8), on a grid `factor` times coarser whose voxel I covers voxels factor I ..
/// factor I + factor - 1 (its centre (factor I + (factor - 1) / 2) h). Only the leaves are
/// averaged; tiles (uniform material) map to coarse tiles of the same value. The volume is
/// kept. (OpenVDB's resampleToMatch did the same by trilinear sampling at every coarse voxel,
/// interior included: 2 s of a 0.1 mm stock 65 x 65 x 10 mm, against tens of ms here.)
FloatGrid::Ptr boxFiltered(const FloatGrid& grid, double h, int factor) {
  const int shift = factor == 2 ? 1 : factor == 4 ? 2 : 3;
  FloatGrid::Ptr coarse = FloatGrid::create(0.0f);
  openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(factor * h);
  xf->postTranslate(openvdb::Vec3d(0.5 * (factor - 1) * h));
  coarse->setTransform(xf);
  for (auto it = grid.cbeginValueAll(); it; ++it) {
    if (it.isVoxelValue() || *it <= 0.0f) continue;
    CoordBBox b = it.getBoundingBox();
    b = CoordBBox(Coord(b.min().x() >> shift, b.min().y() >> shift, b.min().z() >> shift),
                  Coord(b.max().x() >> shift, b.max().y() >> shift, b.max().z() >> shift));
    coarse->fill(b, *it, it.isValueOn());
  }
  auto acc = coarse->getAccessor();
  const float share = 1.0f / static_cast<float>(factor * factor * factor);
  const int n = 8 >> shift;  // coarse voxels along a leaf's side
  std::vector<float> sums(static_cast<std::size_t>(n * n * n));
  for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
    std::fill(sums.begin(), sums.end(), 0.0f);
    for (openvdb::Index i = 0; i < FloatGrid::TreeType::LeafNodeType::SIZE; ++i) {
      const Coord l = FloatGrid::TreeType::LeafNodeType::offsetToLocalCoord(i);
      sums[static_cast<std::size_t>(((l.x() >> shift) * n + (l.y() >> shift)) * n +
                                    (l.z() >> shift))] += leaf->getValue(i);
    }
    const Coord o = leaf->origin();
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z) {
          const float v = sums[static_cast<std::size_t>((x * n + y) * n + z)] * share;
          const Coord c((o.x() >> shift) + x, (o.y() >> shift) + y, (o.z() >> shift) + z);
          if (v > 0.0f)
            acc.setValue(c, v);
          else
            acc.setValueOff(c, 0.0f);
        }
  }
  return coarse;
}

}  // namespace

std::size_t VoxelStock::writeStl(const std::string& path, std::size_t maxTriangles) const {
  TriangleMesh coarse;
  std::shared_ptr<const TriangleMesh> full;
  if (maxTriangles > 0)
    coarse = viewMesh(maxTriangles);
  else
    full = impl_->surfaceMesh();
  const TriangleMesh& mesh = maxTriangles > 0 ? coarse : *full;
  engage::writeStl(mesh, path);
  return boundaryEdgeCount(mesh);
}

double VoxelStock::memoryBound(const Box3& box, double voxelSize) {
  return voxelCount(box, voxelSize) * 18.0 * 1.1;
}

TriangleMesh VoxelStock::viewMesh(std::size_t maxTriangles, double* cellSize) const {
  // About two triangles per partial voxel at full resolution, a quarter of that per halving.
  std::size_t partial = 0;
  for (auto leaf = impl_->grid->tree().cbeginLeaf(); leaf; ++leaf)
    for (auto v = leaf->cbeginValueOn(); v; ++v)
      if (*v > 0.0f && *v < 1.0f) ++partial;
  int c = 1;
  while (c < 8 && 2.0 * static_cast<double>(partial) / (c * c) > static_cast<double>(maxTriangles))
    c *= 2;
  const double h = impl_->h;
  constexpr double kAdaptivity = 0.1;  // merges flat floors and walls, keeps edges
  auto meshAt = [&](int factor) {
    if (factor == 1) return isoSurface(*impl_->grid, kAdaptivity);
    return isoSurface(*boxFiltered(*impl_->grid, h, factor), kAdaptivity);
  };
  TriangleMesh mesh = meshAt(c);
  // Adaptive meshing often leaves far fewer than the estimate: finer while it fits.
  while (c > 1 && mesh.triangles.size() * 4 < maxTriangles) {
    TriangleMesh finer = meshAt(c / 2);
    if (finer.triangles.size() > maxTriangles) break;
    mesh = std::move(finer);
    c /= 2;
  }
  while (mesh.triangles.size() > maxTriangles && c < 64)
    mesh = meshAt(c *= 2);
  if (cellSize) *cellSize = c * h;
  return mesh;
}

}  // namespace engage
