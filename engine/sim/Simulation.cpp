#include "engine/sim/Simulation.h"

#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "cutters/Sweep.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <string>
#include <unordered_map>

namespace engage {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Rapids removing less than this many voxels are rounding, not a collision.
constexpr double kRapidNoiseVoxels = 0.5;
/// Steps removing less than this fraction of a voxel per step are air cuts.
constexpr double kAirVoxels = 0.01;

/// Set by requestStop.
std::atomic<bool> stopFlag{false};
static_assert(std::atomic<bool>::is_always_lock_free, "requestStop must be async-signal-safe");

}  // namespace

void requestStop() noexcept {
  stopFlag.store(true, std::memory_order_relaxed);
}

bool stopRequested() noexcept {
  return stopFlag.load(std::memory_order_relaxed);
}

namespace {

/// Signed curvature of the tool-centre path in XY, 1/mm (+ counter-clockwise).
double curvatureOf(const Move& m) {
  if (m.kind != MoveKind::Arc || m.plane != Plane::XY) return 0.0;
  const double r = arcRadius(m);
  return r > 0.0 ? (m.turns > 0 ? 1.0 : -1.0) / r : 0.0;
}

/// The signed curvature of step `sp` of move `m` at its end across the tool, 1/mm (+ turning
/// left seen from the spindle's side): curvatureOf for an upright tool; for a tilted one, an
/// arc's through its last three points seen along the axis (exact for an arc across the tool,
/// as a table machine carries an XY arc of the joints).
double toolCurvature(const Move& m, const StepPath& sp) {
  if (!sp.tilted()) return curvatureOf(m);
  const std::size_t n = sp.points.size();
  if (m.kind != MoveKind::Arc || n < 3) return 0.0;
  const Eigen::Matrix3d toTool = sp.toolToPart().transpose();
  const Eigen::Vector2d a = (toTool * sp.points[n - 3]).head<2>();
  const Eigen::Vector2d b = (toTool * sp.points[n - 2]).head<2>();
  const Eigen::Vector2d c = (toTool * sp.points[n - 1]).head<2>();
  const Eigen::Vector2d ab = b - a, bc = c - b;
  const double lengths = ab.norm() * bc.norm() * (c - a).norm();
  // Menger's curvature: four times the triangle's area over its sides' product.
  return lengths > 0.0 ? 2.0 * (ab.x() * bc.y() - ab.y() * bc.x()) / lengths : 0.0;
}

/// A count or length for a message, six significant digits ("1.33333e+09").
std::string formatCount(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// A step before it is cut: a piece [t0, t1] of a move.
struct Planned {
  std::size_t move;
  double t0, t1;
  double length;  ///< of the step, mm (a spline's length is a walk over its points: once)
};

/// The longest reach of a cutter from its tip (the hypotenuse of its radius and height), mm.
double reachOf(const AptCutter& cutter) {
  return std::hypot(cutter.maxRadius(), cutter.height());
}

/// Every move in pieces no longer than L (arcs as arc pieces, never longer than the move); on
/// a machine with rotary kinematics, no point of the cutter travels further than L in the
/// part's frame over a step.
std::vector<Planned> planSteps(const Toolpath& path, const CutterSet& cutters, double L,
                               std::size_t maxSteps) {
  checkStepCount(path, L, maxSteps);
  std::vector<Planned> plan;
  for (std::size_t i = 0; i < path.moves.size(); ++i) {
    const Move& m = path.moves[i];
    const double len = path.kinematics.rotary()
                           ? moveTravel(m, path.kinematics, reachOf(cutters.of(m.tool)))
                           : moveLength(m);
    if (len <= 0.0) continue;
    const int n = std::max(1, static_cast<int>(std::ceil(len / L - 1e-9)));
    for (int k = 0; k < n; ++k)
      plan.push_back({i, static_cast<double>(k) / n, static_cast<double>(k + 1) / n, len / n});
  }
  return plan;
}

/// A step's record as far as its move says: where, how long, how fast (`arc` accumulates
/// the path length).
StepRecord plannedRecord(const Planned& p, const Move& m, const StepPath& sp, double& arc) {
  StepRecord r;
  r.move = p.move;
  r.t0 = p.t0;
  r.t1 = p.t1;
  r.line = m.line;
  r.kind = m.kind;
  r.tool = m.tool;
  r.length = p.length;
  arc += r.length;
  r.arcLength = arc;
  r.end = sp.end;
  r.feed = m.kind == MoveKind::Rapid ? 0.0 : m.feed;
  r.dt = r.feed > 0.0 ? r.length / r.feed * 60.0 : 0.0;
  if (turnsRotary(m)) {
    // The rotary axes turn: the time is the move's share of its duration, the length the
    // tip's travel on the part, the feed the tip's speed there.
    const double tipTravel = sp.length();
    arc += tipTravel - r.length;
    r.length = tipTravel;
    r.arcLength = arc;
    r.dt = (p.t1 - p.t0) * rotaryMoveMinutes(m) * 60.0;
    r.feed = r.dt > 0.0 ? r.length / (r.dt / 60.0) : 0.0;
  }
  return r;
}

/// Rotary motion without the machine's kinematics, and U, V, W motion, refused with the line.
void refuseOtherAxes(const Toolpath& path) {
  for (const Move& m : path.moves) {
    if (!m.otherAxes || (turnsRotary(m) && path.kinematics.rotary())) continue;
    const std::string where =
        path.files[static_cast<std::size_t>(m.file)] + ":" + std::to_string(m.line) + ": ";
    if (turnsRotary(m))
      throw ParameterError(where +
                           "this line moves a rotary axis: give the machine's kinematics (a "
                           "--machine file with \"kinematics\") to simulate it");
    throw ParameterError(where +
                         "this line moves a U, V or W axis; engage simulates X, Y, Z "
                         "and, with the machine's kinematics, A, B, C");
  }
}

/// A tilted tool in a stock that cannot follow it, refused with the first such line.
void refuseTilt(const Toolpath& path, const Stock& stock) {
  if (stock.followsTiltedTools()) return;
  for (const Move& m : path.moves)
    if (tiltsTool(m, path.kinematics))
      throw ParameterError(
          path.files[static_cast<std::size_t>(m.file)] + ":" + std::to_string(m.line) +
          ": the tool is tilted here (" + kinematicsTypeName(path.kinematics.type) +
          " kinematics); the dexel stock's rays are vertical and cannot follow it: run it in "
          "the voxel stock (--stock-model voxel)");
}

/// The analytic model of one feed step at stepover s and depth d (plunges: pi W(d)^2 F, no
/// paper form), the step's `travel` in the tool's frame; NaN where the model has no steady
/// state.
void analytic(StepRecord& r, const AptCutter& cutter, const Eigen::Vector3d& travel, double s,
              double d) {
  if (travel.head<2>().norm() <= 1e-9 && r.kind == MoveKind::Line) {
    // A plunge: the cross-section normal to the motion is the cutter's slice where it
    // enters the material, pi W(depth)^2; the paper has no form for it.
    const double w = cutter.radiusAt(d);
    r.mrrExact = travel.z() < 0.0 ? kPi * w * w * r.feed : kNaN;
    r.mrrPaper = kNaN;
    return;
  }
  try {
    const EngagementModel model(cutter, s, d);
    PathShape shape;
    if (r.side != PathSide::Straight) shape = PathShape{r.side, 1.0 / std::abs(r.curvature)};
    r.mrrExact = model.mrr(r.feed, shape);
    r.mrrPaper = model.mrrPaper(r.feed, shape);
  } catch (const ParameterError&) {
    r.mrrExact = r.mrrPaper = kNaN;  // no steady state (arc tighter than the cutter, ...)
  }
}

/// Whether the step's tool is neither square to the part's faces nor steady: its axis turns,
/// or lies off the part's X, Y and Z (a tool along one of them meets a box's faces square or
/// parallel, as the paper's upright tool does).
bool obliqueToPart(const StepPath& sp) {
  if (!sp.tilted()) return false;
  if (sp.turning()) return true;
  return sp.axisEnd.cwiseAbs().maxCoeff() < 1.0 - 1e-6;  // (within 0.08 deg)
}

void accumulate(Agreement& a, double measured, double analytic) {
  if (!(std::isfinite(analytic) && analytic > 0.0)) return;
  const double rel = std::abs(measured / analytic - 1.0);
  a.meanRelative += rel;
  a.maxRelative = std::max(a.maxRelative, rel);
  ++a.steps;
}

void finish(Agreement& a) {
  if (a.steps > 0) a.meanRelative /= static_cast<double>(a.steps);
}

}  // namespace

const std::vector<ToolPart>& CutterSet::partsOf(int tool) const {
  const auto it = partsByTool.find(tool);
  if (it != partsByTool.end()) return it->second;
  static const std::vector<ToolPart> none;
  return byTool.count(tool) ? none : fallbackParts;  // a library tool without parts: none
}

const AptCutter& CutterSet::of(int tool) const {
  const auto it = byTool.find(tool);
  if (it != byTool.end()) return it->second;
  if (fallback) return *fallback;
  throw ParameterError("no cutter for tool T" + std::to_string(tool));
}

double CutterSet::smallestRadius() const {
  double r = fallback ? fallback->radius() : std::numeric_limits<double>::infinity();
  for (const auto& [tool, cutter] : byTool)
    r = std::min(r, cutter.radius());
  return r;
}

double stepCount(const Toolpath& path, double L) {
  double steps = 0.0;
  for (const Move& m : path.moves) {
    const double len = moveTravel(m, path.kinematics, 0.0);
    if (len > 0.0) steps += std::max(1.0, std::ceil(len / L - 1e-9));
  }
  return steps;
}

void checkStepCount(const Toolpath& path, double L, std::size_t maxSteps) {
  const double steps = stepCount(path, L);
  if (!(steps > static_cast<double>(maxSteps))) return;
  double longest = 0.0;
  const Move* longestMove = nullptr;
  for (const Move& m : path.moves) {
    const double len = moveTravel(m, path.kinematics, 0.0);
    if (len > longest) {
      longest = len;
      longestMove = &m;
    }
  }
  throw ParameterError(
      "the program makes " + formatCount(steps) + " steps of at most " + formatCount(L) +
      " mm, more than the limit of " + std::to_string(maxSteps) + " (--max-steps); its longest " +
      "move, at line " + std::to_string(longestMove ? longestMove->line : 0) + ", is " +
      formatCount(longest) + " mm long: check the program's units, or give a longer --step");
}

SimulationResult simulate(const Toolpath& path, const AptCutter& cutter, Stock& stock,
                          const SimulationOptions& options) {
  CutterSet one;
  one.fallback = cutter;
  return simulate(path, one, stock, options);
}

namespace {

/// Add one step's contact to the collisions, joining the last record when it is the same move
/// and part: a rapid's removals add up; a shank or holder meets the same material step after
/// step (it removes nothing), so its record keeps the most it met at once.
void addCollision(std::vector<Collision>& list, const Collision& c) {
  // The records of this move (a rapid's own removal and its shank's contact interleave).
  for (auto it = list.rbegin(); it != list.rend() && it->move == c.move; ++it)
    if (it->part == c.part && it->lastStep + 1 == c.firstStep) {
      it->lastStep = c.lastStep;
      it->volume = c.part == "rapid" ? it->volume + c.volume : std::max(it->volume, c.volume);
      return;
    }
  list.push_back(c);
}

/// Where each tool's tip has been: the lowest height at each exact XY of a move's end (to 1e-9
/// mm for a tilted tool), in the tool's frame (StepPath::toolToPart; XY and Z for an upright
/// tool), for each axis the tool held. A step along the tool's axis (a plunge or a retract) at an
/// XY where the same tool's tip, held on the same axis, has already been at or below the step's
/// lower end, the cutter's top then at or beyond the stock's extent along the axis, can reach no
/// material: that copy of the cutter swept the whole column above it, and for a cutter that widens
/// upwards what moving up adds lies above its top (material never grows). Such a step removes
/// nothing, exactly: measuring it took what the stock model's shares of partly covered cells,
/// evaluated a second time for the same body, found left (a ball end mill's retract after a
/// ramp 0.042 mm^3 in dexels at D/20, retracts in voxels up to 0.0075 mm^3,
/// tests/stock/ReferenceCuts.cpp; a raster's plunge back to where an earlier one went, 0.011
/// mm^3 in dexels, the random campaign's seed 19). A tool buried deeper than its flutes is
/// measured.
class VisitedColumns {
 public:
  /// Tool `tool`'s tip at `tip` on the unit axis `axis` (the part's frame).
  void add(int tool, const Eigen::Vector3d& tip, const Eigen::Vector3d& axis) {
    StepPath at;
    at.axisEnd = axis;
    // (Evaluated as empty() evaluates a step's ends, to the last bit: the keys are exact.)
    const Eigen::Matrix3d toTool = at.toolToPart().transpose();
    const Eigen::Vector3d q = toTool * tip;
    const auto [it, fresh] =
        lowest_.try_emplace(Key{tool, axis, snap(axis, q.x()), snap(axis, q.y())}, q.z());
    if (!fresh) it->second = std::min(it->second, q.z());
  }
  bool empty(int tool, const StepPath& sp, const AptCutter& cutter, const Box3& stock) const {
    if (sp.turning() || cutter.parameters().taperAngleRad < 0.0) return false;
    const Eigen::Matrix3d toTool = sp.toolToPart().transpose();
    const Eigen::Vector3d a = toTool * sp.start, b = toTool * sp.end;
    if ((b.head<2>() - a.head<2>()).squaredNorm() > 1e-24) return false;
    const Eigen::Vector3d& low = a.z() <= b.z() ? a : b;
    // The stock's furthest extent along the axis: its box's corner furthest that way.
    double top = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < 8; ++k)
      top = std::max(top, sp.axisEnd.dot(Eigen::Vector3d((k & 1) ? stock.max.x() : stock.min.x(),
                                                         (k & 2) ? stock.max.y() : stock.min.y(),
                                                         (k & 4) ? stock.max.z() : stock.min.z())));
    // The step's own XY may differ from a move's end by rounding in its t: those are measured.
    const auto it =
        lowest_.find(Key{tool, sp.axisEnd, snap(sp.axisEnd, low.x()), snap(sp.axisEnd, low.y())});
    return it != lowest_.end() && it->second <= low.z() && it->second + cutter.height() >= top;
  }

