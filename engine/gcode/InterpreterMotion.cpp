// Motion: straight moves and their feeds, arcs and helices in three planes, splines and NURBS,
// probing, spindle-synchronised moves, and cutter radius compensation.

#include "engine/gcode/Interpreter.h"

namespace engage::gcode {

Vector3d Interpreter::target(const Words& w, bool machineCoords) const {
  Vector3d end = pos_;
  const Vector3d program = programPosition();
  const Vector3d offset = workOffset();
  for (int a = 0; a < 3; ++a) {
    const char letter = static_cast<char>('X' + a);
    if (!w.has(letter)) continue;
    const double v = w.get(letter);
    if (machineCoords)
      // G53 positions the spindle's gauge line; the tip is one tool length below it.
      end[a] = v * unit() - (a == 2 ? toolLength_ : 0.0);
    else if (incremental_)
      end[a] = (program[a] + v) * unit() + offset[a];
    else
      end[a] = v * unit() + offset[a];
  }
  if (w.has('@') || w.has('^')) {
    const Eigen::Vector2d xy = polarTarget(w, Eigen::Vector2d(program.x(), program.y()));
    end.x() = xy.x() * unit() + offset.x();
    end.y() = xy.y() * unit() + offset.y();
  }
  return end;
}

Eigen::Vector2d Interpreter::polarTarget(const Words& w, const Eigen::Vector2d& current) const {
  const char* clash = w.has('X') ? "X" : w.has('Y') ? "Y" : nullptr;
  if (clash)
    fail(w.column(clash[0]),
         std::string("expected either polar (@, ^) or cartesian words, found both @/^ and ") +
             clash);
  if (plane_ != Plane::XY)
    fail(w.column(w.has('@') ? '@' : '^'),
         "expected the XY plane (G17) for polar words, found " + std::string(planeName(plane_)));
  const double r0 = current.norm();
  const double a0 = std::atan2(current.y(), current.x());
  const double at = w.has('@') ? w.get('@') : 0.0;
  const double angle = w.has('^') ? w.get('^') * kHalfPi / 90.0 : 0.0;
  const double r = incremental_ ? r0 + at : (w.has('@') ? at : r0);
  const double a = incremental_ ? a0 + angle : (w.has('^') ? angle : a0);
  return Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
}

double Interpreter::feedFor(double length, const Words& w, int column) {
  switch (feedMode_) {
    case FeedMode::InverseTime:
      if (!w.has('F'))
        fail(column,
             "expected an F word on every feed move in inverse-time mode (G93), found none");
      if (feed_ <= 0.0) fail(w.column('F'), "expected a positive inverse-time F word, found F0");
      return length * feed_;
    case FeedMode::UnitsPerRevolution:
      if (spindleSpeed_ <= 0.0)
        fail(column, "expected a spindle speed S for feed per revolution (G95), found S0");
      if (feed_ <= 0.0)
        fail(column, "expected a positive F word before the first feed move, found F0");
      return feed_ * spindleSpeed_;
    case FeedMode::UnitsPerMinute:
      break;
  }
  if (feed_ <= 0.0)
    fail(column, "expected a positive F word before the first feed move, found feed 0");
  return feed_;
}

void Interpreter::emitLinear(MoveKind kind, const Vector3d& end, double feed) {
  Move m = base(kind);
  m.end = end;
  m.feed = kind == MoveKind::Rapid ? 0.0 : feed;
  pos_ = end;
  out_.moves.push_back(std::move(m));
}

void Interpreter::failCorner(const std::string& found) const {
  const PendingCorner& c = *corner_;
  throw GcodeError(files_[static_cast<std::size_t>(c.file)]->name, c.line, c.word.column,
                   std::string("expected a G1 in the XY plane (G17) after the corner ,") +
                       c.word.kind +
                       " (Fanuc and Haas round or chamfer the corner between two "
                       "such moves), found " +
                       found);
}

void Interpreter::applyCorner() {
  const PendingCorner c = *corner_;
  corner_.reset();
  Move& a = out_.moves[c.move];
  Move& b = out_.moves[c.move + 1];
  auto flat = [](const Move& m) { return std::abs(m.end.z() - m.start.z()) <= 1e-9; };
  if (!out_.toolLoads.empty() && out_.toolLoads.back().firstMove > c.move)
    failCorner("a tool change");
  if (b.kind != MoveKind::Line || !flat(a) || !flat(b) || plane_ != Plane::XY)
    failCorner(b.kind != MoveKind::Line ? "another move" : "a move that changes Z");
  const Vector3d d1 = (a.end - a.start).normalized(), d2 = (b.end - b.start).normalized();
  const double cross = d1.x() * d2.y() - d1.y() * d2.x();
  const double turn = std::atan2(std::abs(cross), d1.dot(d2));  // 0: straight on
  if (!(turn > 1e-9) || !(turn < kPi - 1e-9)) failCorner("no corner (the moves are in line)");
  const double v = c.word.value * (inch_ ? kInch : 1.0);
  // From the corner back along the first move and on along the second: a fillet's tangent
  // points R tan(turn / 2) away; a chamfer's C.
  const double t = c.word.kind == 'R' ? v * std::tan(0.5 * turn) : v;
  const double la = (a.end - a.start).norm(), lb = (b.end - b.start).norm();
  if (t > la + 1e-9 || t > lb + 1e-9)
    throw GcodeError(files_[static_cast<std::size_t>(c.file)]->name, c.line, c.word.column,
                     std::string("expected a corner ,") + c.word.kind +
                         " that fits both moves (it takes " + length(t / unit()) +
                         " of each), found moves of " + length(la / unit()) + " and " +
                         length(lb / unit()));
  const Vector3d corner = a.end, from = corner - t * d1, to = corner + t * d2;
  Move piece = a;
  piece.start = from;
  piece.end = to;
  if (c.word.kind == 'R') {
    const Vector3d left(-d1.y(), d1.x(), 0.0);  // a left turn's centre is to the left
    piece.kind = MoveKind::Arc;
    piece.turns = cross > 0.0 ? 1 : -1;
    piece.center = from + (cross > 0.0 ? 1.0 : -1.0) * v * left;
  }
  a.end = from;
  b.start = to;
  out_.moves.insert(out_.moves.begin() + static_cast<long>(c.move) + 1, std::move(piece));
}

void Interpreter::motion(const Words& w, bool explicitMotion, bool machineCoords) {
  const int column = explicitMotion ? w.gColumn(motion_) : 1;
  const bool plainLine = motion_ == G_1 && !comp_.offsetting();
  if (corner_ && !plainLine)
    failCorner(comp_.offsetting() ? "a move under cutter radius compensation"
                                  : codeName('G', motion_));
  if (w.corner && !plainLine)
    fail(w.corner->column, std::string("expected a corner ,") + w.corner->kind +
                               " on a G1 without cutter radius compensation, found it with " +
                               codeName('G', motion_));
  if (comp_.on() && motion_ != G_0 && motion_ != G_1 && motion_ != G_2 && motion_ != G_3)
    fail(column, "expected G0, G1, G2 or G3 with cutter radius compensation on, found " +
                     codeName('G', motion_));
  switch (motion_) {
    case G_0:
      arcNotAllowed_ = false;
      if (comp_.offsetting()) {
        compensated(MoveKind::Rapid, target(w, false), 0.0, column);
        return;
      }
      emitLinear(MoveKind::Rapid, target(w, machineCoords));
      return;
    case G_1: {
      arcNotAllowed_ = false;
      const Vector3d end = target(w, machineCoords);
      const double feed = feedFor((end - pos_).norm(), w, column);
      if (comp_.offsetting()) {
        compensated(MoveKind::Line, end, feed, column);
        return;
      }
      emitLinear(MoveKind::Line, end, feed);
      if (corner_) applyCorner();
      if (w.corner) corner_ = PendingCorner{out_.moves.size() - 1, *w.corner, file_, line_ + 1};
      return;
    }
    case G_2:
    case G_3:
      if (arcNotAllowed_)
        fail(column,
             "expected a straight move just after G40 (LinuxCNC ends compensation "
             "with one), found " +
                 codeName('G', motion_));
      arc(w, column);
      return;
    case G_5:
    case G_5_1:
      spline(w, column);
      return;
    case G_5_2:
      nurbsPoint(w, column);
      return;
    case G_5_3:
      nurbsEnd(w, column);
      return;
    case G_73:
    case G_81:
    case G_82:
    case G_83:
    case G_85:
    case G_89:
      cycle(w, column, explicitMotion);
      return;
    case G_33:
    case G_33_1:
      synchronised(w, column);
      return;
    case G_38_2:
    case G_38_3:
    case G_38_4:
    case G_38_5:
      probe(w, column);
      return;
    default:
      if (isLatheCycle(motion_)) {
        latheCycle(w, column);
        return;
      }
      fail(column, "expected a supported motion, found " + codeName('G', motion_));
  }
}

void Interpreter::synchronised(const Words& w, int column) {
  const std::string name = codeName('G', motion_);
  if (!w.has('K'))
    fail(column,
         "expected a K word (distance per spindle revolution) with " + name + ", found none");
  if (!(w.get('K') > 0.0))
    fail(w.column('K'),
         "expected a positive K word with " + name + ", found K" + formatNumber(w.get('K')));
  if (!(spindleSpeed_ > 0.0))
    fail(column, "expected a spindle speed S > 0 for " + name + " (feed = K x S), found S0");
  const double feed = w.get('K') * unit() * spindleSpeed_;
  const Vector3d start = pos_;
  emitLinear(MoveKind::Line, target(w, false), feed);
  out_.moves.back().feedSource = FeedSource::Spindle;
  if (motion_ == G_33_1) {
    emitLinear(MoveKind::Line, start, feed);
    out_.moves.back().feedSource = FeedSource::Spindle;
  }
}

void Interpreter::probe(const Words& w, int column) {
  const std::string name = codeName('G', motion_);
  if (feedMode_ == FeedMode::InverseTime)
    fail(column, "expected units-per-minute feed (G94) for " + name + ", found inverse time (G93)");
  const Vector3d start = pos_;
  const Vector3d end = target(w, false);
  const double distance = (end - start).norm();
  // LinuxCNC 2.9 refuses a zero-length probe only where no contact is an error (G38.2,
  // G38.4); its stand-alone interpreter backs off any probe of non-zero length.
  const bool mustTouch = motion_ == G_38_2 || motion_ == G_38_4;
  if (distance == 0.0 && mustTouch)
    fail(column,
         "expected a probe target away from the start point, found the start point "
         "itself");
  if (options_.probeContact && distance > 0.0 && (motion_ == G_38_2 || motion_ == G_38_3)) {
    // Towards the stock: the probe stops where it touches it.
    const Vector3d frame = options_.machine ? options_.machine->workOffset : Vector3d::Zero();
    const double t = options_.probeContact(start - frame, end - frame, tool_);
    if (t <= 0.0)
      fail(column, "expected the probe clear of the stock when " + name +
                       " starts, found it touching (the control refuses a tripped probe)");
    if (t > 1.0 && mustTouch)
      fail(column,
           "expected the probe to touch the stock on its way to the target, found no "
           "contact (" +
               name + " stops the program then)");
    const Vector3d stop = t > 1.0 ? end : Vector3d(start + t * (end - start));
    emitLinear(MoveKind::Line, stop, feedFor(distance, w, column));
    out_.moves.back().feedSource = FeedSource::Probe;
    const Vector3d program = (stop - workOffset()) / unit();
    for (int a = 0; a < 3; ++a)
      params_[5061 + static_cast<std::size_t>(a)] = program[a];
    params_[5070] = t > 1.0 ? 0.0 : 1.0;
    return;
  }
  if (distance > 0.0) {
    const double feed = feedFor(distance, w, column);
    const double backoff = inch_ ? 0.01 * kInch : 0.254;  // mm
    emitLinear(MoveKind::Line, end, feed);
    out_.moves.back().feedSource = FeedSource::Probe;
    emitLinear(MoveKind::Line, end + (start - end) * (backoff / distance), feed);
    out_.moves.back().feedSource = FeedSource::Probe;
  }
  const Vector3d program = (end - workOffset()) / unit();
  for (int a = 0; a < 3; ++a)
    params_[5061 + static_cast<std::size_t>(a)] = program[a];
  params_[5070] = 0.0;
}

void Interpreter::arc(const Words& w, int column) {
  const PlaneAxes ax = planeAxes(plane_);
  const Vector3d end = target(w, false);
  const bool ccw = motion_ == G_3;
  const double tol = (inch_ ? kArcToleranceInch : kArcToleranceMm) * unit();
  Move m = base(MoveKind::Arc);
  m.end = end;
  int turns = 1;
  if (w.has('P')) {
    const double p = w.get('P');
    if (p < 1.0 || std::abs(p - std::round(p)) > 1e-9)
      fail(w.column('P'), "expected a whole number of turns P >= 1, found P" + formatNumber(p));
    turns = static_cast<int>(std::lround(p));
  }
  m.turns = ccw ? turns : -turns;
  const char offPlane = plane_ == Plane::XY ? 'K' : plane_ == Plane::XZ ? 'J' : 'I';
  // grbl ignores the off-plane word (FreeCAD's grbl post writes K0 on G17 arcs).
  if (w.has(offPlane) && options_.dialect != Dialect::Grbl)
    fail(w.column(offPlane), std::string("expected ") + ax.ia + "/" + ax.ib +
                                 " centre words for an arc in the " + planeName(plane_) +
                                 " plane, found " + offPlane +
                                 " (--dialect grbl ignores it, as grbl does)");
  const double sa = pos_[ax.a], sb = pos_[ax.b], ea = end[ax.a], eb = end[ax.b];
  double ca = 0.0, cb = 0.0;
  if (w.has('R')) {
    if (w.has(ax.ia) || w.has(ax.ib))
      fail(w.column('R'),
           std::string("expected either R or ") + ax.ia + "/" + ax.ib + " for an arc, found both");
    const double radius = w.get('R') * unit();
    if (std::abs(ea - sa) < 1e-12 && std::abs(eb - sb) < 1e-12)
      fail(w.column('R'),
           "expected an R-form arc to end elsewhere than it starts (use I/J for a full circle), "
           "found the same point");
    const double ma = (sa + ea) / 2.0, mb = (sb + eb) / 2.0;
    double half = std::hypot(ea - ma, eb - mb);
    const double r = std::abs(radius);
    if (half - r > tol)
      fail(w.column('R'), "expected an arc radius that reaches the end point (at least " +
                              length(half / unit()) + "), found R" + formatNumber(w.get('R')));
    if (half / r > 1.0 - 1e-12) half = r;
    const double chordAngle = std::atan2(eb - sb, ea - sa);
    const double theta = ((!ccw && radius > 0.0) || (ccw && radius < 0.0)) ? chordAngle - kHalfPi
                                                                           : chordAngle + kHalfPi;
    const double offset = r * std::cos(std::asin(half / r));
    ca = ma + offset * std::cos(theta);
    cb = mb + offset * std::sin(theta);
  } else {
    if (!w.has(ax.ia) && !w.has(ax.ib))
      fail(column, std::string("expected ") + ax.ia + "/" + ax.ib +
                       " centre words or R for an arc in the " + planeName(plane_) +
                       " plane, found neither");
    const Vector3d offset = workOffset();
    const double ia = w.has(ax.ia) ? w.get(ax.ia) * unit() : 0.0;
    const double ib = w.has(ax.ib) ? w.get(ax.ib) * unit() : 0.0;
    if (arcIncremental_) {
      ca = sa + ia;
      cb = sb + ib;
    } else {
      ca = ia + offset[ax.a];
      cb = ib + offset[ax.b];
    }
    const double r1 = std::hypot(sa - ca, sb - cb);
    const double r2 = std::hypot(ea - ca, eb - cb);
    if (r1 < 0.1 * tol || r2 < 0.1 * tol)
      fail(column, "expected an arc of non-zero radius, found radius 0");
    if (std::abs(r1 - r2) > tol)
      fail(column, "expected the arc's end on its circle (radius to start " + length(r1 / unit()) +
                       ", to end " + length(r2 / unit()) + "), found them " +
                       length(std::abs(r1 - r2) / unit()) + " apart, more than " +
                       length(tol / unit()));
  }
  m.center = pos_;
  m.center[ax.a] = ca;
  m.center[ax.b] = cb;
  m.start = pos_;  // (the programmed start, also right after G40: arcs are refused there)
  pos_ = end;
  m.feed = feedFor(moveLength(m), w, column);
  if (comp_.offsetting()) {
    try {
      comp_.arc(std::move(m));
    } catch (const CompensationError& e) {
      failCompensation(column, e);
    }
    return;
  }
  out_.moves.push_back(std::move(m));
}

void Interpreter::compensated(MoveKind kind, const Vector3d& end, double feed, int column) {
  Move m = base(kind);
  m.start = pos_;
  m.end = end;
  m.feed = feed;
  pos_ = end;
  try {
    comp_.straight(std::move(m));
  } catch (const CompensationError& e) {
    failCompensation(column, e);
  }
}

void Interpreter::compensation(int code, const Words& w) {
  const int column = w.gColumn(code);
  if (code == G_40) {
    const bool offsetting = comp_.offsetting();
    Vector3d at;
    try {
      at = comp_.off();
    } catch (const CompensationError& e) {
      failCompensation(column, e);
    }
    if (offsetting) {
      physicalStart_ = at;
      arcNotAllowed_ = true;
    }
    return;
  }
  if (plane_ == Plane::YZ)
    fail(column,
         "expected G17 or G18 (the XY or XZ plane) for cutter radius compensation, "
         "found G19 (YZ)");
  const auto side =
      code == G_41 || code == G_41_1 ? CutterCompensation::Left : CutterCompensation::Right;
  double diameter = 0.0;  // mm
  if (code == G_41_1 || code == G_42_1) {
    if (!w.has('D'))
      fail(column,
           "expected a D word (the tool's diameter) with " + codeName('G', code) + ", found none");
    if (w.has('L'))
      fail(w.column('L'), "expected no L word (a lathe tool's orientation) with " +
                              codeName('G', code) +
                              ", found one (lathe tools are not "
                              "interpreted)");
    diameter = w.get('D') * unit();
  } else {
    int tool = tool_;
    if (options_.wearCompensation) {
      // The D register holds only the wear: the CAM wrote the tool centre's path.
      if (w.has('D') && !(w.get('D') >= 0.0))
        fail(w.column('D'), "expected a register number D with " + codeName('G', code) +
                                ", found D" + formatNumber(w.get('D')));
    } else if (w.has('D')) {
      const double d = w.get('D');
      if (!(d >= 0.0) || std::abs(d - std::round(d)) >= 1e-4)
        fail(w.column('D'), "expected a tool number D with " + codeName('G', code) + ", found D" +
                                formatNumber(d));
      tool = static_cast<int>(std::lround(d));
      // D0 offsets by nothing, as on LinuxCNC, Fanuc and Haas; with no table at all, the one
      // cutter of the run (soleToolDiameter) is every D's.
      if (tool != 0 && !toolDiameters_.count(tool) &&
          !(toolDiameters_.empty() && options_.soleToolDiameter > 0.0))
        fail(w.column('D'),
             "expected a tool of the tool table in D (its radius offsets the "
             "path), found D" +
                 std::to_string(tool) +
                 (options_.toolTable.empty() ? " and no tool table (--tool-table)"
                                             : ", which the table does not have"));
    }
    const auto it = toolDiameters_.find(tool);
    diameter = options_.wearCompensation || (w.has('D') && tool == 0) ? 0.0
               : it != toolDiameters_.end()                           ? it->second
               : toolDiameters_.empty()                               ? options_.soleToolDiameter
                                                                      : 0.0;
    if (!options_.wearCompensation && !(diameter > 0.0))
      out_.unoffsetCompensation.push_back({file_, line_ + 1});
  }
  compensationByRegister_ = code == G_41 || code == G_42;
  // Fanuc and Haas take G41 (G42) restated while it is on, with the same offset, as a no-op
  // (posts write it on every contour line); LinuxCNC refuses it.
  if (options_.dialect == Dialect::Fanuc && comp_.onAs(side, diameter / 2.0)) return;
  try {
    comp_.on(side, diameter / 2.0, physicalStart_ ? *physicalStart_ : pos_, unit(), plane_);
  } catch (const CompensationError& e) {
    failCompensation(column, e);
  }
}

void Interpreter::failCompensation(int column, const CompensationError& e) const {
  std::string message = e.what();
  // A program whose path is already the tool centre's fails here with the tool's radius.
  if (compensationByRegister_ && !options_.wearCompensation)
    message +=
        " (if the program's path is already the tool centre's, the CAM's \"wear\" "
        "compensation with only the wear in the D register, give --cutter-comp wear)";
  fail(column, message);
}

void Interpreter::refuseWithCompensation(const Words& w, bool onBefore) {
  auto refuse = [&](int column, const std::string& what) {
    fail(column, "expected G40 before " + what + ", found cutter radius compensation on");
  };
  if (const auto g = w.gIn(2); g && onBefore) refuse(w.gColumn(*g), "changing the plane");
  if (const auto g = w.gIn(8))
    refuse(w.gColumn(*g), "a tool length offset (" + codeName('G', *g) + ")");
  if (const auto g = w.gIn(12)) refuse(w.gColumn(*g), "changing the coordinate system");
  for (const auto& [code, c] : w.g)
    if (code == G_28 || code == G_30 || code == G_92 || code == G_92_1 || code == G_92_2 ||
        code == G_92_3 || code == G_53 || code == G_10)
      refuse(c, codeName('G', code));
}

void Interpreter::spline(const Words& w, int column) {
  if (plane_ != Plane::XY)
    fail(column, "expected the XY plane (G17) for G5/G5.1 splines, found " +
                     std::string(planeName(plane_)));
  if (w.has('Z'))
    fail(w.column('Z'), "expected no Z word on a G5/G5.1 spline (they are planar), found Z");
  const Vector3d end = target(w, false);
  const Eigen::Vector2d p0(pos_.x(), pos_.y());
  const Eigen::Vector2d p3(end.x(), end.y());
  std::vector<Eigen::Vector2d> pts;
  if (motion_ == G_5) {
    Eigen::Vector2d i;
    if (w.has('I') || w.has('J')) {
      if (!(w.has('I') && w.has('J')))
        fail(column, "expected both I and J (or neither after another G5) on G5, found one");
      i = Eigen::Vector2d(w.get('I'), w.get('J')) * unit();
    } else {
      if (!lastCubic_) fail(column, "expected I and J on the first G5 of a curve, found neither");
      i = -*lastCubic_;
    }
    if (!(w.has('P') && w.has('Q')))
      fail(column, "expected P and Q on G5, found " + std::string(w.has('P') ? "no Q" : "no P"));
    const Eigen::Vector2d pq(w.get('P') * unit(), w.get('Q') * unit());
    pts = flattened(column,
                    [&] { return gcode::flattenCubic(p0, p0 + i, p3 + pq, p3, kSplineTolerance); });
    lastCubic_ = pq;
  } else {
    if (!w.has('I') && !w.has('J')) fail(column, "expected I and/or J on G5.1, found neither");
    const Eigen::Vector2d i(w.has('I') ? w.get('I') * unit() : 0.0,
                            w.has('J') ? w.get('J') * unit() : 0.0);
    pts = flattened(column,
                    [&] { return gcode::flattenQuadratic(p0, p0 + i, p3, kSplineTolerance); });
  }
  emitSpline(pts, w, column);
}

void Interpreter::emitSpline(const std::vector<Eigen::Vector2d>& pts, const Words& w, int column) {
  Move m = base(MoveKind::Spline);
  for (const Eigen::Vector2d& p : pts)
    m.points.emplace_back(p.x(), p.y(), pos_.z());
  m.end = m.points.back();
  pos_ = m.end;
  m.feed = feedFor(moveLength(m), w, column);
  out_.moves.push_back(std::move(m));
}

void Interpreter::nurbsPoint(const Words& w, int column) {
  if (plane_ != Plane::XY)
    fail(column,
         "expected the XY plane (G17) for G5.2 NURBS, found " + std::string(planeName(plane_)));
  if (nurbs_.empty()) {
    nurbsOrder_ = w.has('L') ? static_cast<int>(std::lround(w.get('L'))) : 3;
    if (nurbsOrder_ < 2)
      fail(w.column('L'), "expected a NURBS order L >= 2, found L" + std::to_string(nurbsOrder_));
    nurbs_.push_back({Eigen::Vector2d(pos_.x(), pos_.y()), 1.0});
    nurbsLine_ = line_;
  }
  const Vector3d p = target(w, false);
  const double weight = w.has('P') ? w.get('P') : 1.0;
  if (weight <= 0.0)
    fail(w.column('P'), "expected a positive NURBS weight P, found P" + formatNumber(weight));
  if (w.has('X') || w.has('Y')) nurbs_.push_back({Eigen::Vector2d(p.x(), p.y()), weight});
}

void Interpreter::nurbsEnd(const Words& w, int column) {
  if (nurbs_.size() < 2) fail(column, "expected G5.2 control points before G5.3, found none");
  if (static_cast<int>(nurbs_.size()) < nurbsOrder_)
    fail(column, "expected at least L = " + std::to_string(nurbsOrder_) +
                     " NURBS control points, found " + std::to_string(nurbs_.size()));
  std::vector<Eigen::Vector2d> cp;
  std::vector<double> weights;
  for (const auto& [p, wt] : nurbs_) {
    cp.push_back(p);
    weights.push_back(wt);
  }
  const auto pts = flattened(
      column, [&] { return gcode::flattenNurbs(cp, weights, nurbsOrder_, kSplineTolerance); });
  const int saved = line_;
  recordBlock();  // the G5.3 line carries the curve's F; the move reports its G5.2 line
  line_ = nurbsLine_;
  emitSpline(pts, w, column);
  line_ = saved;
  nurbs_.clear();
  motion_ = G_80;  // G5.3 ends the NURBS block; LinuxCNC then needs a new motion word
}

}  // namespace engage::gcode
