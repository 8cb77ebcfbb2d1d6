#include "tests/support/RandomPrograms.h"

#include "cutters/Numbers.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/run/Resolution.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

namespace engage::test {

namespace {

constexpr double kDeg = kPi / 180.0;

/// Uniform draws of the generator's own, so that a seed means the same case everywhere
/// (std::mt19937_64's sequence is fixed by the standard; the distributions are not).
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed * 0x9E3779B97F4A7C15ull + 1u) {}
  double u() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  double u(double lo, double hi) { return lo + (hi - lo) * u(); }
  int i(int lo, int hi) { return lo + static_cast<int>(u() * (hi - lo + 1) * (1.0 - 1e-12)); }
  bool chance(double p) { return u() < p; }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }

 private:
  std::mt19937_64 rng_;
};

struct Point {
  /// Local coordinates (u, v about the program's centre; z as is); beside a face of the box
  /// (face >= 0: x min, x max, y min, y max), x is how far the cutter's axis stays out of the
  /// face, y the share of the way along it (from 2 mm in from one end to 2 mm from the other).
  Eigen::Vector3d p;
  bool rapid = false;
  int face = -1;
};

/// A program in the local frame, turned and shifted onto the stock when it is written.
class Builder {
 public:
  Builder(double top, double reach, double radius, int budget)
      : top_(top), reach_(reach), radius_(radius), budget_(budget) {}

  double top() const { return top_; }
  double reach() const { return reach_; }  ///< local points stay within this of the centre
  double radius() const { return radius_; }
  int left() const { return budget_ - static_cast<int>(points_.size()); }
  const Eigen::Vector3d& at() const { return at_; }

  void rapid(const Eigen::Vector3d& p) { add(p, true); }
  void feed(const Eigen::Vector3d& p) { add(p, false); }
  /// Beside face `face` of the box (see Point).
  void besideFace(int face, const Eigen::Vector3d& p, bool rapid) {
    points_.push_back({p, rapid, face});
    besideFace_ = true;
  }
  /// Up (straight: nothing to cut), across above the stock, down to 0.3 mm above the top,
  /// then fed down to `p`.
  void approach(const Eigen::Vector3d& p) {
    if (!points_.empty()) rapid({at_.x(), at_.y(), top_ + 2.0});
    rapid({p.x(), p.y(), top_ + 2.0});
    rapid({p.x(), p.y(), std::max(p.z(), top_ + 0.3)});
    if (p.z() < top_ + 0.3) feed(p);
  }
  /// The local point clamped into the reach.
  Eigen::Vector3d inside(Eigen::Vector3d p) const {
    const double r = std::hypot(p.x(), p.y());
    if (r > reach_) {
      p.x() *= reach_ / r;
      p.y() *= reach_ / r;
    }
    return p;
  }
  const std::vector<Point>& points() const { return points_; }

 private:
  void add(const Eigen::Vector3d& p, bool rapid) {
    if (besideFace_) {
      // Back from a pass beside a face: up first, as approach() would.
      besideFace_ = false;
      Point up = points_.back();
      up.p.z() = top_ + 2.0;
      up.rapid = true;
      points_.push_back(up);
    }
    points_.push_back({p, rapid, -1});
    at_ = p;
  }

  double top_, reach_, radius_;
  int budget_;
  std::vector<Point> points_;
  Eigen::Vector3d at_{0.0, 0.0, 0.0};
  bool besideFace_ = false;
};

double deepest(const Builder& b, double stockHeight) {
  return b.top() - std::min(5.0, stockHeight - 1.0);
}

/// Straight moves at random slopes (level, and 1-30 deg down or up) in random directions.
void ramps(Draw& d, Builder& b, double stockHeight) {
  const int n = std::min(d.i(3, 7), b.left() - 5);
  if (n < 1) return;
  const double r = b.reach() * 0.6;
  const double a0 = d.u(0, 2 * kPi), r0 = r * std::sqrt(d.u());
  Eigen::Vector3d p(r0 * std::cos(a0), r0 * std::sin(a0), b.top() - d.u(0.2, 2.5));
  b.approach(p);
  for (int k = 0; k < n; ++k) {
    double a = d.u(0, 2 * kPi);
    const double len = d.u(1.5, 10.0);
    const double slope = d.chance(0.2) ? 0.0 : d.sign() * d.u(1.0, 30.0) * kDeg;
    Eigen::Vector3d q = p + len * Eigen::Vector3d(std::cos(a), std::sin(a), std::tan(slope));
    if (std::hypot(q.x(), q.y()) > b.reach()) {
      a += kPi;
      q = p + len * Eigen::Vector3d(std::cos(a), std::sin(a), std::tan(slope));
    }
    q = b.inside(q);
    q.z() = std::clamp(q.z(), deepest(b, stockHeight), b.top() + 0.3);
    b.feed(q);
    p = q;
  }
}