 private:
  /// A tool-frame coordinate as a key: exact for an upright tool (a step along Z keeps its X
  /// and Y to the last bit); to 1e-9 mm for a tilted one, whose turn rounds them along a step.
  static double snap(const Eigen::Vector3d& axis, double v) {
    return axis == Eigen::Vector3d::UnitZ() ? v : std::round(v * 1e9) / 1e9;
  }
  struct Key {
    int tool;
    Eigen::Vector3d axis;
    double x, y;
    bool operator==(const Key& o) const {
      return tool == o.tool && axis == o.axis && x == o.x && y == o.y;
    }
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      const std::size_t a = std::hash<double>()(k.x), b = std::hash<double>()(k.y);
      return a ^ (b * 0x9E3779B97F4A7C15ull) ^ static_cast<std::size_t>(k.tool);
    }
  };
  std::unordered_map<Key, double, Hash> lowest_;
};

/// The contact of one cutting step at its end (engine/physics/Engagement.h), measured once for
/// the step's width, depth, angles and load: none for a rapid or a step in air; the edges'
/// where it moves horizontally, the end face's where it descends (with `physics`: only the
/// load reads it). The spindle's direction from the move, else `spindleRpm` (clockwise when
/// neither says).
struct StepContact {
  bool cutting = false;  ///< not a rapid, and removed more than air's rounding
  EdgeEngagement edge;
  FaceContact face;  ///< where the step descends
  /// The share of the step's direction at its end across the tool (horizontal for an upright
  /// tool), and the share along its axis towards the tip (0 where it keeps height or rises).
  double horizontal = 0.0;
  double descent = 0.0;
  double rpm = 0.0;  ///< the spindle speed the step runs at (0: stopped or unknown)
  /// The speed the chip is taken at, mm/min: where the axis turns, that of the point on it at
  /// the corner's centre height (StepContact's direction; each slice of the edge then takes
  /// its own share of it, EdgeSlice::feedShare); NaN: the step's feed.
  double feed = std::numeric_limits<double>::quiet_NaN();
};

