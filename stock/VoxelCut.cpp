#include "stock/VoxelCut.h"

#include "stock/CubeClip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>

namespace engage::voxel {
namespace {

/// remaining() for a voxel whose material m is inside either of its planes (an inside
/// corner: the floor and wall a flat bottom's rim left), within its outer plane.
template <typename Kept>
double cutCorner(const Sweep& sweep, const Eigen::Vector3d& p, double h, double before,
                 LeafPlanes& planes, std::uint32_t offset, int serial, StoredMaterial& m,
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
  // plane. (The face alone is needed where a wall is cut back past a corner's floor and wall:
  // otherwise a plane it cut away would be kept.)
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
    // (the two floors) would drop the wall, which the next pass would then cut into again.
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
const CornerProbe& probeCorner(const Sweep& sweep, const Eigen::Vector3i& corner, double h,
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
/// (of a partial voxel, the material its planes hold); 4^3 is the coarsest split that keeps
/// ramps and helical bores within half a percent per step at D/20 (docs/voxel-stock.md). The
/// sub-cubes are cut one by one, not by the rule for one plane nested in the last step's:
/// each step's rim, behind a descending flat end mill, dips below the last step's floor
/// across a corner of the voxel. The voxel keeps the plane normal to the centre's gradient `n`
/// that leaves its share, and the old plane that goes with it best. Out of line: its
/// sub-cubes' planes would weigh on the common path's frame.
[[gnu::noinline]] double rimRemaining(const Sweep& sweep, const Eigen::Vector3d& p, double h,
                                      double before, LeafPlanes& planes, std::uint32_t offset,
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
    const Eigen::Vector3i voxel(static_cast<int>(std::lround(p.x() / h)),
                                static_cast<int>(std::lround(p.y() / h)),
                                static_cast<int>(std::lround(p.z() / h)));
    for (int c = 0; c < 8; ++c) {
      const CornerProbe& probe = probeCorner(
          sweep, voxel + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1), h, sweepId);
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
      // one at 15 deg or more to it (corners under a flat bottom give its plane several times,
      // and a wedge of two floors would keep no wall).
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
    // Beyond its half-diagonal a sub-cube is wholly in or out whatever its plane's normal.
    constexpr double kSubReach = 0.8660254037844386 / kSide;  // sqrt(3) / 2, in voxels
    for (int c = 0; c < kCount; ++c) {
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      const double dk = sweep.distanceWithin(p + h * centre(c), kSubReach * h, &g);
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
      // (Not offered without the outer plane: slower, and no more exact.)
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

}  // namespace

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
/// D / h = 20 (docs/accuracy.md). One function: it runs for every voxel a step reaches; its
/// common path (one plane, no stored planes) stays inline and the rare ones are out of line
/// (rimRemaining, cutCorner).
double remaining(const Sweep& sweep, const Eigen::Vector3d& p, double h, double before,
                 LeafPlanes& planes, std::uint32_t offset, int serial, const Box3* box,
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
    // voxel holds the surface's share to second order (the tangent plane alone takes too much
    // of a ball's tip entering fresh material). Not the mean over a unit square, h trace(K) /
    // 24: cheaper, but half the sagitta on a wall at 45 deg to the grid.
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

}  // namespace engage::voxel
