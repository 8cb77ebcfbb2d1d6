#include "stock/DexelMesh.h"

#include "stock/DexelStock.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace engage {
namespace {

/// Heights along a ray closer than this are one (mm): the floor's and a gap's.
constexpr double kSameHeight = 1e-9;

/// The stock as heights over its box: per ray (row by row, x fastest) its column's material
/// over the floor as a mean height, the floor and the box's far faces.
struct Heights {
  int nx = 0, ny = 0;
  double h = 0.0, x0 = 0.0, y0 = 0.0, xEnd = 0.0, yEnd = 0.0, floor = 0.0;
  std::vector<double> z;
  /// A ray's position: the rim rays on the box's faces, the others at their columns' centres.
  double x(int i) const { return i == 0 ? x0 : (i == nx - 1 ? xEnd : x0 + (i + 0.5) * h); }
  double y(int j) const { return j == 0 ? y0 : (j == ny - 1 ? yEnd : y0 + (j + 0.5) * h); }
};

/// The heights of `d`, or nullopt where it is not a heightfield over a flat floor. A column's
/// height is the floor plus the length of its material weighted by each interval's share of
/// the column (what the column holds, as a height: a wall crossing the column stands where the
/// column's share puts it, between two rays); the box's last row and column by their share of
/// the box (the box's far faces: the most their floor's intervals hold).
std::optional<Heights> heights(const DexelStock& d) {
  Heights f;
  f.nx = d.raysX();
  f.ny = d.raysY();
  if (f.nx < 2 || f.ny < 2 || d.ray(0, 0).empty()) return std::nullopt;
  f.h = d.resolution();
  f.x0 = d.originX();
  f.y0 = d.originY();
  f.floor = d.ray(0, 0).front().z0;
  double lastX = 0.0, lastY = 0.0;  // the far faces' shares of their columns
  for (int j = 0; j < f.ny; ++j)
    for (int i = 0; i < f.nx; ++i) {
      const std::vector<DexelStock::Interval>& r = d.ray(i, j);
      if (r.empty() || std::abs(r.front().z0 - f.floor) > kSameHeight) return std::nullopt;
      const double base = r.front().f * d.weight(i, j);
      if (i == f.nx - 1 && j < f.ny - 1) lastX = std::max(lastX, base);
      if (j == f.ny - 1 && i < f.nx - 1) lastY = std::max(lastY, base);
    }
  lastX = std::min(1.0, lastX);
  lastY = std::min(1.0, lastY);
  if (!(lastX > 0.0 && lastY > 0.0)) return std::nullopt;
  f.xEnd = f.x0 + (f.nx - 1 + lastX) * f.h;
  f.yEnd = f.y0 + (f.ny - 1 + lastY) * f.h;
  f.z.resize(static_cast<std::size_t>(f.nx) * static_cast<std::size_t>(f.ny));
  for (int j = 0; j < f.ny; ++j)
    for (int i = 0; i < f.nx; ++i) {
      const std::vector<DexelStock::Interval>& r = d.ray(i, j);
      const double box = (i == f.nx - 1 ? lastX : 1.0) * (j == f.ny - 1 ? lastY : 1.0);
      const double w = d.weight(i, j) / box;
      double height = f.floor, top = f.floor, over = 0.0;
      bool gap = false;
      for (const DexelStock::Interval& piece : r) {
        const double held = (piece.z1 - piece.z0) * std::min(1.0, piece.f * w);
        if (piece.z0 > top + kSameHeight) gap = true;
        if (gap && (over += held) > 0.5 * f.h) return std::nullopt;  // an overhang
        height += held;
        top = piece.z1;
      }
      f.z[static_cast<std::size_t>(j) * static_cast<std::size_t>(f.nx) +
          static_cast<std::size_t>(i)] = height;
    }
  return f;
}

/// Every s-th ray in x and y (and the last), each the mean height of the rays around it (at
/// s = 1 the rays' own heights, not copied).
struct Lattice {
  int w = 0, n = 0;  ///< vertices in x and y
  std::vector<double> x, y;
  std::vector<double> means;                  ///< the heights where s > 1
  const std::vector<double>* rays = nullptr;  ///< the rays' heights where s = 1
  double at(int a, int b) const {
    return (rays ? *rays : means)[static_cast<std::size_t>(b) * static_cast<std::size_t>(w) +
                                  static_cast<std::size_t>(a)];
  }
};

std::vector<int> every(int count, int s) {
  std::vector<int> v;
  for (int i = 0; i < count - 1; i += s)
    v.push_back(i);
  v.push_back(count - 1);
  return v;
}

Lattice lattice(const Heights& f, int s) {
  Lattice L;
  const std::vector<int> is = every(f.nx, s), js = every(f.ny, s);
  L.w = static_cast<int>(is.size());
  L.n = static_cast<int>(js.size());
  for (int i : is)
    L.x.push_back(f.x(i));
  for (int j : js)
    L.y.push_back(f.y(j));
  if (s == 1) {
    L.rays = &f.z;
    return L;
  }
  L.means.resize(static_cast<std::size_t>(L.w) * static_cast<std::size_t>(L.n));
  for (int b = 0; b < L.n; ++b)
    for (int a = 0; a < L.w; ++a) {
      const int i0 = std::max(0, is[a] - s / 2), i1 = std::min(f.nx, is[a] + (s + 1) / 2);
      const int j0 = std::max(0, js[b] - s / 2), j1 = std::min(f.ny, js[b] + (s + 1) / 2);
      double sum = 0.0;
      for (int j = j0; j < j1; ++j)
        for (int i = i0; i < i1; ++i)
          sum += f.z[static_cast<std::size_t>(j) * static_cast<std::size_t>(f.nx) +
                     static_cast<std::size_t>(i)];
      L.means[static_cast<std::size_t>(b) * static_cast<std::size_t>(L.w) +
              static_cast<std::size_t>(a)] = sum / ((i1 - i0) * (j1 - j0));
    }
  return L;
}

/// A block of the lattice: its vertices a0..a1 in x, b0..b1 in y (inclusive).
struct Block {
  int a0, a1, b0, b1;
};

/// The plane through a block's corners (least squares): its height at (x, y).
struct Plane {
  double m, gx, gy, xc, yc;
  double at(double x, double y) const { return m + gx * (x - xc) + gy * (y - yc); }
};

Plane cornerPlane(const Lattice& L, const Block& k) {
  const double z00 = L.at(k.a0, k.b0), z10 = L.at(k.a1, k.b0), z01 = L.at(k.a0, k.b1),
               z11 = L.at(k.a1, k.b1);
  return {0.25 * (z00 + z10 + z01 + z11),
          0.5 * ((z10 + z11) - (z00 + z01)) / (L.x[k.a1] - L.x[k.a0]),
          0.5 * ((z01 + z11) - (z00 + z10)) / (L.y[k.b1] - L.y[k.b0]),
          0.5 * (L.x[k.a0] + L.x[k.a1]), 0.5 * (L.y[k.b0] + L.y[k.b1])};
}

bool planar(const Lattice& L, const Block& k, double eps) {
  const Plane p = cornerPlane(L, k);
  for (int b = k.b0; b <= k.b1; ++b)
    for (int a = k.a0; a <= k.a1; ++a)
      if (!(std::abs(L.at(a, b) - p.at(L.x[a], L.y[b])) <= eps)) return false;
  return true;
}

/// The blocks the top is made of: the largest aligned blocks of 2^k x 2^k quads (clipped at
/// the far sides) whose quarters are all planar and which are planar within `eps` themselves;
/// single quads where nothing merges.
std::vector<Block> blocks(const Lattice& L, double eps) {
  const int qx = L.w - 1, qy = L.n - 1;
  int levels = 0;
  while ((1 << levels) < std::max(qx, qy))
    ++levels;
  auto count = [](int quads, int k) { return (quads + (1 << k) - 1) >> k; };
  auto block = [&](int k, int bx, int by) {
    return Block{bx << k, std::min((bx + 1) << k, qx), by << k, std::min((by + 1) << k, qy)};
  };
  // flat[k]: the blocks of level k (k >= 1) merged, bottom up.
  std::vector<std::vector<std::uint8_t>> flat(static_cast<std::size_t>(levels) + 1);
  for (int k = 1; k <= levels; ++k) {
    const int bw = count(qx, k), bh = count(qy, k), cw = count(qx, k - 1), ch = count(qy, k - 1);
    std::vector<std::uint8_t>& f = flat[static_cast<std::size_t>(k)];
    f.assign(static_cast<std::size_t>(bw) * static_cast<std::size_t>(bh), 0);
    for (int by = 0; by < bh; ++by)
      for (int bx = 0; bx < bw; ++bx) {
        bool quarters = true;
        for (int c = 0; c < 4 && quarters && k > 1; ++c) {
          const int cx = 2 * bx + (c & 1), cy = 2 * by + (c >> 1);
          if (cx < cw && cy < ch)
            quarters = flat[static_cast<std::size_t>(k) - 1]
                           [static_cast<std::size_t>(cy) * static_cast<std::size_t>(cw) +
                            static_cast<std::size_t>(cx)] != 0;
        }
        f[static_cast<std::size_t>(by) * static_cast<std::size_t>(bw) +
          static_cast<std::size_t>(bx)] = quarters && planar(L, block(k, bx, by), eps) ? 1 : 0;
      }
  }
  // Top down: a merged block is one piece, any other is its quarters.
  std::vector<Block> out;
  struct Node {
    int k, bx, by;
  };
  std::vector<Node> stack{{levels, 0, 0}};
  while (!stack.empty()) {
    const Node n = stack.back();
    stack.pop_back();
    if (n.k == 0 || flat[static_cast<std::size_t>(n.k)]
                        [static_cast<std::size_t>(n.by) * static_cast<std::size_t>(count(qx, n.k)) +
                         static_cast<std::size_t>(n.bx)] != 0) {
      out.push_back(block(n.k, n.bx, n.by));
      continue;
    }
    for (int c = 3; c >= 0; --c) {
      const int cx = 2 * n.bx + (c & 1), cy = 2 * n.by + (c >> 1);
      if (cx < count(qx, n.k - 1) && cy < count(qy, n.k - 1)) stack.push_back({n.k - 1, cx, cy});
    }
  }
  return out;
}

/// The lattice's vertices some block has as a corner: the ones on the blocks' edges.
class Used {
 public:
  Used(const Lattice& L, const std::vector<Block>& blocks)
      : w_(L.w), used_(static_cast<std::size_t>(L.w) * static_cast<std::size_t>(L.n), 0) {
    for (const Block& k : blocks)
      for (int c = 0; c < 4; ++c)
        used_[index((c & 1) ? k.a1 : k.a0, (c >> 1) ? k.b1 : k.b0)] = 1;
  }
  bool operator()(int a, int b) const { return used_[index(a, b)] != 0; }
  std::size_t index(int a, int b) const {
    return static_cast<std::size_t>(b) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(a);
  }