StepContact measureContact(const Move& m, const StepPath& sp, double dtSeconds, const Removal& rem,
                           const AptCutter& cutter, const Stock& stock, double spindleRpm,
                           std::size_t afterStep, bool physics) {
  StepContact c;
  const double h = stock.resolution();
  c.cutting = m.kind != MoveKind::Rapid && rem.volume > kAirVoxels * h * h * h;
  if (!c.cutting) return c;
  // The direction of motion at the step's end in the tool's frame (a tilted tool's:
  // StepPath::toolToPart), and how much of it is across the tool. While the axis turns, the
  // motion of the point on the axis at the corner's centre height over the step's last piece
  // (of even time): a ball's centre, about which the axis's turn moves the ball along its own
  // sphere, cutting nothing.
  Eigen::Vector3d travel = sp.end - sp.at(std::max(0.0, 1.0 - 1e-3));
  // While the axis turns: the tip's motion and the axis's turn over that last piece.
  const bool turning = sp.turning() && sp.points.size() >= 2;
  Eigen::Vector3d tipMove = Eigen::Vector3d::Zero(), axisTurn = Eigen::Vector3d::Zero();
  if (turning) {
    const std::size_t n = sp.points.size();
    const double pieces = static_cast<double>(n - 1);
    tipMove = sp.points[n - 1] - sp.points[n - 2];
    axisTurn = sp.axisEnd - sp.axisAt((pieces - 1.0) / pieces);
    travel = tipMove + cutter.parameters().cornerCenterHeight * axisTurn;
    if (dtSeconds > 0.0) c.feed = travel.norm() / (dtSeconds / 60.0 / pieces);
  }
  const Eigen::Matrix3d toPart = sp.toolToPart();
  const Eigen::Vector3d d = toPart.transpose() * travel;
  c.horizontal = d.norm() > 0.0 ? d.head<2>().norm() / d.norm() : 0.0;
  c.descent = d.norm() > 0.0 ? std::max(0.0, -d.z() / d.norm()) : 0.0;
  c.rpm = m.spindleRpm != 0.0 ? m.spindleRpm : spindleRpm;
  if (physics && c.descent > 1e-3)  // (only the load needs it)
    c.face = measureFace(stock, cutter, sp.end, d.head<2>(), c.rpm >= 0.0, afterStep, toPart);
  if (c.horizontal < 1e-3) return c;
  c.edge = measureEngagement(stock, cutter, sp.end, d.head<2>(), c.rpm >= 0.0,
                             std::min(cutter.height(), rem.top + h), toolCurvature(m, sp),
                             afterStep, toPart);
  if (turning && d.head<2>().norm() > 0.0) {
    // Each slice's own motion over the last piece (the point on the axis at its height),
    // across the axis, against the travel the step's f_z is taken from.
    const double across = d.head<2>().norm();
    for (EdgeSlice& s : c.edge.slices) {
      const Eigen::Vector3d own = toPart.transpose() * (tipMove + s.z * axisTurn);
      s.feedShare =
          Eigen::Vector2d(own.head<2>().dot(c.edge.feed), own.head<2>().dot(c.edge.side)) / across;
    }
  }
  return c;
}

