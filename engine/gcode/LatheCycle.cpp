#include "engine/gcode/LatheCycle.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <sstream>
#include <string>

// The cycles as LinuxCNC 2.9 (Debian 12's linuxcnc-uspace) runs them: its interp_g7x.cc was
// read to learn the behaviour and the moves checked against its rs274; this is engage's own
// code. Where LinuxCNC's choice is odd it is kept, because the moves must be the ones the
// machine makes; the places are marked "(as LinuxCNC)". Where LinuxCNC would loop forever or
// read outside its lists, engage refuses the cycle instead.

namespace engage::gcode {
namespace {

using P = LathePoint;
const P kUp(0.0, 1.0);         // +X as a complex number
constexpr double kTol = 1e-6;  // LinuxCNC's tolerance in these cycles, program units
constexpr std::size_t kMaxMoves = 1000000;
constexpr long kMaxSteps = 4000000;  // loop guard: a cycle of kMaxMoves needs far fewer

[[noreturn]] void refuse(const std::string& why) {
  throw LatheCycleError(why);
}

std::string shortNumber(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

double cross(P a, P b) {
  return a.real() * b.imag() - a.imag() * b.real();
}

// ------------------------------------------------------------------------ one segment

/// LinuxCNC's size of a segment: a line's length; for an arc the smaller of its chord and
/// its radius. Offsetting moves by at most half the smallest size at a time.
double size(const LatheSegment& s) {
  const double chord = std::abs(s.start - s.end);
  return s.arc ? std::min(chord, std::abs(s.start - s.centre)) : chord;
}

/// Whether a segment of a normalised profile goes the way the cycle cuts: Z not growing
/// (lines), Z falling on the upper half of a counter-clockwise arc or the lower half of a
/// clockwise one. Tolerances 0.001 (program units), as LinuxCNC.
bool zFalls(const LatheSegment& s) {
  const double dz = (s.end - s.start).real();
  if (!s.arc) return dz <= 1e-3;
  if (s.corner != 0.0) return true;  // a fillet not shaped yet
  const double entry = (s.start - s.centre).imag();
  const double exit = (s.end - s.centre).imag();
  if (s.ccw) return entry >= -1e-3 && exit >= -1e-3 && dz <= -1e-3;
  return entry <= 1e-3 && exit <= 1e-3 && dz <= -1e-3;
}

/// Moves a segment sideways by `distance`: a line to its left (seen along it), an arc away
/// from its centre when counter-clockwise, towards it when clockwise.
void offset(LatheSegment& s, double distance) {
  if (s.arc) {
    const double r = std::abs(s.start - s.centre);
    const double scale = (r + (s.ccw ? distance : -distance)) / r;
    s.start = s.centre + scale * (s.start - s.centre);
    s.end = s.centre + scale * (s.end - s.centre);
  } else {
    const P shift = kUp * distance * (s.start - s.end) / std::abs(s.start - s.end);
    s.start += shift;
    s.end += shift;
  }
}

bool onArc(const LatheSegment& s, P p) {
  const double fromStart = cross(s.start - s.centre, p - s.centre);
  const double toEnd = cross(s.end - s.centre, p - s.centre);
  return s.ccw ? fromStart >= -kTol && toEnd <= kTol : fromStart <= kTol && toEnd >= -kTol;
}

/// Z values where the segment crosses height X = x, in LinuxCNC's order: a horizontal line
/// gives both ends; an arc its right crossing before its left one.
std::vector<double> crossings(const LatheSegment& s, double x) {
  std::vector<double> zs;
  if (!s.arc) {
    const double sx = s.start.imag(), ex = s.end.imag();
    if (std::min(sx, ex) > x + kTol || std::max(sx, ex) < x - kTol) return zs;
    if (std::abs(sx - ex) < kTol) {
      zs = {s.start.real(), s.end.real()};
    } else {
      zs.push_back((x - sx) / (ex - sx) * (s.end.real() - s.start.real()) + s.start.real());
    }
    return zs;
  }
  const double r = std::abs(s.start - s.centre);
  double h = -(x - r - s.centre.imag()) * (x + r - s.centre.imag());  // half chord squared
  if (h < -kTol) return zs;
  h = std::sqrt(std::max(h, 0.0));
  for (const double z : {s.centre.real() + h, s.centre.real() - h})
    if (onArc(s, P(z, x))) zs.push_back(z);
  return zs;
}

void mirrorX(LatheSegment& s) {  // X -> -X
  s.start = std::conj(s.start);
  s.end = std::conj(s.end);
  s.centre = std::conj(s.centre);
  s.ccw = !s.ccw;
}
void mirrorZ(LatheSegment& s) {  // Z -> -Z
  s.start = -std::conj(s.start);
  s.end = -std::conj(s.end);
  s.centre = -std::conj(s.centre);
  s.ccw = !s.ccw;
}
void quarterTurn(LatheSegment& s) {  // (Z, X) -> (X, -Z)
  s.start *= -kUp;
  s.end *= -kUp;
  s.centre *= -kUp;
}

/// Where a line (through a and b) meets a circle (centre c through point q), seen from the
/// line: the crossing nearest `near`. Tangent misses count as touching (as LinuxCNC).
P lineMeetsCircle(P a, P b, P c, P q, P near) {
  const P rot = std::conj(a - b) / std::abs(a - b);  // turns the line onto the Z axis at b
  const P cl = (c - b) * rot;
  const P ql = (q - b) * rot;
  const double h = std::sqrt(std::max(std::norm(cl - ql) - cl.imag() * cl.imag(), 0.0));
  const P p1 = (cl.real() + h) / rot + b;
  const P p2 = (cl.real() - h) / rot + b;
  return std::abs(near - p1) < std::abs(near - p2) ? p1 : p2;
}

/// Makes two consecutive offset segments meet again: their end and start are moved to
/// where the two curves cross.
void join(LatheSegment& prev, LatheSegment& next) {
  if (!prev.arc && !next.arc) {
    const P rot = std::conj(next.start - next.end) / std::abs(next.start - next.end);
    const P a = (prev.start - next.end) * rot;
    const P b = (prev.end - next.end) * rot;
    if ((a - b).imag() == 0.0)
      refuse(
          "expected consecutive profile lines that are not parallel, found two parallel "
          "lines (LinuxCNC: cannot intersect parallel lines)");
    const P meet = (a + a.imag() / (a - b).imag() * (b - a)) / rot + next.end;
    prev.end = next.start = meet;
  } else if (prev.arc && !next.arc) {
    if (std::abs(next.start - prev.end) < kTol) return;
    prev.end = next.start =
        lineMeetsCircle(next.start, next.end, prev.centre, prev.end, next.start);
  } else if (!prev.arc && next.arc) {
    if (std::abs(next.start - prev.end) < kTol) return;
    prev.end = next.start =
        lineMeetsCircle(prev.start, prev.end, next.centre, next.end, next.start);
  } else {
    const double a = std::abs(next.start - next.centre);
    const double b = std::abs(prev.start - prev.centre);
    const double c = std::abs(next.centre - prev.centre);
    const double cosB = (c * c + a * a - b * b) / 2.0 / a / c;
    const P turn(cosB, std::sqrt(1.0 - std::min(cosB * cosB, 1.0)));
    prev.end = next.start = turn * (prev.centre - next.centre) / c * a + next.centre;
  }
}

// ------------------------------------------------------------------------ output

/// Collects moves made in the normalised frame and maps them back to the program's.
class Output {
 public:
  Output(int flips, std::vector<LatheMove>& moves) : flips_(flips), moves_(moves) {}
  void rapid(P end) { add({LatheMoveKind::Rapid, back(end), {}, false}); }
  void line(P end) { add({LatheMoveKind::Line, back(end), {}, false}); }
  void arc(bool ccw, P centre, P end) {
    const bool mirrored = ((flips_ & 1) != 0) != ((flips_ & 2) != 0);
    const P to = back(end);
    // (as LinuxCNC) an arc ending where the tool is (1e-4 in each axis) is left out
    if (!moves_.empty() && std::abs((to - moves_.back().end).real()) < 1e-4 &&
        std::abs((to - moves_.back().end).imag()) < 1e-4)
      return;
    add({LatheMoveKind::Arc, to, back(centre), ccw != mirrored});
  }
  void move(bool rapidMove, P end) { rapidMove ? rapid(end) : line(end); }
  std::size_t size() const { return moves_.size(); }

 private:
  P back(P p) const {
    if (flips_ & 1) p = -std::conj(p);
    if (flips_ & 2) p = std::conj(p);
    if (flips_ & 4) p = kUp * p;
    return p;
  }
  void add(const LatheMove& m) {
    if (moves_.size() >= kMaxMoves)
      refuse("expected a cycle of at most " + std::to_string(kMaxMoves) +
             " moves, found more (is the depth of cut I too small?)");
    // A cycle stuck in place (where LinuxCNC's interpreter loops forever) repeats a move of
    // no length; a real cycle makes at most a few in a row.
    standing_ = !moves_.empty() && m.end == moves_.back().end ? standing_ + 1 : 0;
    if (standing_ > 1000)
      refuse(
          "expected a cycle that ends, found one repeating a move of no length (LinuxCNC "
          "loops forever here)");
    moves_.push_back(m);
  }
  int flips_;
  int standing_ = 0;  ///< moves in a row that end where the last one did
  std::vector<LatheMove>& moves_;
};

void draw(const LatheSegment& s, Output& out) {
  if (s.arc)
    out.arc(s.ccw, s.centre, s.end);
  else
    out.line(s.end);
}

// ------------------------------------------------------------------------ the profile

/// The profile, its first segment the approach from the cycle's start point, and the
/// mirrors and quarter turn applied to it (bits 1: Z mirrored, 2: X mirrored, 4: turned).
struct Contour {
  std::vector<LatheSegment> segs;
  int flips = 0;

  void turn() {
    for (LatheSegment& s : segs)
      quarterTurn(s);
    flips ^= 4;
  }
  /// Mirrors so that, from the first segment's end to the last one's, X and Z both fall.
  void normalise() {
    const P d = segs.front().end - segs.back().end;
    if (d.imag() > 0) {
      for (LatheSegment& s : segs)
        mirrorX(s);
      flips ^= 2;
    }
    if (d.real() < 0) {
      for (LatheSegment& s : segs)
        mirrorZ(s);
      flips ^= 1;
    }
  }
  /// A first segment that climbs in Z starts level with its end instead; then every segment
  /// must run the cycle's way (no undercut).
  void requireOneWay() {
    LatheSegment& first = segs.front();
    if ((first.end - first.start).real() > 0) first.start.real(first.end.real());
    for (const LatheSegment& s : segs)
      if (!zFalls(s))
        refuse(
            "expected a profile that runs one way along the cut (no undercut), found one "
            "that turns back");
  }
  void shapeCorners();
  void offsetBy(double distance);
};

/// Gives a corner finish its shape: both neighbours offset by its size (to the side where
/// they meet), joined, and the meeting point's feet on the two neighbours become the
/// finish's ends (a chamfer), or the ends of an arc about the meeting point (a fillet).
void shapeCorner(LatheSegment& corner, LatheSegment& prev, LatheSegment& next) {
  double size = corner.corner;
  LatheSegment a = prev, b = next;
  offset(a, size);
  offset(b, size);
  if ((a.end - b.start).real() > 1e-2) {
    size = -size;
    a = prev;
    b = next;
    offset(a, size);
    offset(b, size);
  }
  if ((a.end - b.start).real() > 1e-2)
    refuse("expected a corner that fits its A or C finish, found one that does not");
  join(a, b);
  const P centre = (a.end + b.start) / 2.0;
  offset(a, -size);
  offset(b, -size);
  corner.start = prev.end = a.end;
  corner.end = next.start = b.start;
  if (corner.arc) {
    corner.centre = centre;
    corner.ccw = (corner.start - centre).imag() > 0 || (corner.end - centre).imag() > 0;
    corner.corner = 0.0;
  }
}

void Contour::shapeCorners() {
  for (std::size_t i = 1; i + 1 < segs.size(); ++i)
    if (segs[i].corner != 0.0) shapeCorner(segs[i], segs[i - 1], segs[i + 1]);
  const auto gone = [](const LatheSegment& s) { return size(s) < 1e-3; };
  segs.erase(std::remove_if(segs.begin(), segs.end(), gone), segs.end());
  if (segs.size() < 2)
    refuse("expected a profile of at least one move after its start point, found none");
}

/// Offsets the profile (all but the approach) by `distance` away from the side the cycle
/// starts on, in steps of at most half the smallest segment; convex corners that open up
/// get an arc, segments that vanish or turn back are dropped, and neighbours are joined.
void Contour::offsetBy(double distance) {
  const P along = segs.front().end - segs.front().start;
  const P across = segs.back().start - segs.front().start;
  if ((along / across).imag() < 0) distance = -distance;
  LatheSegment approach = segs.front();
  segs.erase(segs.begin());
  const auto at = [&](std::size_t i) { return segs.begin() + static_cast<std::ptrdiff_t>(i); };

  double done = 0.0;
  for (long round = 0; done != distance; ++round) {
    if (round > 100000)
      refuse(
          "expected a profile that can be offset by D, found one that cannot be (segments "
          "too short)");
    double step = 1e9;
    for (const LatheSegment& s : segs)
      step = std::min(step, size(s) / 2);
    step = std::min(step, std::abs(distance - done));
    if (!(step > 0.0)) refuse("expected profile segments of non-zero size, found one of size 0");
    if (distance < 0) step = -step;

    for (std::size_t i = 0; i < segs.size(); ++i) {
      offset(segs[i], step);
      if (size(segs[i]) < 1e-3) segs.erase(at(i--));
    }
    if (segs.empty()) refuse("expected a profile that survives offsetting by D, found none left");

    for (std::size_t i = 0; i + 1 < segs.size(); ++i) {
      if ((segs[i].end - segs[i + 1].start).real() > 1e-2) {
        LatheSegment a = segs[i], b = segs[i + 1];
        offset(a, -step);
        offset(b, -step);
        LatheSegment bridge;
        bridge.arc = true;
        bridge.ccw = distance > 0;
        bridge.start = segs[i].end;
        bridge.end = segs[i + 1].start;
        bridge.centre = (a.end + b.start) / 2.0;
        segs.insert(at(i + 1), bridge);
        ++i;
      }
    }

    for (std::size_t i = 0; i + 1 < segs.size(); ++i) {
      if (!zFalls(segs[i])) {
        // (as LinuxCNC) the smaller of it and the one before goes, and the pass restarts
        if (i == 0)
          refuse(
              "expected a profile whose offset runs one way, found its first segment "
              "turning back");
        segs.erase(at(size(segs[i]) < size(segs[i - 1]) ? i : i - 1));
        i = 0;
        if (segs.size() < 2)
          refuse("expected a profile that survives offsetting by D, found one segment left");
      }
      if (size(segs[i]) < 1e-3) {
        segs.erase(at(i));
        i = 0;  // (as LinuxCNC) the restart skips the first joint
        continue;
      }
      join(segs[i], segs[i + 1]);
    }
    done += step;
  }
  for (std::size_t i = 0; i + 1 < segs.size(); ++i)
    segs[i].end = segs[i + 1].start = (segs[i].end + segs[i + 1].start) / 2.0;
  approach.end = segs.front().start;
  segs.insert(segs.begin(), approach);
}

// ------------------------------------------------------------------------ roughing

class Roughing {
 public:
  Roughing(const std::vector<LatheSegment>& segs, Output& out, double depth, double retract)
      : segs_(segs), out_(out), depth_(depth), escape_(retract * P(1.0, 1.0)) {}

  /// Cuts from `location` (the start point): passes I apart down to the profile, then along
  /// the profile, and (variants 0 and 2) the pockets found on the way up. Variant 2 becomes 3
  /// inside: pockets only, each pocket's passes starting where it was found.
  void run(int variant, P location) {
    starts_.push_back(location);
    std::size_t p = 0;
    if (variant == 2) {  // skip the main passes: follow the profile down to the first pocket
      for (; p < segs_.size(); ++p)
        if (dive(segs_[p], location, -1e9, p == 0)) break;
      variant = 3;
    }
    long steps = 0;
    // Each round cuts one pocket's passes (LinuxCNC recurses for the next pocket).
    while (pocket(variant, location, p, steps)) {
    }
  }

 private:
  /// One pocket; true when another begins at (location, p).
  bool pocket(int variant, P& location, std::size_t& p, long& steps) {
    double x = starts_.back().imag();
    // The loop's whole state; a round that leaves it as it was would repeat for ever.
    struct State {
      std::size_t p, moves;
      double x;
      P location;
      bool operator==(const State& o) const {
        return p == o.p && moves == o.moves && x == o.x && location == o.location;
      }
    };
    std::optional<State> last;
    while (p < segs_.size()) {
      const State now{p, out_.size(), x, location};
      if (++steps > kMaxSteps || (last && *last == now))
        refuse(
            "expected a roughing cycle that ends, found one that does not (LinuxCNC loops "
            "forever here)");
      last = now;
      if ((x - location.imag()) / depth_ > 1e7)
        refuse("expected at most ten million passes, found more (is I too small?)");
      while (x - kTol > location.imag())
        x -= depth_;
      if (dive(segs_[p], location, x, p == 0)) {
        if (variant == 1) {
          for (; p < segs_.size(); ++p)
            climbOnly(segs_[p], location);
          return false;
        }
        for (; p < segs_.size(); ++p)
          if (climb(segs_[p], location)) {
            if (variant == 3) {  // G7x.2: where the next pocket's passes start
              if (location.imag() > starts_.back().imag() && starts_.size() > 1) starts_.pop_back();
              if (starts_.size() == 1) starts_.push_back(location);
            }
            return true;
          }
        return false;
      }
      if (std::abs(location.imag() - x) > kTol) {
        ++p;  // this segment ends above the pass: the next one goes on down
        continue;
      }
      for (std::size_t ip = p; ip < segs_.size(); ++ip) {
        const std::vector<double> zs = crossings(segs_[ip], location.imag());
        if (zs.empty()) continue;
        // The segment cut down along may be an arc crossing the pass twice.
        const double endZ = ip != p ? zs.front() : zs.back();
        const double distance = std::abs(endZ - location.real());
        if (endZ - kTol > location.real()) continue;  // behind the start of the pass
        if (distance < kTol) {
          if (ip == p) continue;  // the crossing where this pass starts
          if (std::abs(location - segs_[ip].start) < kTol) {
            p = ip;  // another segment starts here: go on down along it
          } else {
            x -= depth_;  // a pass of no length
          }
          break;
        }
        P to = location;
        to.real(endZ);
        out_.line(to);
        // A pass too short for the full retraction retracts by half its length.
        const double scale = std::min(1.0, distance / 2 / escape_.real());
        to += scale * escape_;
        out_.rapid(to);
        out_.rapid(location - std::conj(scale * escape_));
        out_.move(p == 0, location);
        x -= depth_;
        break;
      }
    }
    return false;
  }

  /// Follows segment s down to height x (or its end); false while it still goes down.
  bool dive(const LatheSegment& s, P& location, double x, bool rapidMove) {
    if (!s.arc) {
      if (s.start.imag() <= s.end.imag() + kTol) return true;
      if (x < s.end.imag()) {
        out_.move(rapidMove, s.end);
        location = s.end;
        return false;
      }
      const std::vector<double> zs = crossings(s, x);
      if (zs.empty()) refuse("expected the pass to meet the profile, found it missing it");
      const P to(zs.front(), x);
      out_.move(rapidMove, to);
      location = to;
      return false;
    }
    if (std::abs(location - s.end) < kTol || (location - s.end).real() <= kTol) {
      location = s.end;
      return false;
    }
    std::vector<double> zs = crossings(s, x);
    if (zs.empty()) zs = crossings(s, x - kTol);
    const double cz = s.centre.real();
    if (s.ccw) {
      if (location.real() - kTol > cz) return true;  // climbing
      if (zs.empty() || zs.back() > cz) {
        out_.arc(true, s.centre, s.end);
        location = s.end;
        return false;
      }
      const P to(zs.back(), x);
      out_.arc(true, s.centre, to);
      location = to;
      return false;
    }
    if (location.real() <= cz) return true;  // climbing
    if (zs.empty()) {
      out_.arc(false, s.centre, s.end);
      location = s.end;
      return false;
    }
    if (zs.front() < cz) return false;  // met only on the far side: the next pass goes lower
    const P to(zs.front(), x);
    out_.arc(false, s.centre, to);
    location = to;
    return false;
  }

  /// The top of a counter-clockwise arc's circle when the arc runs past it, else its end.
  static P climbEnd(const LatheSegment& s) {
    if (s.end.real() >= s.centre.real()) return s.end;
    return P(s.centre.real(), s.centre.imag() + std::abs(s.start - s.centre));
  }

  /// Follows segment s up (the profile after the lowest pass); true where a pocket begins.
  bool climb(const LatheSegment& s, P& location) {
    if (!s.arc) {
      if (s.end.imag() + kTol < s.start.imag()) return true;
      if (std::abs(location - s.start) > kTol)
        refuse("expected the profile to continue where the cut is, found a gap");
      out_.line(s.end);
      location = s.end;
      return false;
    }
    if (!s.ccw) {
      if (location.real() > s.centre.real()) return true;
      if (std::abs(location - s.end) > 1e-3) out_.arc(false, s.centre, s.end);
      location = s.end;
      return false;
    }
    if (location.real() < s.centre.real()) return true;
    const P to = climbEnd(s);
    if (std::abs(location - to) > 1e-3) out_.arc(true, s.centre, to);
    location = to;
    return true;  // (as LinuxCNC) past a counter-clockwise arc a pocket always begins
  }

  /// G7x.1: along the profile from where it meets the current height, no pockets.
  void climbOnly(const LatheSegment& s, P& location) {
    const std::vector<double> zs = crossings(s, location.imag());
    if (!s.arc) {
      if (s.end.imag() < s.start.imag() || zs.empty()) return;
      location.real(zs.front());
      out_.line(location);
      out_.line(s.end);
      location = s.end;
      return;
    }
    if (zs.empty()) return;
    if (!s.ccw) {
      if (zs.back() > s.centre.real()) return;
      location.real(zs.back());
      out_.line(location);
      if (std::abs(location - s.end) > 1e-3) out_.arc(false, s.centre, s.end);
      location = s.end;
      return;
    }
    if (zs.front() < s.centre.real()) return;
    location.real(zs.front());
    out_.line(location);
    const P to = climbEnd(s);
    if (std::abs(location - to) > 1e-3) out_.arc(true, s.centre, to);
    location = to;
  }

  const std::vector<LatheSegment>& segs_;
  Output& out_;
  double depth_;
  P escape_;
  std::vector<P> starts_;  ///< where the passes of the pockets being cut start (G7x.2)
};

bool finite(P p) {
  return std::isfinite(p.real()) && std::isfinite(p.imag());
}

std::vector<LatheMove> finishing(Contour contour, const LatheCycle& c) {
  // Whether the profile is cut along Z or (turned) along X: decided on the profile alone.
  Contour alone = contour;
  alone.segs.erase(alone.segs.begin());
  alone.normalise();
  for (const LatheSegment& s : alone.segs)
    if (!zFalls(s)) {
      alone.turn();
      alone.normalise();
      break;
    }
  alone.requireOneWay();
  if (alone.flips & 4) contour.turn();
  contour.normalise();
  contour.shapeCorners();
  contour.requireOneWay();

  std::vector<LatheMove> moves;
  Output out(contour.flips, moves);
  if (c.passes > 10000) refuse("expected at most 10000 finishing passes P, found more");
  const int passes = static_cast<int>(c.passes);  // (as LinuxCNC) P4.5 makes 4 passes
  for (int pass = passes; pass > 0; --pass) {
    const double distance = (pass - 1) * (c.d - c.e) / c.passes + c.e;
    Contour path = contour;
    path.offsetBy(distance);
    out.rapid(path.segs.front().start);
    out.rapid(path.segs.front().end);
    for (std::size_t i = 1; i < path.segs.size(); ++i)
      draw(path.segs[i], out);
  }
  return moves;
}

std::vector<LatheMove> roughing(Contour contour, const LatheCycle& c) {
  if (c.code == 72) contour.turn();
  contour.normalise();
  contour.shapeCorners();
  contour.requireOneWay();
  contour.offsetBy(c.d);
  for (LatheSegment& s : contour.segs) {
    const P shift(c.w, c.u);  // (as LinuxCNC) in the normalised frame
    s.start += shift;
    s.end += shift;
    s.centre += shift;
  }
  std::vector<LatheMove> moves;
  Output out(contour.flips, moves);
  const P start = contour.segs.front().start;
  out.rapid(start);
  const LatheSegment& last = contour.segs.back();
  if (last.end.imag() < start.imag()) {
    LatheSegment up;
    up.start = last.end;
    up.end = P(last.end.real(), start.imag());
    contour.segs.push_back(up);
  }
  Roughing(contour.segs, out, std::max(c.depth, 2 * kTol), c.retract).run(c.variant, start);
  return moves;
}

}  // namespace

std::vector<LatheMove> latheCycleMoves(std::vector<LatheSegment> profile, const LatheCycle& c) {
  for (const LatheSegment& s : profile)
    if (!finite(s.start) || !finite(s.end) || (s.arc && !finite(s.centre)))
      refuse("expected finite profile coordinates, found an infinite or undefined one");
  for (const double v : {c.d, c.e, c.passes, c.depth, c.retract, c.u, c.w})
    if (!std::isfinite(v))
      refuse("expected finite cycle words, found an infinite or undefined one");
  if (!finite(c.start)) refuse("expected a finite start point, found an undefined one");
  if (profile.size() < 2) return {};  // (as LinuxCNC) no profile, no cycle
  if (!(c.depth > 0.0))
    refuse("expected a depth of cut I greater than zero, found I" + shortNumber(c.depth));

  Contour contour;
  contour.segs = std::move(profile);
  contour.segs.front().start = c.start;
  return c.code == 70 ? finishing(std::move(contour), c) : roughing(std::move(contour), c);
}

}  // namespace engage::gcode
