#pragma once
/// \file CutterComp.h
/// Cutter radius compensation (G41/G41.1/G42/G42.1, G40) in the XY plane (or XZ) as LinuxCNC 2.9's
/// interpreter does it, so that programs written for it run here move for move:
/// - the entry move (the first straight move after G41/G42) goes to the point a radius to the
///   side of its programmed end, perpendicular to the move;
/// - each later move is offset by the radius to its side; an outside (convex) corner gets an
///   arc about the programmed corner; an inside (concave) corner moves the end of the move
///   before it back to where the two offset paths meet (line-line, line-arc, arc-line,
///   arc-arc), which is why a move is held back until the next one is known;
/// - G40 ends the last move at its offset point; the next move starts there and goes to its
///   programmed end (it must be straight);
/// - the errors LinuxCNC gives: an entry move not longer than the radius, a tool too big for
///   an inside arc or for an inside corner's moves ("gouging"), a zero-degree inside corner.
/// An arc as the entry move keeps its end's direction from the programmed centre and passes
/// through the tool's position (its centre moves).
/// Positions are machine coordinates, mm (the offsets are translations: they do not change
/// the geometry).

#include "engine/gcode/Toolpath.h"

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace engage {

/// A program that compensation cannot run, with LinuxCNC's reason.
class CompensationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CutterCompensation {
 public:
  enum Side { Off = 0, Left = 1, Right = -1 };
  /// Receives the compensated moves, in order, their start set to where the last one ended.
  using Sink = std::function<void(Move)>;

  explicit CutterCompensation(Sink sink) : sink_(std::move(sink)) {}

  /// G41/G42 with the tool's radius (mm; a negative radius switches the side, as LinuxCNC
  /// does) at the tool's position. Throws when compensation is on already.
  /// `unit`: mm per program unit (LinuxCNC's checks are in program units). `plane`: XY, or
  /// XZ as LinuxCNC allows (its coordinates Z, X).
  void on(Side side, double radius, const Eigen::Vector3d& position, double unit,
          Plane plane = Plane::XY);
  /// Compensation is on (G41/G42 given, G40 not yet).
  bool on() const { return side_ != Off; }
  /// The side the tool is on (Off after G40).
  Side side() const { return side_; }
  /// Whether it is on to `side` with `radius` (mm).
  bool onAs(Side side, double radius) const { return side_ == side && radius_ == radius; }
  /// Moves are offset (on, with a radius above 0: with radius 0 they run as programmed).
  bool offsetting() const { return side_ != Off && radius_ > 0.0; }

  /// A straight move (rapid or line), as programmed: m.start the programmed start, m.end the
  /// programmed end; the rest of m (line, feed, ...) is carried to what it becomes.
  void straight(Move m);
  /// An arc in the plane, as programmed (m.center its programmed centre).
  void arc(Move m);
  /// G40: the last move ends at its offset point and everything is emitted. Returns where the
  /// tool is (the next move starts there).
  Eigen::Vector3d off();
  /// Emit what is held back, as it is (the program ends).
  void flush();

 private:
  struct Held {
    Move move;
    Eigen::Vector2d direction{0.0, 0.0};  ///< lines: programmed direction (the gouge check)
    double originalTurn = 0.0;            ///< arcs: swept angle as first computed (radians)
  };
  void entryArc(Move m);
  Eigen::Vector2d xy(const Eigen::Vector3d& p) const;
  void setXy(Eigen::Vector3d& p, const Eigen::Vector2d& v) const;
  Eigen::Vector3d point(const Eigen::Vector2d& v, double height) const;
  void enqueue(Move m, const Eigen::Vector2d& direction, double originalTurn);
  void dequeue();
  void setEndpoint(const Eigen::Vector2d& p);
  void moveEndpointAndFlush(const Eigen::Vector2d& p);
  Move cornerArc(const Move& like, const Eigen::Vector2d& end, const Eigen::Vector2d& centre,
                 double z) const;

  Sink sink_;
  double unit_ = 1.0;
  Plane plane_ = Plane::XY;
  PlaneAxes axes_ = planeAxes(Plane::XY);
  Side side_ = Off;
  double radius_ = 0.0;
  bool first_ = true;
  Eigen::Vector3d current_{0.0, 0.0, 0.0};  ///< where the (offset) tool is
  Eigen::Vector3d emitted_{0.0, 0.0, 0.0};  ///< where the last emitted move ended
  std::vector<Held> queue_;
  Eigen::Vector2d endpoint_{0.0, 0.0};  ///< start of the held move(s)
  bool endpointValid_ = false;
};

}  // namespace engage