/// Zig-zag rows over a random surface, along u or v, and cross-hatched: the other way over the
/// same patch, as deep or 0.01-0.1 mm deeper.
void raster(Draw& d, Builder& b, double diameter) {
  const double base = d.u(0.3, 2.0), amp = d.chance(0.2) ? 0.0 : d.u(0.2, 1.5);
  const double ku = 2 * kPi / d.u(8.0, 25.0), kv = 2 * kPi / d.u(8.0, 25.0);
  const double pu = d.u(0, 2 * kPi), pv = d.u(0, 2 * kPi);
  const double top = b.top();
  auto surface = [&](double u, double v, double lower) {
    return top - base - lower - amp * 0.5 * (1.0 + std::sin(ku * u + pu) * std::sin(kv * v + pv));
  };
  const int passes = d.chance(0.4) ? 2 : 1;
  const bool alongV = d.chance(0.5);
  const double stepover = d.u(0.15, 0.6) * diameter, seg = d.u(1.2, 4.0);
  // The patch, shrunk until its rows fit the moves left.
  double w = d.u(6.0, 16.0), h = d.u(4.0, 12.0);
  auto movesOf = [&](double pw, double ph) {
    const int rows = static_cast<int>(ph / stepover) + 1, segs = static_cast<int>(pw / seg) + 1;
    const int rowsX = static_cast<int>(pw / stepover) + 1, segsX = static_cast<int>(ph / seg) + 1;
    return rows * (segs + 1) + 4 + (passes == 2 ? rowsX * (segsX + 1) + 4 : 0);
  };
  while (movesOf(w, h) > b.left() && (w > 2.0 || h > 2.0)) {
    w = std::max(2.0, w * 0.8);
    h = std::max(2.0, h * 0.8);
  }
  if (movesOf(w, h) > b.left()) return;
  const Eigen::Vector2d c =
      b.inside(Eigen::Vector3d(d.u(-0.4, 0.4) * b.reach(), d.u(-0.4, 0.4) * b.reach(), 0.0))
          .head<2>();
  const double lower = d.chance(0.5) ? 0.0 : d.u(0.01, 0.1);
  for (int pass = 0; pass < passes; ++pass) {
    const bool v = alongV != (pass == 1);
    const double len = v ? h : w, across = v ? w : h;
    const int rows = static_cast<int>(across / stepover) + 1,
              segs = static_cast<int>(len / seg) + 1;
    auto point = [&](double s, double t) {  // s along the rows, t across them
      const double u = v ? c.x() - w / 2 + t : c.x() - w / 2 + s;
      const double vv = v ? c.y() - h / 2 + s : c.y() - h / 2 + t;
      return Eigen::Vector3d(u, vv, surface(u, vv, pass == 1 ? lower : 0.0));
    };
    b.approach(point(0.0, 0.0));
    for (int row = 0; row < rows; ++row) {
      const double t = std::min(across, row * stepover);
      // Even rows from s = 0 to len, odd rows back; each row's start fed to from the last's end.
      if (row > 0) b.feed(point(row % 2 ? len : 0.0, t));
      for (int k = 1; k <= segs; ++k) {
        const double s = len * k / segs;
        b.feed(point(row % 2 ? len - s : s, t));
      }
    }
  }
}