 private:
  int w_;
  std::vector<std::uint8_t> used_;
};

/// fn(a, b) for the used vertices on a block's edges, counter-clockwise seen from above, from
/// its corner (a0, b0).
template <typename Fn>
void aroundBlock(const Block& k, const Used& used, Fn&& fn) {
  for (int a = k.a0; a < k.a1; ++a)
    if (used(a, k.b0)) fn(a, k.b0);
  for (int b = k.b0; b < k.b1; ++b)
    if (used(k.a1, b)) fn(k.a1, b);
  for (int a = k.a1; a > k.a0; --a)
    if (used(a, k.b1)) fn(a, k.b1);
  for (int b = k.b1; b > k.b0; --b)
    if (used(k.a0, b)) fn(k.a0, b);
}

/// fn(a, b) for the used vertices on the lattice's rim, counter-clockwise seen from above.
template <typename Fn>
void aroundRim(const Lattice& L, const Used& used, Fn&& fn) {
  aroundBlock(Block{0, L.w - 1, 0, L.n - 1}, used, fn);
}

std::size_t triangleCount(const Lattice& L, const std::vector<Block>& blocks, const Used& used) {
  std::size_t n = 0;
  for (const Block& k : blocks) {
    std::size_t edge = 0;
    aroundBlock(k, used, [&](int, int) { ++edge; });
    n += edge == 4 ? 2 : edge;
  }
  std::size_t rim = 0;
  aroundRim(L, used, [&](int, int) { ++rim; });
  return n + 3 * rim;  // two a wall's segment, one the floor's
}

TriangleMesh mesh(const Lattice& L, const std::vector<Block>& blocks, const Used& used,
                  double floor) {
  TriangleMesh m;
  auto point = [&m](double x, double y, double z) {
    m.points.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    return static_cast<unsigned>(m.points.size() - 1);
  };
  std::vector<unsigned> id(static_cast<std::size_t>(L.w) * static_cast<std::size_t>(L.n),
                           std::numeric_limits<unsigned>::max());
  for (int b = 0; b < L.n; ++b)
    for (int a = 0; a < L.w; ++a)
      if (used(a, b)) id[used.index(a, b)] = point(L.x[a], L.y[b], L.at(a, b));
  std::vector<unsigned> edge;
  for (const Block& k : blocks) {
    edge.clear();
    aroundBlock(k, used, [&](int a, int b) { edge.push_back(id[used.index(a, b)]); });
    if (edge.size() == 4) {
      // Split along the diagonal whose ends differ less in height: a wall crossing the quad
      // stays on one side of it.
      auto z = [&](std::size_t c) { return static_cast<double>(m.points[edge[c]][2]); };
      if (std::abs(z(0) - z(2)) <= std::abs(z(1) - z(3))) {
        m.triangles.push_back({edge[0], edge[1], edge[2]});
        m.triangles.push_back({edge[0], edge[2], edge[3]});
      } else {
        m.triangles.push_back({edge[0], edge[1], edge[3]});
        m.triangles.push_back({edge[1], edge[2], edge[3]});
      }
      continue;
    }
    const Plane p = cornerPlane(L, k);
    const unsigned c = point(p.xc, p.yc, p.m);
    for (std::size_t e = 0; e < edge.size(); ++e)
      m.triangles.push_back({c, edge[e], edge[(e + 1) % edge.size()]});
  }
  // The walls from the rim down to the floor, and the floor.
  std::vector<unsigned> top, bottom;
  aroundRim(L, used, [&](int a, int b) {
    top.push_back(id[used.index(a, b)]);
    bottom.push_back(point(L.x[a], L.y[b], floor));
  });
  const unsigned centre =
      point(0.5 * (L.x.front() + L.x.back()), 0.5 * (L.y.front() + L.y.back()), floor);
  for (std::size_t e = 0; e < top.size(); ++e) {
    const std::size_t f = (e + 1) % top.size();
    m.triangles.push_back({top[f], top[e], bottom[e]});
    m.triangles.push_back({top[f], bottom[e], bottom[f]});
    m.triangles.push_back({centre, bottom[f], bottom[e]});
  }
  return m;
}

}  // namespace

