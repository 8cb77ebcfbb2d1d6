#include "engine/physics/Engagement.h"
#include "cutters/Numbers.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

namespace engage {
namespace {

constexpr int kAngleSamples = 30;  ///< intervals over the front half: 6 degrees
constexpr int kMaxSlices = 64;
/// Every this many slices is sampled first (then halfway between any two that differ).
constexpr std::size_t kSliceStride = 8;
constexpr int kRefinements = 10;  ///< halvings of a 6 degree interval: 0.006 degrees
/// Contact is read this many cells outside the surface (MaterialReader).
constexpr double kOutside = 0.1;
/// Where a wall the contact ends at is read again: these many cells beyond the stock's
/// readingReach outside the surface; and how far from the first reading it is looked for (rad).
constexpr std::array<double, 3> kWallOffsets{0.0, 1.0, 2.0};
constexpr double kReach = 30.0 * kPi / 180.0;
constexpr int kWallSamples = 20;  ///< over 2 kReach: 3 degrees
/// A wall is read at most this many times its offset out in a slice's plane (sin 30 deg: the
/// edge's surface at a lead angle kappa lies offset / sin(kappa) away horizontally).
constexpr double kSteepest = 0.5;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Boundaries of neighbouring slices this close are one wall's (rad: a hundredth of a degree).
constexpr double kSameBoundary = kPi / 18000.0;
/// Arcs shorter than this are not contact (a cell where three faces meet, the stock's top, a
/// wall and the cut, may read as material just above the top; a contact this short carries
/// no load), nor are gaps this short between arcs: 2 degrees.
constexpr double kShortestArc = kPi / 90.0;
/// Wall points whose offsets from the path's centre line agree to this share of a cell lie
/// on a wall parallel to the path.
constexpr double kParallel = 0.05;

/// The offset of a point p (horizontal, from the axis) from the path's centre line towards the
/// side phi = 0 (`side`; `feed` the feed direction): on an arc of signed curvature
/// `curvature` (+ turning left), its distance from the arc's centre less the path's radius,
/// signed so. Monotonic in phi over the front half for points on the edge's circle.
double pathOffset(const Eigen::Vector2d& p, const Eigen::Vector2d& feed,
                  const Eigen::Vector2d& side, double curvature) {
  if (curvature == 0.0) return p.dot(side);
  const Eigen::Vector2d left(-feed.y(), feed.x());
  const Eigen::Vector2d centre = (1.0 / curvature) * left;  // + curvature: on the left
  // The side phi = 0 points away from the centre when the centre is on the other side.
  const double away = curvature * side.dot(left) < 0.0 ? 1.0 : -1.0;
  return away * ((p - centre).norm() - 1.0 / std::abs(curvature));
}

/// pathOffset of the point of the edge's circle (radius `radius` about the axis) at immersion
/// angle phi.
double edgeOffset(double radius, double phi, const Eigen::Vector2d& feed,
                  const Eigen::Vector2d& side, double curvature) {
  return pathOffset(radius * (std::sin(phi) * feed + std::cos(phi) * side), feed, side, curvature);
}

/// The middle of `cutter`'s edge between heights z0 and z1 by length along the profile: the
/// profile in 16 chords (the first chord of a ball's tip strays from its arc by a few 1e-4 of
/// its length).
EdgeSlice::Middle edgeMiddle(const AptCutter& cutter, double z0, double z1) {
  constexpr int kChords = 16;
  std::array<Eigen::Vector2d, kChords + 1> p;
  std::array<double, kChords + 1> along{};
  for (int i = 0; i <= kChords; ++i) {
    const double z = z0 + (z1 - z0) * i / kChords;
    p[static_cast<std::size_t>(i)] = {cutter.radiusAt(z), z};
    if (i > 0)
      along[static_cast<std::size_t>(i)] =
          along[static_cast<std::size_t>(i - 1)] +
          (p[static_cast<std::size_t>(i)] - p[static_cast<std::size_t>(i - 1)]).norm();
  }
  EdgeSlice::Middle m;
  m.length = along.back();
  std::size_t j = 0;
  while (j + 2 < along.size() && along[j + 1] < 0.5 * m.length)
    ++j;
  const Eigen::Vector2d chord = p[j + 1] - p[j];
  const double piece = along[j + 1] - along[j];
  const double f = piece > 0.0 ? (0.5 * m.length - along[j]) / piece : 0.5;
  m.radius = p[j].x() + f * chord.x();
  m.kappa = std::atan2(chord.y(), chord.x());
  return m;
}

/// The stock's material read from a tool's frame (Stock::materialReader): points given in the
/// frame turned about the tip by `toPart` (its z the tool's axis) are read where they lie on
/// the part. An upright tool's points are read as they are.
class FramedReader {
 public:
  FramedReader(const Stock& stock, std::size_t afterStep, const Eigen::Vector3d& tip,
               const Eigen::Matrix3d& toPart)
      : reader_(stock.materialReader(afterStep)),
        tip_(tip),
        toPart_(toPart),
        upright_(toPart.isIdentity(0.0)) {}