/// The load of one step (engine/physics) at its programmed feed, from its contact.
StepLoad stepLoad(const PhysicsOptions& o, const StepRecord& r, const StepContact& c,
                  const AptCutter& cutter, SimulationResult& out) {
  StepLoad load;
  load.exponent = o.material.exponent();
  load.entry = load.exit = kNaN;
  if (!c.cutting) return load;
  // A plunge of a cutter without a flat end (a ball's or a cone's point): not modelled.
  const bool face = c.face.radius > 0.0;
  if ((c.horizontal < 1e-3 && !face) || c.rpm == 0.0) {
    ++(c.rpm == 0.0 ? out.stoppedSteps : out.plungeSteps);
    return unmodelledLoad();
  }
  const int flutes = cutter.fluteCount();
  const double perTooth = (std::isnan(c.feed) ? r.feed : c.feed) / (std::abs(c.rpm) * flutes);
  const double fz = c.horizontal < 1e-3 ? 0.0 : perTooth * c.horizontal;
  StepLoad l = cuttingLoad(c.edge, o.material, {flutes, o.helix, cutter.maxRadius()}, fz, c.rpm,
                           {&c.face, perTooth * c.descent});
  // The end's cut is whole only where the face is flat out to the side: a corner radius
  // descending cuts with the axial feed too, unmodelled.
  const AptParameters& ap = cutter.parameters();
  l.endFace = l.endFace && ap.cornerRadius == 0.0 && ap.bottomAngleRad == 0.0;
  return l;
}