/// A helix as straight pieces (6-24 a turn), down from the top; then straight up out of it
/// (nothing to cut), and perhaps its last turn again 0.01-0.1 mm wider.
void helix(Draw& d, Builder& b, double diameter, double stockHeight) {
  const double turns = d.u(0.75, 2.5), depth = d.u(0.3, 3.0);
  const double rho = d.u(0.2, 1.2) * diameter;
  const bool again = d.chance(0.5);
  // 6-24 pieces a turn, fewer where the moves left ask for it.
  int perTurn = d.i(6, 24);
  const int left = b.left() - 8;
  while (perTurn > 4 && std::ceil(turns * perTurn) + (again ? perTurn : 0) > left)
    --perTurn;
  const int n = static_cast<int>(std::ceil(turns * perTurn));
  if (n + (again ? perTurn : 0) > left) return;
  const double floor = deepest(b, stockHeight);
  const double z0 = b.top() + 0.2, pitch = (0.2 + depth) / turns;
  const double reach = std::max(0.0, b.reach() * 0.5 - rho);
  const Eigen::Vector2d c(d.u(-1, 1) * reach, d.u(-1, 1) * reach);
  const double a0 = d.u(0, 2 * kPi), dir = d.sign();
  auto at = [&](double k, double radius, double zStart, double down) {
    const double a = a0 + dir * 2 * kPi * k / perTurn;
    return Eigen::Vector3d(c.x() + radius * std::cos(a), c.y() + radius * std::sin(a),
                           std::max(floor, zStart - down * pitch * k / perTurn));
  };
  b.approach(at(0, rho, z0, 1.0));
  for (int k = 1; k <= n; ++k)
    b.feed(at(k, rho, z0, 1.0));
  b.rapid(Eigen::Vector3d(b.at().x(), b.at().y(), b.top() + 2.0));
  if (again) {  // the last turn again, 0.01-0.1 mm wider, climbing
    const double wider = rho + d.u(0.01, 0.1);
    const double zLast = std::max(floor, z0 - pitch * n / perTurn);
    b.approach(at(0, wider, zLast, 0.0));
    for (int k = 1; k <= perTurn; ++k)
      b.feed(at(k, wider, zLast, -1.0));
  }
}