std::optional<std::vector<TriangleMesh>> heightfieldMeshes(const DexelStock& stock,
                                                           const std::vector<std::size_t>& budgets,
                                                           std::vector<double>* cellSizes) {
  const std::optional<Heights> f = heights(stock);
  if (!f) return std::nullopt;
  std::vector<TriangleMesh> meshes(budgets.size());
  if (cellSizes) cellSizes->assign(budgets.size(), 0.0);
  std::vector<bool> done(budgets.size(), false);
  std::size_t left = budgets.size();
  // Every ray, then every 2nd, 4th, ...: each budget meshed at the first spacing that fits it
  // (a budget of 0 at every ray, only exactly planar blocks merged: a level of its own).
  for (const bool exact : {true, false}) {
    if (exact && std::find(budgets.begin(), budgets.end(), std::size_t{0}) == budgets.end())
      continue;
    for (int s = 1; left > 0; s *= 2) {
      const Lattice L = lattice(*f, s);
      const double eps = exact ? kSameHeight : 0.1 * s * f->h;
      const std::vector<Block> top = blocks(L, eps);
      const Used used(L, top);
      const bool last = L.w <= 2 && L.n <= 2;
      const std::size_t count = exact || last ? 0 : triangleCount(L, top, used);
      for (std::size_t b = 0; b < budgets.size(); ++b) {
        if (done[b] || (budgets[b] == 0) != exact || (!last && !exact && count > budgets[b]))
          continue;
        meshes[b] = mesh(L, top, used, f->floor);
        if (cellSizes) (*cellSizes)[b] = s * f->h;
        done[b] = true;
        --left;
      }
      if (exact || last) break;
    }
  }
  return meshes;
}

std::optional<TriangleMesh> heightfieldMesh(const DexelStock& stock, std::size_t maxTriangles,
                                            double* cellSize) {
  std::vector<double> cells;
  std::optional<std::vector<TriangleMesh>> meshes =
      heightfieldMeshes(stock, {maxTriangles}, &cells);
  if (!meshes) return std::nullopt;
  if (cellSize) *cellSize = cells[0];
  return std::move(meshes->front());
}

}  // namespace engage
