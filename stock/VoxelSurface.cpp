// The voxel stock's surface: the fractions' 0.5 iso-surface as a mesh (stock.stl, the report's
// 3D view, within a triangle budget by block averaging) and as the narrow-band level set of
// stock.vdb (surfaceLevelSet: patches of the surface carried out layer by layer).

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
#include <vector>

namespace engage {
using namespace voxel;

namespace voxel {

/// The 0.5 iso-surface of a fraction grid as a triangle mesh with outward normals; OpenVDB's
/// `adaptivity` (0: none) merges cells where the surface is nearly flat.
TriangleMesh isoSurface(const FloatGrid& grid, double adaptivity, double isovalue) {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(grid, points, triangles, quads, isovalue, adaptivity);
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

}  // namespace voxel

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

/// A patch of surface: its foot and normal (zero: a point).
struct Patch {
  openvdb::Vec3s point, normal;
};

/// Where the surface is a level face far around, the propagation is short-cut. A column (x, y)
/// is plain where every column within kPlainReach of it holds the same layer-0 voxels (the
/// same heights, each patch level, +Z or -Z, with its foot at the same height): then no patch
/// nearer than the band's width lies off the column's own plane, and each voxel of the
/// column within the width of one of its feet takes its height above or below the nearest
/// foot, which is what the propagation would hand it. Those voxels are filled here (reached,
/// not handed on) and the plain columns' layer-0 voxels leave the front; the rest propagates
/// as before and may still lower them. (A board's faces are most of its band: 2.7 million
/// voxels at 0.04 mm, of which the propagation took 0.6 s.)
void fillPlainColumns(BandBlocks& band, std::vector<std::pair<std::int32_t, std::uint32_t>>& front,
                      const std::vector<Patch>& patches, float h, float width) {
  constexpr int kPlainReach = 4;  // columns: the width, 3 voxels, plus a patch's radius, 0.35
  if (front.empty()) return;
  // The columns' box and, per column, a signature of its layer-0 voxels: their count and the
  // sum of a hash of each one's height, foot and normal (zero count: none; a patch not level:
  // never plain).
  int x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = std::numeric_limits<int>::min(), y1 = x1;
  for (const auto& [bi, o] : front) {
    const Coord c = band[bi].origin + Leaf::offsetToLocalCoord(o);
    x0 = std::min(x0, c.x());
    x1 = std::max(x1, c.x());
    y0 = std::min(y0, c.y());
    y1 = std::max(y1, c.y());
  }
  const std::size_t nx = static_cast<std::size_t>(x1 - x0 + 1),
                    ny = static_cast<std::size_t>(y1 - y0 + 1);
  // (A surface whose columns' box is mostly empty, a thin slanted wall's, keeps the
  // propagation: the columns' arrays would outgrow the band.)
  if (nx * ny > 4 * front.size()) return;
  struct Signature {
    std::uint64_t sum = 0;
    std::uint32_t count = 0;
    bool level = true;
    bool operator==(const Signature& o) const {
      return sum == o.sum && count == o.count && level && o.level;
    }
  };
  std::vector<Signature> sig(nx * ny);
  auto column = [&](const Coord& c) {
    return static_cast<std::size_t>(c.y() - y0) * nx + static_cast<std::size_t>(c.x() - x0);
  };
  auto bits = [](float v) {
    std::uint32_t b;
    std::memcpy(&b, &v, sizeof b);
    return static_cast<std::uint64_t>(b);
  };
  for (const auto& [bi, o] : front) {
    const Coord c = band[bi].origin + Leaf::offsetToLocalCoord(o);
    const Patch& p = patches[band[bi].patch[o]];
    Signature& s = sig[column(c)];
    ++s.count;
    if (p.normal.x() != 0.0f || p.normal.y() != 0.0f || std::abs(p.normal.z()) != 1.0f)
      s.level = false;
    std::uint64_t k = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z())) << 32) ^
                      (bits(p.point.z()) * 0x9E3779B97F4A7C15ull) ^ bits(p.normal.z());
    k ^= k >> 29;
    s.sum += k * 0xBF58476D1CE4E5B9ull;
  }
  // Plain: the same signature (level) over the (2 kPlainReach + 1)^2 columns around, by runs
  // along x, then along y.
  const int reach = kPlainReach;
  std::vector<std::uint8_t> rowSame(nx * ny, 0), plain(nx * ny, 0);
  std::vector<int> left(nx), right(nx), down(ny), up(ny);  // runs of equal signatures
  for (std::size_t y = 0; y < ny; ++y) {
    for (std::size_t x = 0; x < nx; ++x) {
      const std::size_t i = y * nx + x;
      left[x] = x > 0 && sig[i] == sig[i - 1] ? left[x - 1] + 1 : 1;
    }
    for (std::size_t x = nx; x-- > 0;) {
      const std::size_t i = y * nx + x;
      right[x] = x + 1 < nx && sig[i] == sig[i + 1] ? right[x + 1] + 1 : 1;
    }
    for (std::size_t x = 0; x < nx; ++x)
      rowSame[y * nx + x] =
          sig[y * nx + x].count > 0 && sig[y * nx + x].level && left[x] > reach && right[x] > reach;
  }
  for (std::size_t x = 0; x < nx; ++x) {
    auto same = [&](std::size_t y, std::size_t other) {
      return rowSame[y * nx + x] && rowSame[other * nx + x] &&
             sig[y * nx + x] == sig[other * nx + x];
    };
    for (std::size_t y = 0; y < ny; ++y)
      down[y] = !rowSame[y * nx + x] ? 0 : y > 0 && same(y, y - 1) ? down[y - 1] + 1 : 1;
    for (std::size_t y = ny; y-- > 0;)
      up[y] = !rowSame[y * nx + x] ? 0 : y + 1 < ny && same(y, y + 1) ? up[y + 1] + 1 : 1;
    for (std::size_t y = 0; y < ny; ++y)
      plain[y * nx + x] = down[y] > reach && up[y] > reach;
  }
  // Each plain column's voxels within the width of a foot: its distance (as the propagation
  // computes it, in floats) unless nearer already; their layer-0 voxels out of the front.
  constexpr std::uint8_t kFar = BandBlocks::kFar, kNotSurface = BandBlocks::kNotSurface;
  const int span = static_cast<int>(std::ceil(width / h)) + 1;
  std::size_t kept = 0;
  for (const auto& [bi, o] : front) {
    const Coord c = band[bi].origin + Leaf::offsetToLocalCoord(o);
    if (!plain[column(c)]) {
      front[kept++] = {bi, o};
      continue;
    }
    const std::uint32_t from = band[bi].patch[o];
    const float foot = patches[from].point.z();
    for (int dz = -span; dz <= span; ++dz) {
      if (dz == 0) continue;
      const Coord v = c.offsetBy(0, 0, dz);
      const float d = std::abs(static_cast<float>(v.z()) * h - foot);
      if (!(d < width)) continue;
      const int lz = (c.z() & 7) + dz;
      const std::int32_t ui = lz < 0 || lz > 7 ? band.next(bi, 0, 0, lz < 0 ? -1 : 1) : bi;
      BandBlocks::Block& u = band[ui];
      const auto uo = static_cast<std::uint32_t>(Leaf::coordToOffset(v));
      std::uint8_t& state = u.layer[uo];
      if (state == 0 || (state < kNotSurface && !(d < u.d[uo]))) continue;
      u.d[uo] = d;
      u.patch[uo] = from;
      state = kFar;
    }
  }
  front.resize(kept);
}

}  // namespace