/// A few level moves, then the same again 0.01-0.1 mm beside them, below them or both.
void recut(Draw& d, Builder& b) {
  const int n = d.i(2, 4), times = d.i(1, 3);
  if (b.left() < (n + 4) * (times + 1)) return;
  const double depth = d.u(0.3, 3.0);
  std::vector<Eigen::Vector3d> path;
  const double r = b.reach() * 0.5;
  Eigen::Vector3d p(d.u(-r, r), d.u(-r, r), b.top() - depth);
  path.push_back(p);
  for (int k = 0; k < n; ++k) {
    const double a = d.u(0, 2 * kPi), len = d.u(2.0, 9.0);
    p = b.inside(p + len * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
    path.push_back(p);
  }
  Eigen::Vector2d side = (path[1] - path[0]).head<2>();
  side = side.norm() > 0 ? Eigen::Vector2d(-side.y(), side.x()).normalized()
                         : Eigen::Vector2d(1.0, 0.0);
  Eigen::Vector3d shift(0, 0, 0);
  for (int t = 0; t <= times; ++t) {
    b.approach(path[0] + shift);
    for (std::size_t k = 1; k < path.size(); ++k)
      b.feed(path[k] + shift);
    const int how = d.i(0, 2);  // beside, below, both
    const double s = how != 1 ? d.sign() * d.u(0.01, 0.1) : 0.0;
    const double z = how != 0 ? d.u(0.01, 0.1) : 0.0;
    shift += Eigen::Vector3d(s * side.x(), s * side.y(), -z);
  }
}

/// A level cut, then moves of 0.02-0.1 mm in random directions from its end (a plunge among
/// them), a pass along the cut 0.001-0.05 mm into or short of its wall, and a pass along one of
/// the stock's own side faces 0.001-0.05 mm into it or outside it.
void tiny(Draw& d, Builder& b, double radius) {
  const int n = d.i(5, 12);
  if (b.left() < n + 16) return;
  const double depth = d.u(0.3, 3.0), len = d.u(3.0, 8.0);
  const double r = b.reach() * 0.5;
  const double a = d.u(0, 2 * kPi);
  const Eigen::Vector3d dir(std::cos(a), std::sin(a), 0.0), side(-dir.y(), dir.x(), 0.0);
  const Eigen::Vector3d p0(d.u(-r, r), d.u(-r, r), b.top() - depth);
  const Eigen::Vector3d p1 = b.inside(p0 + len * dir);
  b.approach(p0);
  b.feed(p1);
  Eigen::Vector3d p = p1;
  const int plunge = d.i(0, n - 1);
  for (int k = 0; k < n; ++k) {
    const double step = d.u(0.02, 0.1);
    Eigen::Vector3d v;
    if (k == plunge) {
      v = Eigen::Vector3d(0, 0, -1);
    } else {
      const double az = d.u(0, 2 * kPi), el = d.u(-60, 30) * kDeg;
      v = Eigen::Vector3d(std::cos(az) * std::cos(el), std::sin(az) * std::cos(el), std::sin(el));
    }
    p += step * v;
    b.feed(p);
  }
  // Along the first cut, its edge 0.001-0.05 mm into the wall on one side or short of it.
  const double graze = d.sign() * d.u(0.001, 0.05);
  b.approach(p0 + graze * side);
  b.feed(p1 + graze * side);
  // Along a face of the box: the cutter's edge 0.001-0.05 mm into the face or outside it.
  const int face = d.i(0, 3);
  const double out = radius - d.sign() * d.u(0.001, 0.05), z = b.top() - d.u(0.3, 3.0);
  b.rapid({b.at().x(), b.at().y(), b.top() + 2.0});
  b.besideFace(face, {out, 0.0, b.top() + 2.0}, true);
  b.besideFace(face, {out, 0.0, b.top() + 0.3}, true);
  b.besideFace(face, {out, 0.0, z}, false);
  b.besideFace(face, {out, 1.0, z}, false);
}

AptCutter drawCutter(Draw& d, std::string& label) {
  const double diameter = std::round(d.u(3.0, 10.0) * 10.0) / 10.0;
  const double flute = 25.0;
  char buf[96];
  switch (d.i(0, 5)) {
    case 0:
      std::snprintf(buf, sizeof buf, "flat D%g", diameter);
      label = buf;
      return AptCutter::flat(diameter, flute);
    case 1:
      std::snprintf(buf, sizeof buf, "ball D%g", diameter);
      label = buf;
      return AptCutter::ball(diameter, flute);
    case 2: {
      const double rc = std::round(d.u(0.1, 0.45) * diameter * 100.0) / 100.0;
      std::snprintf(buf, sizeof buf, "bull D%g r%g", diameter, rc);
      label = buf;
      return AptCutter::bull(diameter, rc, flute);
    }
    case 3: {
      const double beta = std::round(d.u(2.0, 15.0) * 10.0) / 10.0;
      std::snprintf(buf, sizeof buf, "taper tip D%g %g deg", diameter, beta);
      label = buf;
      return AptCutter::taper(diameter, beta * kDeg, flute);
    }
    case 4: {
      const double beta = std::round(d.u(2.0, 15.0) * 10.0) / 10.0;
      std::snprintf(buf, sizeof buf, "tapered ball D%g %g deg", diameter, beta);
      label = buf;
      return AptCutter::taperedBall(diameter, beta * kDeg, flute);
    }
    default: {
      const double included = std::round(d.u(60.0, 120.0));
      std::snprintf(buf, sizeof buf, "chamfer D%g %g deg", diameter, included);
      label = buf;
      return AptCutter::chamfer(diameter, included * kDeg, flute);
    }
  }
}

std::string render(const std::vector<Point>& points, const Eigen::Vector2d& centre, double angle,
                   const Box3& box, const std::string& title) {
  std::string text = "(" + title + ")\nG21 G90 G17 G94\n";
  const double c = std::cos(angle), s = std::sin(angle);
  char buf[128];
  bool rapid = true;
  for (const Point& p : points) {
    Eigen::Vector3d w(centre.x() + c * p.p.x() - s * p.p.y(),
                      centre.y() + s * p.p.x() + c * p.p.y(), p.p.z());
    const double along = p.p.y();
    if (p.face == 0 || p.face == 1)
      w = {p.face == 0 ? box.min.x() - p.p.x() : box.max.x() + p.p.x(),
           box.min.y() + 2.0 + along * (box.max.y() - box.min.y() - 4.0), p.p.z()};
    else if (p.face >= 2)
      w = {box.min.x() + 2.0 + along * (box.max.x() - box.min.x() - 4.0),
           p.face == 2 ? box.min.y() - p.p.x() : box.max.y() + p.p.x(), p.p.z()};
    if (p.rapid)
      std::snprintf(buf, sizeof buf, "G0 X%.4f Y%.4f Z%.4f\n", w.x(), w.y(), w.z());
    else
      std::snprintf(buf, sizeof buf, "G1 X%.4f Y%.4f Z%.4f%s\n", w.x(), w.y(), w.z(),
                    rapid ? " F800" : "");
    rapid = p.rapid;
    text += buf;
  }
  return text + "M2\n";
}

}  // namespace

