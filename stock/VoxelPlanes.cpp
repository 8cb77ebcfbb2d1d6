#include "stock/VoxelPlanes.h"

#include <algorithm>
#include <cmath>

namespace engage::voxel {
namespace {

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

}  // namespace

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

/// Share of the cube inside the material of planes q (inside both, or with `united` inside
/// either, and inside `outer` if given) and inside all of `extra`; with `centroid`, that
/// part's centroid.
double materialShare(const HalfSpace q[2], bool united, const HalfSpace* extra, int count,
                     Eigen::Vector3d* centroid, const HalfSpace* outer) {
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
bool storedMaterial(const LeafPlanes& planes, std::uint32_t offset, double before, const Box3* box,
                    const Eigen::Vector3d& p, double h, StoredMaterial& m) {
  if (!(before < 1.0)) return false;
  if (planes.get(offset, m.q, m.made, m.held, m.united, &m.outer, &m.madeOuter) != 0) return true;
  if (!box) return false;
  boxFaces(*box, p, h, m.q);
  return true;
}

}  // namespace engage::voxel