/// Each tool's non-cutting parts (shank, holder), each with its shape a cell slimmer.
using SlimParts = std::map<int, std::vector<std::pair<ToolPart, AptCutter>>>;

SlimParts slimPartsOf(const Toolpath& path, const CutterSet& cutters, double h) {
  SlimParts slimParts;
  for (const Move& m : path.moves) {
    if (slimParts.count(m.tool)) continue;
    auto& list = slimParts[m.tool];
    for (const ToolPart& part : cutters.partsOf(m.tool)) {
      AptParameters slim = part.shape.parameters();
      slim.radius = std::max(0.5 * slim.radius, slim.radius - h);
      slim.cornerCenterRadial = std::max(0.0, slim.radius - slim.cornerRadius);
      list.emplace_back(part, AptCutter::fromApt(slim, 2, CutterShape::General));
    }
  }
  return slimParts;
}

/// The sweeps of tool `tool`'s shank and holder over step `sp` (those below the stock's top),
/// asked after the step's removal: what they meet is a crash. Whether they meet material is
/// asked of the part a cell slimmer: a shank as wide as its cutter grazes the wall the cutter
/// just cut, whose cells hold fractions up to a cell's half diagonal inside the cutter's
/// radius; how much they meet, of the part itself.
void addPartSweeps(const SlimParts& slimParts, int tool, const StepPath& sp, double h,
                   double stockTop, std::deque<Sweep>& sweeps, StepCut& c,
                   std::vector<const ToolPart*>& asked) {
  const auto parts = slimParts.find(tool);
  if (parts == slimParts.end()) return;
  for (const auto& [part, slim] : parts->second) {
    if (!sp.tilted() && std::min(sp.start.z(), sp.end.z()) + part.zOffset >= stockTop) continue;
    StepPath raised = sp;
    // Up the tool's axis (turning with it on a 5-axis step).
    raised.start += part.zOffset * sp.axisStart;
    raised.end += part.zOffset * sp.axisEnd;
    raised.center += part.zOffset * sp.axisStart;
    for (std::size_t i = 0; i < raised.points.size(); ++i)
      raised.points[i] += part.zOffset * sp.axisAt(static_cast<double>(i) /
                                                   static_cast<double>(raised.points.size() - 1));
    const Sweep& slimSweep = sweeps.emplace_back(slim, raised, h);
    const Sweep& fullSweep = sweeps.emplace_back(part.shape, raised, h);
    c.parts.push_back({&slimSweep, &fullSweep, stockTop, kRapidNoiseVoxels * h * h * h});
    asked.push_back(&part);
  }
}