RandomCase randomCase(std::uint64_t seed, int maxMoves) {
  Draw d(seed);
  RandomCase c;
  c.seed = seed;
  std::string label;
  c.cutter = drawCutter(d, label);
  const double diameter = 2.0 * c.cutter.radius();
  const bool heavy = c.cutter.shape() == CutterShape::Ball ||
                     c.cutter.shape() == CutterShape::TaperedBall ||
                     c.cutter.shape() == CutterShape::Bull;
  const double height = d.u(5.0, 12.0);
  const Eigen::Vector3d corner(d.u(-20, 20), d.u(-20, 20), d.u(-12, 0));
  double sx = d.u(18.0, 36.0), sy = d.u(18.0, 36.0);
  const double top = corner.z() + height;
  Builder b(top, 0.5 * std::min(sx, sy), c.cutter.maxRadius(), heavy ? maxMoves / 2 : maxMoves);

  // One to three pieces.
  std::string pieces;
  const int count = d.i(1, 3);
  for (int k = 0; k < count; ++k) {
    const int kind = d.i(0, 4);
    const int before = static_cast<int>(b.points().size());
    switch (kind) {
      case 0:
        ramps(d, b, height);
        break;
      case 1:
        raster(d, b, diameter);
        break;
      case 2:
        helix(d, b, diameter, height);
        break;
      case 3:
        recut(d, b);
        break;
      default:
        tiny(d, b, c.cutter.radius());
        break;
    }
    static const char* kNames[] = {"ramps", "raster", "helix", "recut", "tiny"};
    if (static_cast<int>(b.points().size()) > before)
      pieces += std::string(pieces.empty() ? "" : " + ") + kNames[kind];
  }
  if (b.points().empty()) ramps(d, b, height), pieces = "ramps";
  b.rapid({b.at().x(), b.at().y(), top + 2.0});

  // Placement: the cell first (it follows the depths, not the place), then the program's centre
  // and the box's far faces on whole cells, half cells or anywhere.
  const double angle = d.chance(0.25) ? d.i(0, 3) * 0.5 * kPi : d.u(0, 2 * kPi);
  const int onGrid = d.i(0, 3);  // 0: whole cells, 1: half cells, else anywhere
  const int sizes = d.i(0, 3);
  auto boxOf = [&] {
    Box3 box;
    box.min = corner;
    box.max = corner + Eigen::Vector3d(sx, sy, height);
    return box;
  };
  // The tool starts above the stock's middle (the first move is a rapid above the stock).
  const Eigen::Vector3d start(corner.x() + 0.5 * sx, corner.y() + 0.5 * sy, top + 5.0);
  auto cellOf = [&](const std::string& text) {
    ReaderOptions options;
    options.start = start;
    Toolpath path = readProgramText(text, "random", options);
    CutterSet cutters;
    cutters.fallback = c.cutter;
    const Box3 box = boxOf();
    StockModels models;
    models.dexel = true;
    return std::make_pair(defaultCell(path, cutters, box, models, 0.0).cell, std::move(path));
  };
  const Eigen::Vector2d mid = corner.head<2>() + 0.5 * Eigen::Vector2d(sx, sy);
  const double cell = cellOf(render(b.points(), mid, angle, boxOf(), "")).first;
  auto snap = [&](double v, int mode, double origin) {
    if (mode > 1) return v;
    const double k = std::round((v - origin) / cell);
    return origin + (k + (mode == 1 ? 0.5 : 0.0)) * cell;
  };
  if (sizes <= 1) {
    sx = snap(sx, sizes, 0.0);
    sy = snap(sy, sizes, 0.0);
  }
  Eigen::Vector2d centre(snap(mid.x() + d.u(-1, 1), onGrid, corner.x()),
                         snap(mid.y() + d.u(-1, 1), onGrid, corner.y()));
  c.stock = boxOf();
  char title[300];
  std::snprintf(title, sizeof title,
                "seed %llu: %s, %s; stock %.4f %.4f %.4f to %.4f %.4f %.4f; tool starts at %.4f "
                "%.4f %.4f",
                static_cast<unsigned long long>(seed), label.c_str(), pieces.c_str(),
                c.stock.min.x(), c.stock.min.y(), c.stock.min.z(), c.stock.max.x(), c.stock.max.y(),
                c.stock.max.z(), start.x(), start.y(), start.z());
  c.program = render(b.points(), centre, angle, c.stock, title);
  auto [finalCell, path] = cellOf(c.program);
  c.cell = finalCell;
  c.path = std::move(path);
  c.name = std::string(title).substr(0, std::string(title).find(';'));
  return c;
}

