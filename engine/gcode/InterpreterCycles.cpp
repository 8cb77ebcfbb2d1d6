// Canned drilling cycles (G73, G81-G83, G85, G89 in G17) and the lathe cycles G70-G72 with the
// profile they read.

#include "engine/gcode/Interpreter.h"

namespace engage::gcode {

void Interpreter::cycle(const Words& w, int column, bool explicitMotion) {
  if (plane_ != Plane::XY)
    fail(column,
         "expected the XY plane (G17) for canned cycles, found " + std::string(planeName(plane_)));
  const bool newCycle = explicitMotion && (!cycleActive_ || motionBefore_ != motion_);
  if (newCycle) {
    // Fanuc and Haas take a cycle without R as one whose R plane is the initial level.
    if (!w.has('R') && fanucLike())
      cycleR_ = incremental_ ? 0.0 : (pos_.z() - workOffset().z()) / unit();
    else if (!w.has('R'))
      fail(column,
           "expected an R word (retract plane) when a canned cycle starts, found none "
           "(--dialect fanuc or haas: the R plane at the initial level)");
    if (!w.has('Z'))
      fail(column, "expected a Z word (hole bottom) when a canned cycle starts, found none");
  }
  if (newCycle && (motion_ == G_82 || motion_ == G_89) && !w.has('P'))
    fail(column, "expected a P word (dwell seconds) when " + codeName('G', motion_) +
                     " starts, found none");
  cycleActive_ = true;
  const Vector3d offset = workOffset();
  // The initial level is the Z where this run of canned-cycle blocks began (LinuxCNC's
  // cycle_il): G98 returns there, and G91 measures R from it.
  if (!cycleInitialValid_) {
    cycleInitial_ = pos_.z();
    cycleInitialValid_ = true;
  }
  double oldZ = cycleInitial_;  // machine mm
  // R and Z: absolute in program coordinates (G90), or R from the current Z and Z from R (G91).
  if (w.has('R')) cycleR_ = w.get('R');
  if (w.has('Z')) cycleZ_ = w.get('Z');
  if (w.has('Q')) cycleQ_ = w.get('Q');
  double r, bottom;
  if (incremental_) {
    r = oldZ + cycleR_ * unit();
    bottom = r + cycleZ_ * unit();
  } else {
    r = cycleR_ * unit() + offset.z();
    bottom = cycleZ_ * unit() + offset.z();
  }
  if (bottom > r)
    fail(w.has('Z') ? w.column('Z') : column,
         "expected the hole bottom Z below the retract plane R, found it above");
  if ((motion_ == G_83 || motion_ == G_73) && !(cycleQ_ > 0.0))
    fail(column, "expected a positive peck depth Q for " + codeName('G', motion_) + ", found Q" +
                     formatNumber(cycleQ_));
  if ((motion_ == G_83 || motion_ == G_73) && (r - bottom) / (cycleQ_ * unit()) > kMaxPecks)
    fail(column, "expected at most " + std::to_string(kMaxPecks) + " pecks, found Q" +
                     formatNumber(cycleQ_) + " over a depth of " + length((r - bottom) / unit()));
  int repeats = 1;
  if (w.has('L')) {
    const double l = w.get('L');
    if (!(l >= 0.0 && l <= kMaxPecks))
      fail(w.column('L'), "expected a repeat count L in 0.." + std::to_string(kMaxPecks) +
                              ", found L" + formatNumber(l));
    repeats = static_cast<int>(std::lround(l));
  }
  // Below the R plane: climb to R first, where the tool is.
  if (oldZ < r) {
    emitLinear(MoveKind::Rapid, Vector3d(pos_.x(), pos_.y(), r));
    oldZ = r;
  }
  const double clear = retractToR_ ? r : oldZ;
  // The first positioning rapid runs at the current height with G99 and at the initial
  // level with G98 (LinuxCNC 2.9 as packaged in Debian 12); later repeats at `clear`.
  double level = retractToR_ ? std::max(pos_.z(), r) : oldZ;
  double x = pos_.x(), y = pos_.y();
  const Vector3d program = programPosition();
  for (int i = 0; i < repeats; ++i) {
    if (w.has('@') || w.has('^')) {
      const Eigen::Vector2d xy =
          polarTarget(w, Eigen::Vector2d((x - offset.x()) / unit(), (y - offset.y()) / unit()));
      x = xy.x() * unit() + offset.x();
      y = xy.y() * unit() + offset.y();
    } else if (incremental_) {
      x += w.has('X') ? w.get('X') * unit() : 0.0;
      y += w.has('Y') ? w.get('Y') * unit() : 0.0;
    } else {
      x = (w.has('X') ? w.get('X') : program.x()) * unit() + offset.x();
      y = (w.has('Y') ? w.get('Y') : program.y()) * unit() + offset.y();
    }
    emitLinear(MoveKind::Rapid, Vector3d(x, y, level));
    emitLinear(MoveKind::Rapid, Vector3d(x, y, r));
    const double f = [&] { return feedFor(1.0, w, column); }();
    auto feedTo = [&](double z) {
      emitLinear(
          MoveKind::Line, Vector3d(x, y, z),
          feedMode_ == FeedMode::InverseTime ? feedFor(std::abs(z - pos_.z()), w, column) : f);
    };
    auto rapidTo = [&](double z) { emitLinear(MoveKind::Rapid, Vector3d(x, y, z)); };
    const double delta = kPeckClearanceInch * kInch;
    switch (motion_) {
      case G_81:
      case G_82:
        feedTo(bottom);
        rapidTo(clear);
        break;
      case G_83:
      case G_73: {
        const double q = cycleQ_ * unit();
        for (double depth = r - q; depth > bottom; depth -= q) {
          feedTo(depth);
          if (motion_ == G_83) {
            rapidTo(r);
            rapidTo(depth + delta);
          } else {
            rapidTo(depth + delta);
          }
        }
        feedTo(bottom);
        rapidTo(clear);
        break;
      }
      case G_85:
      case G_89:
        feedTo(bottom);
        feedTo(r);
        if (clear > r) rapidTo(clear);
        break;
      default:
        break;
    }
    level = clear;
  }
}

void Interpreter::markLathe(const std::string& what) {
  if (out_.latheLine != 0) return;
  out_.latheLine = line_ + 1;
  out_.lathe = what;
}

void Interpreter::latheCycle(const Words& w, int column) {
  const std::string name = codeName('G', motion_);
  if (!w.has('Q'))
    fail(column,
         "expected a Q word (the profile's subroutine number) with " + name + ", found none");
  if (incremental_)
    fail(column, "expected absolute distance mode (G90) for " + name + ", found G91");
  if (plane_ != Plane::XZ)
    fail(column,
         "expected the XZ plane (G18) for " + name + ", found the " + planeName(plane_) + " plane");
  gcode::LatheCycle cycle;
  cycle.code = motion_ / 10;
  cycle.variant = motion_ % 10;
  const Vector3d here = programPosition();
  cycle.start = {w.has('Z') ? w.get('Z') : here.z(), w.has('X') ? w.get('X') : here.x()};
  const auto word = [&](char c, double& v) {
    if (w.has(c)) v = w.get(c);
  };
  word('D', cycle.d);
  word('E', cycle.e);
  word('P', cycle.passes);
  word('I', cycle.depth);
  word('R', cycle.retract);
  word('U', cycle.u);
  word('W', cycle.w);
  // The rapid to the start point comes first, then the profile is read.
  const Vector3d startPoint = target(w, false);
  if ((startPoint - pos_).cwiseAbs().maxCoeff() > 1e-9) emitLinear(MoveKind::Rapid, startPoint);
  const std::vector<gcode::LatheSegment> profile =
      readLatheProfile(std::to_string(std::lround(w.get('Q'))), w.column('Q'), cycle.start);

  std::vector<gcode::LatheMove> moves;
  try {
    moves = gcode::latheCycleMoves(profile, cycle);
  } catch (const gcode::LatheCycleError& e) {
    fail(column, std::string(e.what()) + " in " + name);
  }
  const bool arcIncremental = arcIncremental_;
  arcIncremental_ = false;
  for (const gcode::LatheMove& m : moves) {
    Words step;
    step.v[slot('X')] = m.end.imag();
    step.v[slot('Z')] = m.end.real();
    if (m.kind == gcode::LatheMoveKind::Arc) {
      step.v[slot('I')] = m.centre.imag();
      step.v[slot('K')] = m.centre.real();
      motion_ = m.ccw ? 30 : 20;
      try {
        arc(step, column);
      } catch (const GcodeError& e) {
        // Name the arc's maker: the program has no such arc line.
        throw GcodeError(e.file(), e.line(), e.column(),
                         e.message() + " (an arc that " + name + " made from its profile)");
      }
    } else {
      motion_ = m.kind == gcode::LatheMoveKind::Rapid ? 0 : 10;
      const Vector3d end = target(step, false);
      if ((end - pos_).cwiseAbs().maxCoeff() <= 1e-9) continue;  // LinuxCNC's zero moves
      if (motion_ == G_0)
        emitLinear(MoveKind::Rapid, end);
      else
        emitLinear(MoveKind::Line, end, feedFor((end - pos_).norm(), step, column));
    }
  }
  arcIncremental_ = arcIncremental;
}

std::vector<gcode::LatheSegment> Interpreter::readLatheProfile(const std::string& label, int column,
                                                               gcode::LathePoint start) {
  const int callerLine = line_;
  const Vector3d machinePosition = pos_;
  profile_ = LatheProfile{start.imag(), start.real(), {}};
  gcode::OWord o;
  o.label = label;
  o.keyword = "call";
  o.column = column;
  call(o);
  const std::size_t depth = frames_.size();
  execute(depth);
  if (frames_.size() >= depth)  // it stopped inside the subroutine (a closing '%')
    fail(1, "expected O-endsub closing the profile subroutine o" + label +
                ", found the end of the program");
  std::vector<gcode::LatheSegment> segments = std::move(profile_->segments);
  profile_.reset();
  pos_ = machinePosition;
  line_ = callerLine;
  return segments;
}

void Interpreter::profileBlock(const Block& b) {
  if (b.words.empty()) return;
  Words pw = collect(b);
  LatheProfile& p = *profile_;
  const gcode::LathePoint start{p.z, p.x};
  gcode::LathePoint end = start;
  for (const auto& [absolute, relative] : {std::pair{'X', 'U'}, std::pair{'Z', 'W'}}) {
    if (pw.has(relative) && pw.has(absolute))
      fail(pw.column(relative), std::string("expected either ") + absolute + " or " + relative +
                                    " on a line of a lathe profile, found both");
  }
  if (pw.has('U')) end.imag(end.imag() + pw.get('U') / (diameterMode_ ? 2.0 : 1.0));
  if (pw.has('X')) end.imag(pw.get('X') / (diameterMode_ ? 2.0 : 1.0));
  if (pw.has('W')) end.real(end.real() + pw.get('W'));
  if (pw.has('Z')) end.real(pw.get('Z'));
  gcode::LathePoint centre{pw.has('K') ? pw.get('K') : 0.0, pw.has('I') ? pw.get('I') : 0.0};
  if (const std::optional<int> g = pw.gIn(1)) motion_ = *g;  // they stay in effect
  if (end == start) return;
  gcode::LatheSegment s;
  s.start = start;
  s.end = end;
  if (motion_ == G_2 || motion_ == G_3) {
    if (pw.has('R')) {
      if (pw.has('I') || pw.has('K'))
        fail(pw.column('R'), "expected either R or I/K for an arc, found both");
      // The centre on the side G2/G3 and the sign of R put it.
      const double r = pw.get('R');
      const gcode::LathePoint chord = end - start;
      const double h2 = (r * r - std::norm(chord) / 4) / std::norm(chord);
      if (h2 < -1e-9)
        fail(pw.column('R'), "expected an arc radius that reaches the end point (at least " +
                                 length(std::abs(chord) / 2.0) + "), found R" + formatNumber(r));
      const gcode::LathePoint d =
          gcode::LathePoint(0.0, 1.0) * std::sqrt(std::max(h2, 0.0)) * chord;
      centre = (start + end) / 2.0 + (motion_ == G_3 ? d : -d);
    } else {
      if (!pw.has('I') && !pw.has('K'))
        fail(1, "expected I or K (or R) for an arc of the lathe profile, found neither");
      if (arcIncremental_) centre += start;
    }
    s.arc = true;
    s.ccw = motion_ == G_3;
    s.centre = centre;
  }
  // (as LinuxCNC) other motions add nothing; the next segment starts at their end
  if (motion_ == G_0 || motion_ == G_1 || motion_ == G_2 || motion_ == G_3) {
    p.segments.push_back(s);
    if (pw.has('A') && pw.has('C'))
      fail(pw.column('C'),
           "expected either A (fillet) or C (chamfer) at a profile corner, "
           "found both");
    if (pw.has('A') || pw.has('C')) {
      gcode::LatheSegment corner;
      corner.arc = pw.has('A');
      corner.start = corner.end = corner.centre = end;
      corner.corner = pw.get(corner.arc ? 'A' : 'C');
      p.segments.push_back(corner);
    }
  }
  p.x = end.imag();
  p.z = end.real();
  const Vector3d program = programPosition();
  pos_ = toMachine(Vector3d(p.x, program.y(), p.z));
}

}  // namespace engage::gcode