/// The collisions of step `si` (of move `move`) after its removal `rem`: a rapid that removes
/// more than half a voxel hits material (a crash on a machine; below that it is the fraction
/// scheme's rounding along walls it retraces), and the tool's parts `asked` (in the order of
/// rem.partsMet) that met more.
void stepCollisions(SimulationResult& out, const Move& m, std::size_t move, std::size_t si,
                    const Removal& rem, const std::vector<const ToolPart*>& asked, double h) {
  const double noise = kRapidNoiseVoxels * h * h * h;
  if (m.kind == MoveKind::Rapid && rem.volume > noise) {
    out.rapidRemoved += rem.volume;
    addCollision(out.collisions, {move, m.line, m.tool, "rapid", si, si, rem.volume});
  }
  for (std::size_t q = 0; q < asked.size(); ++q)
    if (rem.partsMet.at(q).first > noise)
      addCollision(out.collisions,
                   {move, m.line, m.tool, asked[q]->name, si, si, rem.partsMet[q].second});
}

/// Measured against the analytic model on the steady-state steps (cutting, and within
/// kSteadyChange of both neighbours on the move), per path class and form.
void agreeWithModel(SimulationResult& out) {
  for (std::size_t i = 1; i + 1 < out.steps.size(); ++i) {
    const StepRecord& a = out.steps[i - 1];
    const StepRecord& r = out.steps[i];
    const StepRecord& b = out.steps[i + 1];
    if (r.kind == MoveKind::Rapid || r.mrr <= 0.0 || a.move != r.move || b.move != r.move) continue;
    if (!steadyBetween(a.mrr, r.mrr, b.mrr)) continue;
    Agreement& exact = r.side == PathSide::Concave  ? out.concave
                       : r.side == PathSide::Convex ? out.convex
                                                    : out.straight;
    Agreement& paper = r.side == PathSide::Concave  ? out.concavePaper
                       : r.side == PathSide::Convex ? out.convexPaper
                                                    : out.straightPaper;
    accumulate(exact, r.mrr, r.mrrExact);
    accumulate(paper, r.mrr, r.mrrPaper);
  }
  for (Agreement* a : {&out.straight, &out.concave, &out.convex, &out.straightPaper,
                       &out.concavePaper, &out.convexPaper})
    finish(*a);
}

/// Where measurement and the exact model differ most, over all cutting steps: the ten largest,
/// kept as they come (never all of them at once).
void largestDifferences(SimulationResult& out) {
  auto larger = [](const Difference& x, const Difference& y) {
    return std::abs(x.relative) != std::abs(y.relative)
               ? std::abs(x.relative) > std::abs(y.relative)
               : x.step < y.step;
  };
  constexpr std::size_t kLargest = 10;
  for (std::size_t i = 0; i < out.steps.size(); ++i) {
    const StepRecord& r = out.steps[i];
    if (r.kind == MoveKind::Rapid || r.mrr <= 0.0 ||
        !(std::isfinite(r.mrrExact) && r.mrrExact > 0.0))
      continue;
    const Difference d{i, r.line, r.mrr, r.mrrExact, r.mrr / r.mrrExact - 1.0};
    if (out.largest.size() < kLargest) {
      out.largest.push_back(d);
      std::sort(out.largest.begin(), out.largest.end(), larger);
    } else if (larger(d, out.largest.back())) {
      out.largest.back() = d;
      std::sort(out.largest.begin(), out.largest.end(), larger);
    }
  }
}

}  // namespace

