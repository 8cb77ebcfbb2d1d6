// The voxel stock's files and conversions: stock.vdb (fractions, planes, the surface level set)
// written and read back (on the same grid, or resampled by overlap onto another), removed.vdb,
// and the dexel stock as voxels (fromDexels, dexelsFromVdb).

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
namespace {

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
  // A dexel run's fractions coarser than its rays (VoxelStock::writeDexelStockVdb): the
  // fractions at the rays' spacing, from the rays, as a file of finer ones holds them.
  if (const auto coarser = grid->getMetadata<openvdb::Int32Metadata>("dexel_coarser");
      coarser && coarser->value() > 1) {
    const double spacing = grid->transform().voxelSize()[0] / coarser->value();
    const std::optional<DexelStock> rays = exactDexels(path, spacing);
    if (!rays)
      throw ParameterError("stock '" + path + "' holds its fractions " +
                           std::to_string(coarser->value()) +
                           " times coarser than its rays, and the rays (grids dexel_z0, "
                           "dexel_z1, dexel_f, dexel_weight) cannot be read");
    grid = dexelFractions(*rays);
  }
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
                         formatNumber(grid->background()) +
                         ", not 0 (air): not material fractions");
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    const float v = *it;
    if (!(v >= -1e-6f && v <= 1.0f + 1e-6f)) {
      const Coord c = it.getCoord();
      throw ParameterError("grid 'stock' of '" + path + "' holds " + formatNumber(v) +
                           " at voxel (" + std::to_string(c.x()) + ", " + std::to_string(c.y()) +
                           ", " + std::to_string(c.z()) + "): not a material fraction (0 to 1)");
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

namespace voxel {

void writeVdb(const std::string& path, const openvdb::GridPtrVec& grids) {
  writeFileAtomically(path, [&](std::ostream& os) { CheckedArchive().writeTo(os, grids); });
}

void fillFullRuns(FloatGrid& grid, const std::vector<FullRun>& runs, int ax, int by, int cx,
                  int cy) {
  auto acc = grid.getAccessor();
  for (int b0 = 0; b0 < by; b0 += 8)
    for (int a0 = 0; a0 < ax; a0 += 8) {
      // The heights every column of the block is full at, as one box.
      int k0 = std::numeric_limits<int>::min(), k1 = std::numeric_limits<int>::max();
      for (int b = b0; b < std::min(by, b0 + 8); ++b)
        for (int a = a0; a < std::min(ax, a0 + 8); ++a) {
          const FullRun& run = runs[static_cast<std::size_t>(b) * static_cast<std::size_t>(ax) +
                                    static_cast<std::size_t>(a)];
          k0 = std::max(k0, run.k0);
          k1 = std::min(k1, run.k1);
        }
      if (k0 <= k1)
        grid.tree().fill(
            CoordBBox(Coord(cx + a0, cy + b0, k0),
                      Coord(cx + std::min(ax, a0 + 8) - 1, cy + std::min(by, b0 + 8) - 1, k1)),
            1.0f, true);
      acc.clear();  // (the box may have replaced nodes the accessor holds)
      for (int b = b0; b < std::min(by, b0 + 8); ++b)
        for (int a = a0; a < std::min(ax, a0 + 8); ++a) {
          const FullRun& run = runs[static_cast<std::size_t>(b) * static_cast<std::size_t>(ax) +
                                    static_cast<std::size_t>(a)];
          for (int k = run.k0; k <= run.k1; ++k)
            if (k < k0 || k > k1) acc.setValue(Coord(cx + a, cy + b, k), 1.0f);
        }
    }
}

FloatGrid::Ptr dexelFractions(const DexelStock& d) {
  initVdb();
  const double h = d.resolution();
  FloatGrid::Ptr grid = FloatGrid::create(0.0f);
  grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
  grid->setName("stock");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  // Each voxel gets the material of the columns it overlaps: volume share x the interval's
  // share x the column's weight. Voxel column by voxel column, its four dexel columns' material
  // merged (as writeRemovedVdb merges their losses); the voxels below 1
  // written one by one, and the run of full ones each 8 x 8 block of voxel columns shares as
  // one box (tiles where it covers whole leaves), the rest of each run one by one: each
  // voxel is written once, not added into from each of its columns.
  const ColumnFootprint corner(d);
  const int nx = d.raysX(), ny = d.raysY();
  const int ax = nx + 1, by = ny + 1;  // voxel columns (corner.cx + a, corner.cy + b)
  std::vector<FullRun> full(static_cast<std::size_t>(ax) * static_cast<std::size_t>(by));
  auto acc = grid->getAccessor();
  std::vector<std::pair<int, double>> levels, pieces;  // (voxel height, material)
  for (int b = 0; b < by; ++b)
    for (int a = 0; a < ax; ++a) {
      struct Part {
        int i, j;
        double share;
      } parts[4];
      int count = 0;
      int kHigh = std::numeric_limits<int>::min();
      corner.columnsOf(d, a, b, [&](int i, int j, double inVoxel) {
        const double share = inVoxel * d.weight(i, j);
        const auto& ray = d.ray(i, j);
        if (!(share > 0.0) || ray.empty()) return;
        parts[count++] = {i, j, share};
        kHigh = std::max(kHigh, static_cast<int>(std::floor(ray.back().z1 / h + 0.5)));
      });
      if (count == 0) continue;
      // Each interval adds its material w to the voxels it covers whole (a change of the
      // column's level from its first whole voxel on, and back after its last) and its share
      // of each end voxel (a piece): the column is then walked from change to change, not
      // voxel by voxel (a column is tens to thousands of voxels high and mostly whole).
      levels.clear();
      pieces.clear();
      // Columns of one interval over the same heights (a stock's uncut or flat-floored areas,
      // most of a fine grid) add up as that interval with their materials summed.
      const DexelStock::Interval& first = d.ray(parts[0].i, parts[0].j).front();
      bool alike = true;
      double sum = 0.0;
      for (int p = 0; p < count && alike; ++p) {
        const auto& ray = d.ray(parts[p].i, parts[p].j);
        alike = ray.size() == 1 && ray[0].z0 == first.z0 && ray[0].z1 == first.z1;
        sum += ray[0].f * parts[p].share;
      }
      for (int p = 0; p < (alike ? 1 : count); ++p)
        for (const DexelStock::Interval& iv : d.ray(parts[p].i, parts[p].j)) {
          const double w = alike ? sum : iv.f * parts[p].share;
          const int k0 = static_cast<int>(std::floor(iv.z0 / h + 0.5));
          const int k1 = static_cast<int>(std::floor(iv.z1 / h + 0.5));
          if (k0 == k1) {
            pieces.emplace_back(k0, (iv.z1 - iv.z0) / h * w);
            continue;
          }
          pieces.emplace_back(k0, ((k0 + 0.5) * h - iv.z0) / h * w);
          pieces.emplace_back(k1, (iv.z1 - (k1 - 0.5) * h) / h * w);
          if (k0 + 1 < k1) {
            levels.emplace_back(k0 + 1, w);
            levels.emplace_back(k1, -w);
          }
        }
      std::sort(levels.begin(), levels.end());
      std::sort(pieces.begin(), pieces.end());
      FullRun& run = full[static_cast<std::size_t>(b) * static_cast<std::size_t>(ax) +
                          static_cast<std::size_t>(a)];
      // Voxels [k, end) of material v: the column's first run of whole voxels kept as a run
      // (boxes of 8 x 8 columns below), everything else written one by one.
      auto emit = [&](int k, int end, double m) {
        const auto v = static_cast<float>(std::min(1.0, m));
        if (!(v > 0.0f)) return;
        if (v == 1.0f && (run.k0 > run.k1 || run.k1 == k - 1)) {
          if (run.k0 > run.k1) run.k0 = k;
          run.k1 = end - 1;
          return;
        }
        for (int q = k; q < end; ++q)
          acc.setValue(Coord(corner.cx + a, corner.cy + b, q), v);
      };
      double level = 0.0;
      std::size_t li = 0, pi = 0;
      int k = std::min(levels.empty() ? kHigh + 1 : levels.front().first,
                       pieces.empty() ? kHigh + 1 : pieces.front().first);
      while (k <= kHigh) {
        while (li < levels.size() && levels[li].first == k)
          level += levels[li++].second;
        double m = level;  // voxel k: the level and its pieces
        while (pi < pieces.size() && pieces[pi].first == k)
          m += pieces[pi++].second;
        const int next = std::min(li < levels.size() ? levels[li].first : kHigh + 1,
                                  pi < pieces.size() ? pieces[pi].first : kHigh + 1);
        emit(k, k + 1, m);
        if (next > k + 1) emit(k + 1, next, level);
        k = next;
      }
    }
  acc.clear();
  fillFullRuns(*grid, full, ax, by, corner.cx, corner.cy);
  grid->tree().prune();
  return grid;
}

}  // namespace voxel

VoxelStock VoxelStock::fromDexels(const DexelStock& d) {
  auto impl = std::make_unique<Impl>();
  impl->h = d.resolution();
  impl->grid = dexelFractions(d);
  return VoxelStock(std::move(impl));
}

namespace {

/// removed.vdb's three grids, their voxels `factor` times the stock's cell h (voxel I covering
/// the stock's voxels factor I .. factor I + factor - 1, as boxFiltered), metadata `coarser`
/// where factor > 1.
struct RemovedGrids {
  FloatGrid::Ptr removed = FloatGrid::create(0.0f), mrr = FloatGrid::create(0.0f);
  Int32Grid::Ptr step = Int32Grid::create(-1);
  RemovedGrids(double h, int factor) {
    openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(factor * h);
    xf->postTranslate(openvdb::Vec3d(0.5 * (factor - 1) * h));
    const openvdb::GridBase::Ptr grids[3] = {removed, step, mrr};
    const char* names[3] = {"removed", "step", "mrr"};
    for (int k = 0; k < 3; ++k) {
      grids[k]->setTransform(xf->copy());
      grids[k]->setName(names[k]);
      if (factor > 1) grids[k]->insertMeta("coarser", openvdb::Int32Metadata(factor));
    }
    removed->setGridClass(openvdb::GRID_FOG_VOLUME);
  }
};

}  // namespace

int VoxelStock::removedFileFactor(double voxels, double values) {
  int c = 1;
  while (c < 8 && 3.0 * voxels / (c * c * c) > values)
    c *= 2;
  return c;
}

void VoxelStock::writeRemovedVdb(const DexelStock& d, const std::string& path, double values) {
  initVdb();
  const double h = d.resolution();
  // Each voxel column's four dexel columns' losses (per voxel height) merged, then added into
  // the file's voxels: at the rays' cell, or where the removed voxels' three values would
  // exceed `values`, `factor` times coarser (their mean removal, first step and its MRR).
  const ColumnFootprint corner(d);
  const int nx = d.raysX(), ny = d.raysY();
  double lostCells = 0.0;  // (about the voxels at the rays' cell: a voxel column has 4 rays)
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      if (const DexelStock::LostColumn* c = d.removedColumn(i, j))
        lostCells += static_cast<double>(c->cells.size());
  const int factor = removedFileFactor(lostCells, values);
  const int shift = factor == 1 ? 0 : factor == 2 ? 1 : factor == 4 ? 2 : 3;
  const RemovedGrids file(h, factor);
  FloatGrid::Ptr removed = file.removed, mrr = file.mrr;
  Int32Grid::Ptr step = file.step;
  auto racc = removed->getAccessor();
  auto sacc = step->getAccessor();
  auto macc = mrr->getAccessor();
  const std::vector<double>& stepMrr = d.stepMrr();
  struct Height {
    double removed = 0.0;
    int step = std::numeric_limits<int>::max();  // the first step to reach it
  };
  // One row of the file's voxels (y) at a time: x from a0, each column's heights from its k0.
  struct Column {
    int k0 = 0;
    std::vector<Height> at;
  };
  const int a0 = corner.cx >> shift, na = ((corner.cx + nx) >> shift) - a0 + 1;
  std::vector<Column> row(static_cast<std::size_t>(na));
  const double share = 1.0 / (static_cast<double>(factor) * factor * factor);
  auto flush = [&](int y) {
    for (int a = 0; a < na; ++a) {
      Column& column = row[static_cast<std::size_t>(a)];
      for (std::size_t k = 0; k < column.at.size(); ++k) {
        const Height& at = column.at[k];
        if (at.step == std::numeric_limits<int>::max()) continue;
        const Coord c(a0 + a, y, column.k0 + static_cast<int>(k));
        racc.setValue(c, static_cast<float>(std::min(1.0, at.removed * share)));
        sacc.setValue(c, at.step);
        const auto s = static_cast<std::size_t>(at.step);
        macc.setValue(c, static_cast<float>(s < stepMrr.size() ? stepMrr[s] : 0.0));
      }
      column.at.clear();
    }
  };
  // Voxel (x, k) of the row, its column grown to reach it.
  auto cell = [&](int x, int k) -> Height& {
    Column& column = row[static_cast<std::size_t>(x)];
    if (column.at.empty()) column.k0 = k;
    if (k < column.k0) {
      column.at.insert(column.at.begin(), static_cast<std::size_t>(column.k0 - k), Height{});
      column.k0 = k;
    }
    const auto i = static_cast<std::size_t>(k - column.k0);
    if (i >= column.at.size()) column.at.resize(i + 1);
    return column.at[i];
  };
  std::vector<Height> merged;
  int y = (corner.cy + 0) >> shift;
  for (int b = 0; b <= ny; ++b) {
    if (((corner.cy + b) >> shift) != y) {
      flush(y);
      y = (corner.cy + b) >> shift;
    }
    for (int a = 0; a <= nx; ++a) {
      struct Part {
        const DexelStock::LostColumn* column;
        double share;
      } parts[4];
      int count = 0;
      int kLow = std::numeric_limits<int>::max(), kHigh = std::numeric_limits<int>::min();
      corner.columnsOf(d, a, b, [&](int i, int j, double inVoxel) {
        const DexelStock::LostColumn* c = d.removedColumn(i, j);
        if (!c || c->cells.empty()) return;
        parts[count++] = {c, inVoxel};
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
      const int x = ((corner.cx + a) >> shift) - a0;
      for (int k = kLow; k <= kHigh; ++k) {
        const Height& at = merged[static_cast<std::size_t>(k - kLow)];
        if (at.step == std::numeric_limits<int>::max()) continue;
        Height& to = cell(x, k >> shift);
        to.removed += std::min(1.0, at.removed);
        to.step = std::min(to.step, at.step);
      }
    }
  }
  flush(y);
  writeVdb(path, openvdb::GridPtrVec{removed, step, mrr});
}

std::optional<Box3> VoxelStock::fileBounds(const std::string& path) {
  initVdb();
  try {
    openvdb::io::File file(path);
    file.open(false);
    if (!file.hasGrid("stock")) return std::nullopt;
    const openvdb::GridBase::ConstPtr meta = file.readGridMetadata("stock");
    file.close();
    if (meta->getMetadata<openvdb::Int32Metadata>("dexel_coarser")) {
      const auto lo = meta->getMetadata<openvdb::Vec3DMetadata>("material_min");
      const auto hi = meta->getMetadata<openvdb::Vec3DMetadata>("material_max");
      if (!lo || !hi) return std::nullopt;
      Box3 box;
      for (int k = 0; k < 3; ++k) {
        box.min[k] = lo->value()[k];
        box.max[k] = hi->value()[k];
      }
      return box;
    }
    const auto lo = meta->getMetadata<openvdb::Vec3IMetadata>("file_bbox_min");
    const auto hi = meta->getMetadata<openvdb::Vec3IMetadata>("file_bbox_max");
    const openvdb::math::Transform& xf = meta->transform();
    if (!lo || !hi || !xf.isLinear()) return std::nullopt;
    Box3 box;
    const openvdb::Vec3d a = xf.indexToWorld(openvdb::Vec3d(lo->value()) - openvdb::Vec3d(0.5));
    const openvdb::Vec3d b = xf.indexToWorld(openvdb::Vec3d(hi->value()) + openvdb::Vec3d(0.5));
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(a[k], b[k]);
      box.max[k] = std::max(a[k], b[k]);
    }
    return box;
  } catch (const openvdb::Exception&) {
    return std::nullopt;
  }
}

double VoxelStock::fileVolume(const std::string& path, const std::string& name) {
  initVdb();
  FloatGrid::Ptr grid;
  try {
    openvdb::io::File file(path);
    file.open(false);
    if (file.hasGrid(name)) grid = openvdb::gridPtrCast<FloatGrid>(file.readGrid(name));
    file.close();
  } catch (const openvdb::Exception& e) {
    throw Error("cannot read stock '" + path + "' as an OpenVDB file: " + e.what());
  }
  if (!grid) throw Error("stock '" + path + "' has no float grid named '" + name + "'");
  double sum = 0.0;
  for (auto it = grid->cbeginValueOn(); it; ++it)
    sum += static_cast<double>(*it) * static_cast<double>(it.getVoxelCount());
  const double h = grid->transform().voxelSize()[0];
  return sum * h * h * h;
}

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
  if (std::optional<DexelStock> exact = exactDexels(path, h)) return std::move(*exact);
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

void VoxelStock::writeStockVdb(const std::string& path, const DexelStock* rays) const {
  const FloatGrid& grid = *impl_->grid;
  const double h = impl_->h;
  // The level set at the grid's cell, or coarser where that would be large (a fine tool's
  // grid over a whole board): it is for viewing; a run goes on from the fractions and planes.
  const int coarser = fileSurfaceFactor(grid);
  FloatGrid::Ptr surface;
  if (coarser == 1)
    surface = surfaceLevelSet(grid, h, 3);
  else
    surface = surfaceLevelSet(*boxFiltered(grid, h, coarser), coarser * h, 3);
  // The partial voxels' planes (or the stock box's faces), for a run that goes on from here.
  openvdb::Vec3SGrid::Ptr planes[3];
  for (int i = 0; i < 3; ++i) {
    planes[i] = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    planes[i]->setTransform(grid.transform().copy());
    planes[i]->setName("planes_" + std::to_string(i));
    planes[i]->setGridClass(openvdb::GRID_UNKNOWN);
  }
  // (None without planes or a box: a dexel stock's voxels.)
  if (!impl_->planes.empty() || impl_->box) {
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
  openvdb::GridPtrVec grids{impl_->grid, surface, planes[0], planes[1], planes[2]};
  if (rays)
    for (const openvdb::GridBase::Ptr& g : dexelGrids(*rays, grid.transform()))
      grids.push_back(g);
  writeVdb(path, grids);
}

std::size_t VoxelStock::removedVoxels() const {
  return impl_->removed ? static_cast<std::size_t>(impl_->removed->activeVoxelCount()) : 0;
}

void VoxelStock::writeRemovedVdb(const std::string& path, double values) const {
  if (!impl_->removed) throw Error("removed.vdb needs captureRemoved(true) before the removals");
  const int factor = removedFileFactor(static_cast<double>(removedVoxels()), values);
  if (factor == 1) {
    writeVdb(path, openvdb::GridPtrVec{impl_->removed, impl_->step, impl_->mrr});
    return;
  }
  // Leaf by leaf (a factor divides a leaf's 8: its coarse voxels are its own): each coarse
  // voxel the mean removal of the voxels it covers, the first step among them and its MRR.
  const int shift = factor == 2 ? 1 : factor == 4 ? 2 : 3, n = 8 >> shift;
  const RemovedGrids file(impl_->h, factor);
  auto racc = file.removed->getAccessor();
  auto sacc = file.step->getAccessor();
  auto macc = file.mrr->getAccessor();
  const auto step = impl_->step->getConstAccessor();
  const auto mrr = impl_->mrr->getConstAccessor();
  const auto cells = static_cast<std::size_t>(n * n * n);
  std::vector<double> sum(cells);
  std::vector<int> first(cells);
  std::vector<float> firstMrr(cells);
  const double share = 1.0 / (static_cast<double>(factor) * factor * factor);
  for (auto leaf = impl_->removed->tree().cbeginLeaf(); leaf; ++leaf) {
    std::fill(sum.begin(), sum.end(), 0.0);
    std::fill(first.begin(), first.end(), std::numeric_limits<int>::max());
    for (auto v = leaf->cbeginValueOn(); v; ++v) {
      const Coord c = v.getCoord(), l = Leaf::offsetToLocalCoord(v.pos());
      const auto at = static_cast<std::size_t>(((l.x() >> shift) * n + (l.y() >> shift)) * n +
                                               (l.z() >> shift));
      sum[at] += static_cast<double>(*v);
      if (const int s = step.getValue(c); s < first[at]) {
        first[at] = s;
        firstMrr[at] = mrr.getValue(c);
      }
    }
    const Coord o = leaf->origin();
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z) {
          const auto at = static_cast<std::size_t>((x * n + y) * n + z);
          if (first[at] == std::numeric_limits<int>::max()) continue;
          const Coord c((o.x() >> shift) + x, (o.y() >> shift) + y, (o.z() >> shift) + z);
          racc.setValue(c, static_cast<float>(std::min(1.0, sum[at] * share)));
          sacc.setValue(c, first[at]);
          macc.setValue(c, firstMrr[at]);
        }
  }
  writeVdb(path, openvdb::GridPtrVec{file.removed, file.step, file.mrr});
}

}  // namespace engage