namespace voxel {

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
  auto it = grid.cbeginValueAll();
  it.setMaxDepth(FloatGrid::TreeType::ValueAllCIter::LEAF_DEPTH - 1);  // the tiles, not the voxels
  for (; it; ++it) {
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

std::size_t partialVoxels(const FloatGrid& grid) {
  std::size_t partial = 0;
  for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf)
    for (auto v = leaf->cbeginValueOn(); v; ++v)
      if (*v > 0.0f && *v < 1.0f) ++partial;
  return partial;
}

int fileSurfaceFactor(const FloatGrid& grid) {
  const std::size_t partial = partialVoxels(grid);
  const openvdb::CoordBBox b = grid.evalActiveVoxelBoundingBox();
  const openvdb::Coord d = b.dim();
  const double faces =
      2.0 * (static_cast<double>(d.x()) * d.y() + static_cast<double>(d.y()) * d.z() +
             static_cast<double>(d.z()) * d.x());
  const double band = 7.0 * (faces + static_cast<double>(partial));  // voxels at h
  int c = 1;
  while (c < 8 && band / (c * c) > kFileBandVoxels)
    c *= 2;
  return c;
}

/// The stock's surface as a narrow-band level set (negative inside, within `halfWidth` voxels
/// of it) of the fractions' 0.5 iso-surface, by patches of surface carried out from it.
/// Layer 0, the voxels with a face neighbour on the other side of 1/2 (crossingVoxels, from
/// the fractions themselves: an iso-surface's mesh to find them cost a board's file 0.24 s):
/// the plane normal to the
/// fractions' gradient through the crossings on those edges (the fractions interpolated linearly
/// along each; the crossings weighted by how square their edge is to the plane) gives the voxel's
/// distance, and its foot and normal make a patch, a disc of radius 0.35 h. Then layer by
/// layer, each voxel handed on in the last layer hands its patch to those of its 26
/// neighbours not behind it as seen from the patch (handing to all 26 is slower and no more
/// exact); each
/// keeps the nearest patch it is handed and, when that is new or nearer and within the band,
/// hands it on in the next layer (a voxel of an earlier layer can get a nearer patch from
/// farther round: one 2 h under a top face beside a bowl's wall had its from the wall, 0.76
/// mm where the face is 0.6 mm away). The sign is the fractions' side of 1/2, so the level
/// set's zero crossings are between the voxels the fractions' are. One block per leaf, found
/// through its neighbours, keeps the propagation to array reads.
///
/// Against the exact distance to a ball's bowl in a block (tests/stock/VoxelStock.cpp, 55,000
/// band voxels at 0.3 mm, 3 h from its rim and more), worst 0.18 h and mean 0.0088 h from
/// voxels, 0.20 h and 0.0095 h from dexels. The patch's radius is the one of least worst error
/// on that bowl (smaller discs leave gaps between the points, larger ones reach over the rim).
/// This is more exact and faster than OpenVDB's fast sweeping of a first guess or than meshing
/// and re-voxelising (docs/voxel-stock.md). One function: its layers share the band's blocks and
/// patches, and the propagation is the hot loop of writing stock.vdb.
namespace {

/// The voxels with a face neighbour on the other side of 1/2, some twice: in the leaves, each
/// voxel against its six neighbours (and a neighbour across outside any leaf with it); where a
/// tile of material meets a tile or the background below 1/2, the voxels either side of its
/// faces.
std::vector<Coord> crossingVoxels(const FloatGrid& grid) {
  std::vector<Coord> out;
  auto acc = grid.getConstAccessor();
  auto inLeaf = [&](const Coord& c) { return acc.probeConstLeaf(c) != nullptr; };
  for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
    const Coord origin = leaf->origin();
    std::array<bool, Leaf::SIZE> in;
    for (openvdb::Index i = 0; i < Leaf::SIZE; ++i)
      in[i] = leaf->getValue(i) >= 0.5f;
    // Across each face, the next leaf, or where there is none the one value there (a tile's or
    // the background).
    const Leaf* next[3][2];
    bool beyond[3][2];
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 2; ++k) {
        Coord c = origin;
        c[a] += k == 0 ? -1 : 8;
        next[a][k] = acc.probeConstLeaf(c);
        beyond[a][k] = acc.getValue(c) >= 0.5f;
      }
    for (openvdb::Index i = 0; i < Leaf::SIZE; ++i) {
      const Coord l = Leaf::offsetToLocalCoord(i);
      bool crossing = false;
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 2; ++k) {
          Coord n = l;
          n[a] += k == 0 ? -1 : 1;
          if (n[a] >= 0 && n[a] < 8) {
            crossing = crossing || in[Leaf::coordToOffset(n)] != in[i];
            continue;
          }
          const Leaf* other = next[a][k];
          if (other) {
            n[a] &= 7;
            crossing = crossing || (other->getValue(Leaf::coordToOffset(n)) >= 0.5f) != in[i];
          } else if (beyond[a][k] != in[i]) {
            crossing = true;
            Coord c = origin + l;
            c[a] += k == 0 ? -1 : 1;
            out.push_back(c);
          }
        }
      if (crossing) out.push_back(origin + l);
    }
  }
  auto tile = grid.cbeginValueAll();
  tile.setMaxDepth(FloatGrid::TreeType::ValueAllCIter::LEAF_DEPTH - 1);  // the tiles only
  for (; tile; ++tile) {
    if (tile.isVoxelValue() || !(*tile >= 0.5f)) continue;
    const CoordBBox b = tile.getBoundingBox();
    const int level = static_cast<int>(tile.getLevel());
    for (int a = 0; a < 3; ++a)
      for (const int s : {-1, 1}) {
        CoordBBox face = b;
        face.min()[a] = face.max()[a] = s < 0 ? b.min()[a] : b.max()[a];
        // A face against a material tile as large or larger (aligned: it covers the face; its
        // depth in the tree, the root 0 and a leaf 3, at most 3 less this tile's level).
        Coord across = face.min();
        across[a] += s;
        const int depth = acc.getValueDepth(across);
        if (depth >= 0 && depth <= 3 - level && acc.getValue(across) >= 0.5f) continue;
        for (auto it = face.begin(); it; ++it) {
          Coord n = *it;
          n[a] += s;
          if (inLeaf(n) || acc.getValue(n) >= 0.5f) continue;
          out.push_back(*it);
          out.push_back(n);
        }
      }
  }
  return out;
}