SimulationResult simulate(const Toolpath& path, const CutterSet& cutters, Stock& stock,
                          const SimulationOptions& options) {
  refuseOtherAxes(path);
  refuseTilt(path, stock);
  for (const Move& m : path.moves)
    (void)cutters.of(m.tool);  // every move has its cutter before anything is cut
  const double h = stock.resolution();
  const double L = options.stepLength > 0.0 ? options.stepLength : 2.5 * h;
  SimulationResult out;
  out.volumeBefore = stock.volume();
  const Box3 stockBox = stock.bounds();
  const double stockTop = stockBox.max.z();
  const SlimParts slimParts = slimPartsOf(path, cutters, h);

  // Plan the steps first (for progress and for the records).
  const std::vector<Planned> plan = planSteps(path, cutters, L, options.maxSteps);

  // Steps go to the stock in batches where it can tell each step's contact as it was after
  // that step (Stock::readsWithinBatch) and nothing else reads it between them but their
  // tool's shank and holder (asked by the stock after each step's removal; no per-step
  // timing): the dexel stock removes a batch tile by tile, the tiles side by side
  // (stock/DexelStock.h), to the same numbers; the steps' contacts are then measured side by
  // side.
  const bool batches = stock.readsWithinBatch() && !options.timeSteps;
  // A batch ends at 128 steps or at steps whose boxes hold 8192 columns of the stock's
  // resolution: small steps (a few dozen columns each) need many to give the cores tiles
  // enough, large ones fewer; more would hold the batch's sweeps and records in memory for
  // nothing.
  constexpr std::size_t kBatchSteps = 128;
  constexpr double kBatchColumns = 8192.0;

  const auto start = std::chrono::steady_clock::now();
  double arc = 0.0;
  out.steps.reserve(plan.size());
  struct Pending {
    StepPath sp;
    StepRecord r;
    int cut = -1;  // its entry in `cuts` (none: removes nothing, asks nothing)
    std::vector<const ToolPart*> parts;  // the parts its entry asks about, in order
  };
  std::vector<Pending> batch;
  VisitedColumns visited;
  std::size_t visitedUpTo = 0;  // the moves before this one have their ends in `visited`
  std::deque<Sweep> sweeps;     // (a deque: the cuts point into it)
  std::vector<StepCut> cuts;
  for (std::size_t first = 0; first < plan.size();) {
    if (stopRequested()) throw Interrupted();
    const std::size_t most = std::min(plan.size(), first + (batches ? kBatchSteps : 1));
    batch.clear();
    sweeps.clear();
    cuts.clear();
    double columns = 0.0;
    std::size_t last = first;
    for (std::size_t si = first; si < most && columns < kBatchColumns; ++si, ++last) {
      const Planned& p = plan[si];
      const Move& m = path.moves[p.move];
      Pending& b = batch.emplace_back();
      b.sp = stepPath(m, p.t0, p.t1, path);
      b.r = plannedRecord(p, m, b.sp, arc);
      const AptCutter& cutter = cutters.of(m.tool);
      StepCut c{nullptr, static_cast<int>(si), b.r.dt, {}};
      // The tip has been at the end of every move before this one (not where the program
      // starts: a tool put down in the stock is measured).
      for (; visitedUpTo < p.move; ++visitedUpTo) {
        const Move& done = path.moves[visitedUpTo];
        if (path.kinematics.rotary() || done.frame != 0)
          visited.add(
              done.tool,
              movePose(done, path.kinematics, path.frameOf(done), done.end, done.rotaryEnd).tip,
              path.kinematics.axis(done.rotaryEnd));
        else
          visited.add(done.tool, done.end, Eigen::Vector3d::UnitZ());
      }
      if (!visited.empty(m.tool, b.sp, cutter, stockBox)) {
        c.sweep = &sweeps.emplace_back(cutter, b.sp, h, stockTop);
        const Box3 box = c.sweep->bounds();
        columns +=
            ((box.max.x() - box.min.x()) / h + 1.0) * ((box.max.y() - box.min.y()) / h + 1.0);
      }
      // The shank and the holder, after the cutter took its share.
      addPartSweeps(slimParts, m.tool, b.sp, h, stockTop, sweeps, c, b.parts);
      if (c.sweep || !c.parts.empty()) {
        b.cut = static_cast<int>(cuts.size());
        cuts.push_back(std::move(c));
      }
    }
    const auto stepStart = std::chrono::steady_clock::now();
    const std::vector<Removal> removals = stock.removeSteps(cuts);
    if (options.timeSteps)  // (one step a batch)
      out.stepSeconds.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - stepStart).count());
    // Each step's contact, as the stock was after it (independent of one another).
    std::vector<StepContact> contacts(batch.size());
    const double spindleRpm = options.physics ? options.physics->spindleRpm : 0.0;
    auto measure = [&](std::size_t k) {
      if (batch[k].cut < 0) return;
      const Move& m = path.moves[plan[first + k].move];
      contacts[k] = measureContact(
          m, batch[k].sp, batch[k].r.dt, removals[static_cast<std::size_t>(batch[k].cut)],
          cutters.of(m.tool), stock, spindleRpm,
          batches ? static_cast<std::size_t>(batch[k].cut) : Stock::kLatest,
          options.physics.has_value());
    };
    if (batch.size() > 1)
      tbb::parallel_for(std::size_t(0), batch.size(), measure);
    else if (!batch.empty())
      measure(0);
    for (std::size_t k = 0; k < batch.size(); ++k) {
      const std::size_t si = first + k;
      const Planned& p = plan[si];
      const Move& m = path.moves[p.move];
      const StepPath& sp = batch[k].sp;
      StepRecord& r = batch[k].r;
      const AptCutter& cutter = cutters.of(m.tool);
      const Removal rem =
          batch[k].cut >= 0 ? removals[static_cast<std::size_t>(batch[k].cut)] : Removal{};
      r.removed = rem.volume;
      r.voxelsChanged = static_cast<std::int32_t>(rem.voxelsChanged);
      r.mrr = r.dt > 0.0 ? r.removed / (r.dt / 60.0) : 0.0;
      r.curvature = toolCurvature(m, sp);
      // The cut's width, depth and angle from its contact; a plunge's from what it removed:
      // the cutter's diameter at that depth.
      const StepContact& contact = contacts[k];
      if (contact.edge.any()) {
        r.width = radialDepth(contact.edge);
        r.depth = axialDepth(contact.edge);
        r.engagementRad = contact.edge.exit - contact.edge.entry;
      } else if (contact.cutting) {
        r.depth = rem.axialDepth;
        r.width = contact.horizontal < 1e-3 ? 2.0 * cutter.radiusAt(r.depth) : 0.0;
      }
      out.removed += r.removed;
      out.voxelsChanged += r.voxelsChanged;
      stepCollisions(out, m, p.move, si, rem, batch[k].parts, h);
      out.cuttingTime += r.dt;

      // Side of the curve the stock is on: concave when it lies on the outer side.
      if (r.curvature != 0.0 && r.removed > kAirVoxels * h * h * h)
        r.side = r.curvature * rem.lateral < 0.0 ? PathSide::Concave : PathSide::Convex;

      if (options.physics) {
        StepLoad load = stepLoad(*options.physics, r, contact, cutter, out);
        if (sp.tilted()) load.force = sp.toolToPart() * load.force;  // (the part's frame)
        out.loads.push_back(load);
      }

      // The analytic model of this step: its stepover and depth (given or measured).
      r.mrrExact = r.mrrPaper = 0.0;
      if (contact.cutting && obliqueToPart(sp)) {
        r.mrrExact = r.mrrPaper = kNaN;
        ++out.obliqueSteps;
      } else if (contact.cutting) {
        analytic(r, cutter, sp.toolToPart().transpose() * (sp.end - sp.start),
                 options.stepover.value_or(std::min(r.width, 2.0 * cutter.maxRadius())),
                 std::min(options.depth.value_or(r.depth), cutter.height()));
      }
      out.steps.push_back(r);
      if (options.progress && (si % 256 == 0 || si + 1 == plan.size()))
        options.progress(si + 1, plan.size());
    }
    first = last;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.volumeAfter = stock.volume();

  agreeWithModel(out);
  largestDifferences(out);
  return out;
}