  const std::vector<std::uint8_t>& read(const std::vector<Eigen::Vector3d>& points) {
    if (upright_) return reader_->read(points);
    turned_.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
      turned_[i] = tip_ + toPart_ * (points[i] - tip_);
    return reader_->read(turned_);
  }

 private:
  std::unique_ptr<MaterialReader> reader_;
  Eigen::Vector3d tip_;
  Eigen::Matrix3d toPart_;
  bool upright_;
  std::vector<Eigen::Vector3d> turned_;
};

}  // namespace

bool FaceContact::any() const {
  return std::any_of(onMaterial.begin(), onMaterial.end(), [](std::uint8_t b) { return b != 0; });
}

FaceContact measureFace(const Stock& stock, const AptCutter& cutter, const Eigen::Vector3d& tip,
                        const Eigen::Vector2d& feedDir, bool clockwise, std::size_t afterStep,
                        const Eigen::Matrix3d& toPart) {
  constexpr int kRings = 8, kFaceAngles = 72;
  FaceContact out;
  const Eigen::Vector2d u =
      feedDir.norm() > 0.0 ? Eigen::Vector2d(feedDir.normalized()) : Eigen::Vector2d(1.0, 0.0);
  const Eigen::Vector2d left(-u.y(), u.x());
  const Eigen::Vector2d v = clockwise ? left : Eigen::Vector2d(-left);
  out.feed = u;
  out.side = v;
  // The flat end: the bottom's radius where the profile starts level (radiusAt(0)), if the
  // profile's first piece is level (a flat or bull end; not a ball's or a cone's point).
  const auto& profile = cutter.profile();
  if (profile.empty() || profile.front().start.y() != 0.0 || profile.front().end.y() != 0.0)
    return out;
  out.radius = profile.front().end.x();
  if (!(out.radius > 0.0)) return out;
  out.rings = kRings;
  out.angles = kFaceAngles;
  std::vector<Eigen::Vector3d> points;
  points.reserve(kRings * kFaceAngles);
  const double below = tip.z() - kOutside * stock.resolution();
  for (int i = 0; i < kRings; ++i) {
    const double r = (i + 0.5) * out.radius / kRings;
    for (int k = 0; k < kFaceAngles; ++k) {
      const double phi = (k + 0.5) * 2.0 * kPi / kFaceAngles;
      const Eigen::Vector2d p = tip.head<2>() + r * (std::sin(phi) * u + std::cos(phi) * v);
      points.emplace_back(p.x(), p.y(), below);
    }
  }
  FramedReader reader(stock, afterStep, tip, toPart);
  out.onMaterial = reader.read(points);
  return out;
}

// One function: it runs for every cutting step, and its slices, angular samples, boundary
// refinements and wall readings share one reader of the stock.
EdgeEngagement measureEngagement(const Stock& stock, const AptCutter& cutter,
                                 const Eigen::Vector3d& tip, const Eigen::Vector2d& feedDir,
                                 bool clockwise, double zTop, double curvature,
                                 std::size_t afterStep, const Eigen::Matrix3d& toPart) {
  EdgeEngagement out;
  out.entry = out.exit = std::numeric_limits<double>::quiet_NaN();
  const double h = stock.resolution();
  zTop = std::min(zTop, cutter.height());
  if (!(zTop > 0.0) || !(feedDir.norm() > 0.0)) return out;
  const Eigen::Vector2d u = feedDir.normalized();
  const Eigen::Vector2d left(-u.y(), u.x());
  const Eigen::Vector2d v = clockwise ? left : Eigen::Vector2d(-left);
  out.feed = u;
  out.side = v;
  out.curvature = curvature;
  const int n = std::clamp(static_cast<int>(std::ceil(zTop / h)), 1, kMaxSlices);
  const double dz = zTop / n;
  const double eps = kOutside * h;
  FramedReader reader(stock, afterStep, tip, toPart);

  std::vector<EdgeSlice> slices;
  std::vector<std::array<double, 2>> lead;  // per slice: sin and cos of its lead angle
  for (int k = 0; k < n; ++k) {
    EdgeSlice s;
    s.z = (k + 0.5) * dz;
    s.dz = dz;
    s.radius = cutter.radiusAt(s.z);
    if (!(s.radius > 1e-9)) continue;
    const double d = 1e-4;  // the profile is analytic: a central difference to 1e-8
    const double slope = (cutter.radiusAt(s.z + d) - cutter.radiusAt(std::max(0.0, s.z - d))) /
                         (s.z + d - std::max(0.0, s.z - d));
    s.kappa = std::atan2(1.0, slope);
    slices.push_back(s);
    lead.push_back({std::sin(s.kappa), std::cos(s.kappa)});
  }
  // The edge's direction (from the axis) at immersion angle phi.
  auto direction = [&](double phi) -> Eigen::Vector2d {
    return std::sin(phi) * u + std::cos(phi) * v;
  };
  // The point `offset` outside the surface at height z of slice k (its radius there `r`),
  // in direction e (direction(phi)).
  auto pointAt = [&](std::size_t k, double z, double r, const Eigen::Vector2d& e, double offset) {
    const double reach = r + offset * lead[k][0];
    return Eigen::Vector3d(tip.x() + reach * e.x(), tip.y() + reach * e.y(),
                           tip.z() + z - offset * lead[k][1]);
  };
  auto point = [&](std::size_t k, const Eigen::Vector2d& e, double offset) {
    return pointAt(k, slices[k].z, slices[k].radius, e, offset);
  };
  std::vector<Eigen::Vector3d> points;
  points.reserve(slices.size() * (kAngleSamples + 1));
  std::array<Eigen::Vector2d, kAngleSamples + 1> sample;  // the samples' directions
  for (int i = 0; i <= kAngleSamples; ++i)
    sample[static_cast<std::size_t>(i)] = direction(kPi * i / kAngleSamples);
  // The samples of every kSliceStride-th slice (and the last), then of the slice halfway
  // between two sampled ones where they differ: in their samples, or in radius or lead angle.
  // A slice between two that agree takes their samples (source) and later their contact: a
  // wall parallel to the axis is read once, not at every height.
  const std::size_t count = slices.size();
  std::vector<std::uint8_t> share(count * (kAngleSamples + 1), 0);
  std::vector<std::size_t> source(count, count);  // count: not known yet
  auto sampleSlices = [&](const std::vector<std::size_t>& list) {
    points.clear();
    for (const std::size_t k : list) {
      const EdgeSlice& s = slices[k];
      const double reach = s.radius + eps * lead[k][0];
      const double z = tip.z() + s.z - eps * lead[k][1];
      for (const Eigen::Vector2d& e : sample)
        points.emplace_back(tip.x() + reach * e.x(), tip.y() + reach * e.y(), z);
    }
    const std::vector<std::uint8_t>& in = reader.read(points);
    for (std::size_t q = 0; q < list.size(); ++q) {
      std::copy_n(in.begin() + static_cast<std::ptrdiff_t>(q * (kAngleSamples + 1)),
                  kAngleSamples + 1,
                  share.begin() + static_cast<std::ptrdiff_t>(list[q] * (kAngleSamples + 1)));
      source[list[q]] = list[q];
    }
  };
  auto agree = [&](std::size_t a, std::size_t b) {
    return slices[a].radius == slices[b].radius && slices[a].kappa == slices[b].kappa &&
           std::equal(share.begin() + static_cast<std::ptrdiff_t>(a * (kAngleSamples + 1)),
                      share.begin() + static_cast<std::ptrdiff_t>((a + 1) * (kAngleSamples + 1)),
                      share.begin() + static_cast<std::ptrdiff_t>(b * (kAngleSamples + 1)));
  };
  if (count > 0) {
    std::vector<std::size_t> list;
    for (std::size_t k = 0; k < count; k += kSliceStride)
      list.push_back(k);
    if (list.back() != count - 1) list.push_back(count - 1);
    sampleSlices(list);
    std::vector<std::array<std::size_t, 2>> open;  // sampled ends with slices between
    for (std::size_t q = 0; q + 1 < list.size(); ++q)
      if (list[q + 1] > list[q] + 1) open.push_back({list[q], list[q + 1]});
    while (!open.empty()) {
      std::vector<std::array<std::size_t, 2>> next;
      list.clear();
      for (const auto& [a, b] : open) {
        const std::size_t mid = (a + b) / 2;
        if (agree(a, b) && slices[mid].radius == slices[a].radius) {
          for (std::size_t k = a + 1; k < b; ++k)
            source[k] = a;
          continue;
        }
        list.push_back(mid);
        if (mid > a + 1) next.push_back({a, mid});
        if (b > mid + 1) next.push_back({mid, b});
      }
      if (!list.empty()) sampleSlices(list);
      open = std::move(next);
    }
  }

  // Boundaries between samples of the sampled slices, refined by halving: (slice, low angle,
  // high angle, low side in contact).
  struct Edge {
    std::size_t slice;
    double lo, hi;
    bool loIn;
  };
  std::vector<Edge> edges;
  for (std::size_t k = 0; k < count; ++k)
    for (int i = 0; i < kAngleSamples && source[k] == k; ++i) {
      const bool a = share[k * (kAngleSamples + 1) + static_cast<std::size_t>(i)] != 0;
      const bool b = share[k * (kAngleSamples + 1) + static_cast<std::size_t>(i) + 1] != 0;
      if (a != b) edges.push_back({k, kPi * i / kAngleSamples, kPi * (i + 1) / kAngleSamples, a});
    }
  // A wall's point `offset` beyond the edge in the slice's own plane (the wall's trace there;
  // the distance from the edge's surface at least `offset` on a sloping side).
  auto wallPoint = [&](std::size_t k, const Eigen::Vector2d& e, double offset) {
    const EdgeSlice& s = slices[k];
    const double reach = s.radius + offset / std::max(lead[k][0], kSteepest);
    return Eigen::Vector3d(tip.x() + reach * e.x(), tip.y() + reach * e.y(), tip.z() + s.z);
  };
  // (The directions of an edge's ends carried along: the middle's is their normalized sum,
  // its angle less than pi.)
  std::vector<std::array<Eigen::Vector2d, 2>> ends;
  auto refine = [&](std::vector<Edge>& list, double offset, int rounds, bool wall = false) {
    ends.resize(list.size());
    for (std::size_t i = 0; i < list.size(); ++i)
      ends[i] = {direction(list[i].lo), direction(list[i].hi)};
    for (int round = 0; round < rounds && !list.empty(); ++round) {
      points.clear();
      for (std::size_t i = 0; i < list.size(); ++i) {
        const Eigen::Vector2d e = (ends[i][0] + ends[i][1]).normalized();
        points.push_back(wall ? wallPoint(list[i].slice, e, offset)
                              : point(list[i].slice, e, offset));
      }
      const std::vector<std::uint8_t>& mid = reader.read(points);
      for (std::size_t i = 0; i < list.size(); ++i) {
        Edge& e = list[i];
        const bool low = (mid[i] != 0) == e.loIn;
        (low ? e.lo : e.hi) = 0.5 * (e.lo + e.hi);
        ends[i][low ? 0 : 1] = (ends[i][0] + ends[i][1]).normalized();
      }
    }
  };
  refine(edges, eps, kRefinements);
  // The boundary read just outside the surface lies in a cell the cut has just crossed too,
  // where the stock holds two surfaces in one cell (the wall the contact ends at and the cut)
  // only approximately. The wall is read again where no cell of the cut reaches it, at
  // kWallOffsets cells out (each within kReach of the first reading), and its trace through
  // those three points (a circle; a line through the first two where the third is missing or
  // in line) followed back to the cutter's surface: exact for a plane or a cylindrical wall
  // parallel to the axis. Where the first two are missing (a wall ending there, a grazing
  // contact) or the trace does not lead back to the surface within kReach, the first reading
  // stays.
  // A boundary where the slice below had the same one (the same radius and lead angle, the
  // same side, within a hundredth of a degree: a wall parallel to the axis) takes that one's
  // result instead of reading the wall again.
  std::vector<double> boundary(edges.size());
  std::vector<std::size_t> same(edges.size());  // the edge whose wall this one takes
  // The edges of the sampled slice below the current edge's: [below, belowEnd).
  for (std::size_t i = 0, below = 0, belowEnd = 0, start = 0; i < edges.size(); ++i) {
    if (i > 0 && edges[i].slice != edges[i - 1].slice) {
      below = start;
      belowEnd = i;
      start = i;
    }
    boundary[i] = 0.5 * (edges[i].lo + edges[i].hi);
    same[i] = i;
    for (std::size_t j = below; j < belowEnd; ++j) {
      const EdgeSlice &a = slices[edges[i].slice], &b = slices[edges[j].slice];
      if (edges[j].loIn == edges[i].loIn && std::abs(boundary[j] - boundary[i]) < kSameBoundary &&
          a.radius == b.radius && a.kappa == b.kappa) {
        same[i] = same[j];
        break;
      }
    }
  }
  std::vector<Edge> walls;  // the edges whose walls are read
  std::vector<std::size_t> wallOf;
  for (std::size_t i = 0; i < edges.size(); ++i)
    if (same[i] == i) {
      walls.push_back(edges[i]);
      wallOf.push_back(i);
    }
  constexpr std::size_t kWalls = kWallOffsets.size();
  std::array<std::vector<Eigen::Vector2d>, kWalls> wallAt;       // [k][q]: walls[q]'s, or NaN
  std::vector<std::array<std::uint8_t, kWallSamples + 1>> rows;  // a wall's samples read
  std::vector<std::size_t> pending;                              // walls without a change yet
  std::array<std::array<double, 2>, kWallSamples + 1> turn;      // cos, sin of sample j's turn
  std::vector<std::array<double, 3>> firstAt;  // per wall: cos, sin of the first reading, it
  for (const Edge& e : walls) {
    const double at = 0.5 * (e.lo + e.hi);
    firstAt.push_back({std::cos(at), std::sin(at), at});
  }
  for (std::size_t j = 0; j <= kWallSamples; ++j) {
    const double d = -kReach + 2.0 * kReach * static_cast<double>(j) / kWallSamples;
    turn[j] = {std::cos(d), std::sin(d)};
  }
  for (std::size_t k = 0; k < kWalls; ++k) {
    const double offset = (stock.readingReach() + kWallOffsets[k]) * h;
    // Sampled every 3 degrees within kReach of the first reading: of the changes of the same
    // sense (the contact's side below if it was below), the one nearest that reading (a thin
    // wall of stock beyond may hold a second change). Read outwards from the first reading,
    // a pair of samples a round, until a wall has its change: the gap between a change and the
    // first reading grows with its rank on either side, by a sample on the other, so the
    // first rank that holds one holds the nearest.
    // The j-th wall sample about the first reading `at` (unclamped, and as sampled).
    auto unclamped = [](double at, int j) { return at - kReach + 2.0 * kReach * j / kWallSamples; };
    auto sampleAngle = [&](double at, int j) { return std::clamp(unclamped(at, j), 0.0, kPi); };
    // Wall q's: the first reading's direction turned by the sample's angle from it, unless
    // clamped.
    auto sampleDirection = [&](std::size_t q, int j) -> Eigen::Vector2d {
      const double phi = unclamped(firstAt[q][2], j);
      if (phi < 0.0 || phi > kPi) return direction(std::clamp(phi, 0.0, kPi));
      const auto& [c, sn] = turn[static_cast<std::size_t>(j)];
      const double ca = firstAt[q][0], sa = firstAt[q][1];
      return (ca * c - sa * sn) * v + (sa * c + ca * sn) * u;
    };
    constexpr int kMiddle = kWallSamples / 2;  // the sample at the first reading
    rows.assign(walls.size(), {});
    pending.resize(walls.size());
    for (std::size_t q = 0; q < walls.size(); ++q)
      pending[q] = q;
    std::vector<Edge> found;
    std::vector<std::size_t> of;
    for (int rank = 0; rank < kMiddle && !pending.empty(); ++rank) {
      // This rank's changes lie between samples kMiddle - 1 - rank and kMiddle - rank (below)
      // and kMiddle + rank and kMiddle + 1 + rank (above).
      const std::array<int, 3> first{kMiddle - 1, kMiddle, kMiddle + 1};
      const std::array<int, 2> more{kMiddle - 1 - rank, kMiddle + 1 + rank};
      const int* newSamples = rank == 0 ? first.data() : more.data();
      const std::size_t newCount = rank == 0 ? first.size() : more.size();
      points.clear();
      for (const std::size_t q : pending)
        for (std::size_t t = 0; t < newCount; ++t)
          points.push_back(wallPoint(walls[q].slice, sampleDirection(q, newSamples[t]), offset));
      const std::vector<std::uint8_t>& in = reader.read(points);
      std::size_t kept = 0;
      for (std::size_t p = 0; p < pending.size(); ++p) {
        const std::size_t q = pending[p];
        const Edge& e = walls[q];
        auto& row = rows[q];
        for (std::size_t t = 0; t < newCount; ++t)
          row[static_cast<std::size_t>(newSamples[t])] = in[p * newCount + t];
        const double at = firstAt[q][2];
        double best = kNaN, bestLo = 0.0, bestHi = 0.0;
        for (const int j : {kMiddle - 1 - rank, kMiddle + rank}) {
          const auto ju = static_cast<std::size_t>(j);
          if ((row[ju] != 0) != e.loIn || (row[ju + 1] != 0) == e.loIn) continue;
          const double lo = sampleAngle(at, j), hi = sampleAngle(at, j + 1);
          const double gap = std::abs(0.5 * (lo + hi) - at);
          if (std::isnan(best) || gap < best) {
            best = gap;
            bestLo = lo;
            bestHi = hi;
          }
        }
        if (std::isnan(best)) {
          pending[kept++] = q;
          continue;
        }
        found.push_back({e.slice, bestLo, bestHi, e.loIn});
        of.push_back(q);
      }
      pending.resize(kept);
    }
    refine(found, offset, kRefinements, true);
    wallAt[k].assign(walls.size(), Eigen::Vector2d::Constant(kNaN));
    for (std::size_t q = 0; q < found.size(); ++q) {
      const Eigen::Vector3d p =
          wallPoint(found[q].slice, direction(0.5 * (found[q].lo + found[q].hi)), offset);
      wallAt[k][of[q]] = Eigen::Vector2d(p.x() - tip.x(), p.y() - tip.y());
    }
  }
  for (std::size_t q = 0; q < walls.size(); ++q) {
    const std::size_t i = wallOf[q];
    const Eigen::Vector2d a = wallAt[0][q], b = wallAt[1][q], c = wallAt[2][q];
    if (!a.allFinite() || !b.allFinite()) continue;
    const double r = slices[edges[i].slice].radius;
    // A wall parallel to the path (concentric with an arc): its points lie at one offset from
    // the path's centre line, and the edge meets it where its own offset is that, to the
    // bisection's precision however shallow the meeting.
    {
      double lo = pathOffset(a, u, v, curvature), hi = lo, sum = lo;
      int found = 1;
      for (const Eigen::Vector2d& w : {b, c})
        if (w.allFinite()) {
          const double o = pathOffset(w, u, v, curvature);
          lo = std::min(lo, o);
          hi = std::max(hi, o);
          sum += o;
          ++found;
        }
      const double at = sum / found;
      auto offsetAt = [&](double phi) { return edgeOffset(r, phi, u, v, curvature); };
      if (found == 3 && hi - lo <= kParallel * h && at <= offsetAt(0.0) && at >= offsetAt(kPi)) {
        double p0 = 0.0, p1 = kPi;  // the offset falls with phi
        for (int round = 0; round < 50; ++round) {
          const double mid = 0.5 * (p0 + p1);
          (offsetAt(mid) > at ? p0 : p1) = mid;
        }
        const double phi = 0.5 * (p0 + p1);
        if (std::abs(phi - boundary[i]) <= kReach) {
          boundary[i] = phi;
          continue;
        }
      }
    }
    // Else where the wall's trace meets the edge's circle (radius r about the axis): the
    // circle through the three points, or the line through the first two; the meeting
    // nearest a.
    std::array<Eigen::Vector2d, 2> meet;
    int meets = 0;
    const double cross = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (c.allFinite() && std::abs(cross) > 1e-9 * (b - a).squaredNorm()) {
      // The circumcentre w of a, b, c.
      const double a2 = a.squaredNorm(), b2 = b.squaredNorm(), c2 = c.squaredNorm();
      const double den =
          2.0 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
      const Eigen::Vector2d w(
          (a2 * (b.y() - c.y()) + b2 * (c.y() - a.y()) + c2 * (a.y() - b.y())) / den,
          (a2 * (c.x() - b.x()) + b2 * (a.x() - c.x()) + c2 * (b.x() - a.x())) / den);
      const double rw = (a - w).norm(), dw = w.norm();
      const double along = (r * r - rw * rw + dw * dw) / (2.0 * dw);
      const double across2 = r * r - along * along;
      if (dw > 0.0 && across2 >= 0.0) {
        const Eigen::Vector2d e = w / dw, across(-e.y(), e.x());
        meet[meets++] = along * e + std::sqrt(across2) * across;
        meet[meets++] = along * e - std::sqrt(across2) * across;
      }
    } else {
      // |a + t (b - a)| = r.
      const Eigen::Vector2d d = b - a;
      const double qa = d.squaredNorm(), qb = 2.0 * a.dot(d), qc = a.squaredNorm() - r * r;
      const double disc = qb * qb - 4.0 * qa * qc;
      if (qa > 1e-18 && disc >= 0.0)
        for (const double t :
             {(-qb + std::sqrt(disc)) / (2.0 * qa), (-qb - std::sqrt(disc)) / (2.0 * qa)})
          meet[meets++] = a + t * d;
    }
    if (meets == 0) continue;
    const Eigen::Vector2d m =
        meets == 2 && (meet[1] - a).norm() < (meet[0] - a).norm() ? meet[1] : meet[0];
    const double phi = std::atan2(m.dot(u), m.dot(v));
    if (phi >= -1e-9 && phi <= kPi + 1e-9 && std::abs(phi - boundary[i]) <= kReach)
      boundary[i] = std::clamp(phi, 0.0, kPi);
  }
  for (std::size_t i = 0; i < edges.size(); ++i)
    if (same[i] != i) boundary[i] = boundary[same[i]];
  // Arcs: runs of samples in contact, their ends at the refined boundaries; a slice between
  // two that agreed takes its source's.
  std::vector<std::size_t> kept;  // the index in slices of each of out.slices
  std::size_t next = 0;           // edges are in slice, angle order
  for (std::size_t k = 0; k < count; ++k) {
    EdgeSlice& s = slices[k];
    if (source[k] != k) {
      s.arcs = slices[source[k]].arcs;
    } else {
      const std::uint8_t* row = share.data() + k * (kAngleSamples + 1);
      double start = -1.0;
      for (int i = 0; i <= kAngleSamples; ++i) {
        const bool in = row[i] != 0;
        if (i == 0 && in) start = 0.0;
        if (i > 0 && (row[i - 1] != 0) != in) {
          const double at = boundary[next++];
          if (in)
            start = at;
          else
            s.arcs.push_back({start, at});
        }
        if (i == kAngleSamples && in) s.arcs.push_back({start, kPi});
      }
      // Arcs whose ends, followed to the wall, overlap or leave less than kShortestArc
      // between them are one (a cell the cut crossed read as air inside the contact); then
      // arcs shorter than that are dropped.
      std::sort(s.arcs.begin(), s.arcs.end());
      std::vector<std::array<double, 2>> joined;
      for (const auto& a : s.arcs)
        if (!joined.empty() && a[0] <= joined.back()[1] + kShortestArc)
          joined.back()[1] = std::max(joined.back()[1], a[1]);
        else
          joined.push_back(a);
      s.arcs.clear();
      for (const auto& a : joined)
        if (a[1] - a[0] >= kShortestArc) s.arcs.push_back(a);
    }
    if (s.arcs.empty()) continue;
    out.entry = std::isnan(out.entry) ? s.arcs.front()[0] : std::min(out.entry, s.arcs.front()[0]);
    out.exit = std::isnan(out.exit) ? s.arcs.back()[1] : std::max(out.exit, s.arcs.back()[1]);
    out.slices.push_back(s);
    kept.push_back(k);
  }
  if (out.slices.empty()) return out;
  // The contact's top and bottom to a slice's middle: found between the last slice in contact
  // and the next one's middle (or the flutes' top), at the middle and just inside both ends of
  // the end slice's widest arc (a face the tool meets at a slant reaches highest at an end),
  // the furthest of them, and that slice made to end there.
  auto widestAngles = [](const EdgeSlice& s) {
    std::array<double, 2> best = s.arcs.front();
    for (const auto& a : s.arcs)
      if (a[1] - a[0] > best[1] - best[0]) best = a;
    const double inside = std::min(kShortestArc / 4.0, 0.25 * (best[1] - best[0]));
    return std::array<double, 3>{0.5 * (best[0] + best[1]), best[0] + inside, best[1] - inside};
  };
  // Slice k's point at height z, angle phi.
  auto at = [&](std::size_t k, double z, double phi) {
    return pointAt(k, z, cutter.radiusAt(z), direction(phi), eps);
  };
  auto bisect = [&](std::size_t k, double in, double air, double phi) {
    points.assign({at(k, air, phi)});
    if (reader.read(points)[0] != 0 || !(cutter.radiusAt(air) > 1e-9)) return kNaN;
    for (int round = 0; round < kRefinements + 4; ++round) {
      const double mid = 0.5 * (in + air);
      points.assign({at(k, mid, phi)});
      (reader.read(points)[0] != 0 ? in : air) = mid;
    }
    return 0.5 * (in + air);
  };
  // Slice k's contact followed from its middle towards `air` (then `further`, where the first
  // is in material at an angle), at the angles of widestAngles: the furthest end found (NaN:
  // none).
  auto furthest = [&](std::size_t k, const EdgeSlice& s, double air, double further) {
    double end = kNaN;
    for (const double phi : widestAngles(s)) {
      double e = bisect(k, s.z, air, phi);
      if (std::isnan(e) && !std::isnan(further)) e = bisect(k, s.z, further, phi);
      if (!std::isnan(e) && (std::isnan(end) || std::abs(e - s.z) > std::abs(end - s.z))) end = e;
    }
    return end;
  };
  {
    EdgeSlice& top = out.slices.back();
    const bool last = kept.back() + 1 == slices.size();
    const double bottom = top.z - 0.5 * top.dz;
    // Up to the next slice's middle, or the one after where the next's contact at an angle
    // was too short to keep.
    const double end = furthest(kept.back(), top, last ? zTop : top.z + top.dz,
                                last ? kNaN : std::min(zTop, top.z + 2.0 * top.dz));
    if (!std::isnan(end)) {
      top.dz = end - bottom;
      top.z = 0.5 * (bottom + end);
      top.radius = cutter.radiusAt(top.z);
    }
  }
  {
    EdgeSlice& low = out.slices.front();
    const double top = low.z + 0.5 * low.dz;
    if (kept.front() > 0 && low.z - low.dz > 0.0) {
      const double end = furthest(kept.front(), low, low.z - low.dz,
                                  low.z - 2.0 * low.dz > 0.0 ? low.z - 2.0 * low.dz : kNaN);
      if (!std::isnan(end)) {
        low.dz = top - end;
        low.z = 0.5 * (top + end);
        low.radius = cutter.radiusAt(low.z);
      }
    }
  }
  for (EdgeSlice& s : out.slices)
    s.middle = edgeMiddle(cutter, s.z - 0.5 * s.dz, s.z + 0.5 * s.dz);
  return out;
}

double radialDepth(const EdgeEngagement& e) {
  if (!e.any()) return kNaN;
  double widest = 0.0;
  for (const EdgeSlice& s : e.slices) {
    double sum = 0.0;
    for (const auto& a : s.arcs)
      sum += std::abs(edgeOffset(s.radius, a[0], e.feed, e.side, e.curvature) -
                      edgeOffset(s.radius, a[1], e.feed, e.side, e.curvature));
    widest = std::max(widest, sum);
  }
  return widest;
}

double axialDepth(const EdgeEngagement& e) {
  if (!e.any()) return kNaN;
  const EdgeSlice& low = e.slices.front();
  const EdgeSlice& top = e.slices.back();
  return top.z + 0.5 * top.dz - (low.z - 0.5 * low.dz);
}

}  // namespace engage