FloatGrid::Ptr levelSet(const FloatGrid& grid, double h, int halfWidth) {
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
  std::vector<Patch> patches;
  Front front;
  auto f = grid.getConstAccessor();
  constexpr std::uint8_t kNotSurface = BandBlocks::kNotSurface, kFar = BandBlocks::kFar;
  // Layer 0: the voxels with a face neighbour on the other side.
  for (const Coord& c : crossingVoxels(grid)) {
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
                       planar ? openvdb::Vec3s(static_cast<float>(n.x()), static_cast<float>(n.y()),
                                               static_cast<float>(n.z()))
                              : openvdb::Vec3s(0.0f)});
    front.emplace_back(bi, o);
  }
  fillPlainColumns(band, front, patches, hf, width);
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
  // (The patches and the fronts' room given back before the level set's leaves are made: on
  // a board's coarse file 60 MB of the peak.)
  Front().swap(front);
  Front().swap(next);
  std::vector<Patch>().swap(patches);
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

FloatGrid::Ptr surfaceLevelSet(const FloatGrid& grid, double h, int halfWidth) {
  return levelSet(grid, h, halfWidth);
}

}  // namespace voxel

std::vector<std::pair<Eigen::Vector3d, double>> VoxelStock::surfaceBand() const {
  const double h = impl_->h;
  const FloatGrid::Ptr surface = surfaceLevelSet(*impl_->grid, h, 3);
  std::vector<std::pair<Eigen::Vector3d, double>> out;
  out.reserve(surface->activeVoxelCount());
  for (auto it = surface->cbeginValueOn(); it; ++it)
    if (it.isVoxelValue()) {
      const Coord c = it.getCoord();
      out.emplace_back(Eigen::Vector3d(c.x() * h, c.y() * h, c.z() * h), static_cast<double>(*it));
    }
  return out;
}

TriangleMesh VoxelStock::viewMesh(std::size_t maxTriangles, double* cellSize) const {
  const double h = impl_->h;
  if (maxTriangles == 0) {
    if (cellSize) *cellSize = h;
    return *impl_->surfaceMesh();
  }
  // About two triangles per partial voxel at full resolution, a quarter of that per halving.
  const std::size_t partial = partialVoxels(*impl_->grid);
  int c = 1;
  while (c < 8 && 2.0 * static_cast<double>(partial) / (c * c) > static_cast<double>(maxTriangles))
    c *= 2;
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