SimulationResult analyticSteps(const Toolpath& path, const AptCutter& cutter,
                               const SimulationOptions& options, bool stockOnRight) {
  CutterSet one;
  one.fallback = cutter;
  return analyticSteps(path, one, options, stockOnRight);
}

SimulationResult analyticSteps(const Toolpath& path, const CutterSet& cutters,
                               const SimulationOptions& options, bool stockOnRight) {
  refuseOtherAxes(path);
  if (tiltsTool(path))
    throw ParameterError(
        "the analytic model is of a vertical tool, and this program tilts it "
        "(" +
        std::string(kinematicsTypeName(path.kinematics.type)) +
        " kinematics): simulate it in a stock");
  if (!options.stepover || !options.depth)
    throw ParameterError("the analytic model without a stock needs --stepover and --depth");
  for (const Move& m : path.moves)
    (void)cutters.of(m.tool);
  const double L =
      options.stepLength > 0.0 ? options.stepLength : 2.0 * cutters.smallestRadius() / 10.0;
  SimulationResult out;
  out.volumeBefore = out.volumeAfter = kNaN;
  double arc = 0.0;
  for (const Planned& p : planSteps(path, cutters, L, options.maxSteps)) {
    if (stopRequested()) throw Interrupted();
    const Move& m = path.moves[p.move];
    const StepPath sp = stepPath(m, p.t0, p.t1, path);
    StepRecord r = plannedRecord(p, m, sp, arc);
    const AptCutter& cutter = cutters.of(m.tool);
    const double d = std::min(*options.depth, cutter.height());
    r.removed = r.mrr = r.width = r.depth = r.engagementRad = kNaN;
    r.curvature = curvatureOf(m);
    out.cuttingTime += r.dt;
    // The stock on the right: turning left puts it on the outer side (concave).
    if (r.curvature != 0.0)
      r.side = (r.curvature > 0.0) == stockOnRight ? PathSide::Concave : PathSide::Convex;
    r.mrrExact = r.mrrPaper = 0.0;
    if (m.kind != MoveKind::Rapid) analytic(r, cutter, sp.end - sp.start, *options.stepover, d);
    out.steps.push_back(r);
  }
  return out;
}

}  // namespace engage