TiltedCase tiltedCase(const RandomCase& c, Tilt tilt) {
  Draw d(c.seed ^ 0x5EEDu);
  TiltedCase t;
  t.abc = {d.u(10.0, 60.0), 0.0, d.u(0.0, 360.0)};
  if (tilt == Tilt::Quarter) t.abc = {90.0, 0.0, 90.0 * d.i(0, 3)};
  if (tilt == Tilt::Upright) t.abc.setZero();
  t.path = c.path;
  t.path.kinematics.type = Kinematics::Type::TableAC;
  t.path.kinematics.tcp = true;
  const Eigen::Matrix3d q =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), t.path.kinematics.axis(t.abc))
          .toRotationMatrix();
  for (Move& m : t.path.moves) {
    m.start = q * m.start;
    m.end = q * m.end;
    m.center = q * m.center;
    m.rotaryStart = m.rotaryEnd = t.abc;
  }
  // The box's corners (bit i of k: the max in axis i), turned, and its faces outwards.
  t.box.min = Eigen::Vector3d::Constant(1e300);
  t.box.max = Eigen::Vector3d::Constant(-1e300);
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p((k & 1) ? c.stock.max.x() : c.stock.min.x(),
                            (k & 2) ? c.stock.max.y() : c.stock.min.y(),
                            (k & 4) ? c.stock.max.z() : c.stock.min.z());
    const Eigen::Vector3d r = q * p;
    t.box.min = t.box.min.cwiseMin(r);
    t.box.max = t.box.max.cwiseMax(r);
    t.stock.points.push_back(
        {static_cast<float>(r.x()), static_cast<float>(r.y()), static_cast<float>(r.z())});
  }
  const unsigned faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    t.stock.triangles.push_back({f[0], f[1], f[2]});
    t.stock.triangles.push_back({f[0], f[2], f[3]});
  }
  return t;
}

double MoveComparison::totalPct() const {
  return exactTotal > 0.0 ? 100.0 * (measuredTotal / exactTotal - 1.0)
                          : (measuredTotal > 0.0 ? 100.0 : 0.0);
}

MoveComparison compareMoves(const Toolpath& path, const std::vector<double>& exact,
                            const std::vector<double>& measured, double cell) {
  MoveComparison m;
  const double cellVolume = cell * cell * cell;
  char buf[200];
  for (std::size_t i = 0; i < exact.size() && i < measured.size(); ++i) {
    m.exactTotal += exact[i];
    m.measuredTotal += measured[i];
    const double err = measured[i] - exact[i];
    bool fails = false;
    if (exact[i] >= 1.0) {
      ++m.bigMoves;
      const double pct = 100.0 * err / exact[i];
      if (std::abs(pct) <= 0.5) ++m.bigWithinHalfPct;
      if (std::abs(pct) > std::abs(m.worstBigPct)) m.worstBigPct = pct, m.worstBigMove = i;
      fails = std::abs(pct) > 1.0;
    } else if (exact[i] > 0.0) {
      const double cells = err / cellVolume;
      if (std::abs(cells) > std::abs(m.worstSmallCells))
        m.worstSmallCells = cells, m.worstSmallMove = i;
      fails = std::abs(cells) > 2.0;
    } else {
      if (measured[i] > m.worstZeroMm3) m.worstZeroMm3 = measured[i], m.worstZeroMove = i;
      fails = measured[i] != 0.0;
    }
    if (fails) {
      std::snprintf(buf, sizeof buf,
                    "move %zu (line %d): exact %.6g mm3, measured %.6g mm3 (%+.3g %%, %+.3g cells)",
                    i, path.moves[i].line, exact[i], measured[i],
                    exact[i] > 0 ? 100.0 * err / exact[i] : 0.0, err / cellVolume);
      m.failures.emplace_back(buf);
    }
  }
  return m;
}

}  // namespace engage::test
