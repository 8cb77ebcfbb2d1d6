#pragma once
/// \file RandomPrograms.h
/// Random 3-axis programs for the campaign of both stock models against the exact reference
/// (issue 44): from a seed, a cutter of any shape, a stock box at a random place on the grid and
/// a program of straight moves (the reference takes no arcs) built from pieces: ramps at random
/// slopes and directions, rasters over a random surface (along X, Y or cross-hatched), polyline
/// helices, re-cuts 0.01-0.1 mm beside or below a cut, moves of 0.02-0.1 mm and grazes beside
/// walls, retracts and traverses that cannot reach material. The program is turned by a random
/// angle (a quarter of them kept on the grid's axes) and shifted by a random part of a cell (or
/// by whole and half cells). The same seed gives the same case on every machine (the draws are
/// the generator's own, not std::uniform_real_distribution's).

#include "cutters/AptCutter.h"
#include "engine/gcode/Toolpath.h"
#include "stock/TriangleMesh.h"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace engage::test {

struct RandomCase {
  std::uint64_t seed = 0;
  std::string name;  ///< e.g. "seed 17: bull D6.5 r1.2, ramps + helix"
  AptCutter cutter = AptCutter::flat(6.0, 25.0);
  Box3 stock;
  double cell = 0.0;    ///< the default cell of the case (engine/run/Resolution.h), mm
  std::string program;  ///< G-code (G21, straight moves only)
  Toolpath path;        ///< the program, read, the tool starting 5 mm above the stock's middle
};

/// The case of `seed`. At most `maxMoves` feed and rapid moves (the exact reference's time
/// grows with them; a ball's hull is 20 times a flat's).
RandomCase randomCase(std::uint64_t seed, int maxMoves = 30);

/// A case carried onto a tilted tool (issue 48): a table-ac machine holding the tip (tcp,
/// xyzac-trt-kins) at A and C, held through the program, and the program and the stock turned
/// by the rotation that takes +Z to the tool's axis there. A rotation keeps volumes: the case's
/// exact removals are the upright case's.
enum class Tilt {
  Oblique,  ///< A 10-60 deg, C any, drawn from the seed: the box's faces oblique to the grid
  Quarter,  ///< A 90 deg, C a multiple of 90 from the seed: the tool lies along X or Y and the
            ///< turned box is a box again
  Upright   ///< A and C 0, nothing turned (the same box as a mesh: a control)
};
struct TiltedCase {
  Toolpath path;       ///< the moves' tips turned, each at (A, 0, C)
  TriangleMesh stock;  ///< the box turned (12 triangles)
  Box3 box;            ///< its bounds: the stock itself for Tilt::Quarter and Tilt::Upright
  Eigen::Vector3d abc{0.0, 0.0, 0.0};  ///< degrees
};
TiltedCase tiltedCase(const RandomCase& c, Tilt tilt = Tilt::Oblique);

/// How a stock model's per-move removal compares with the exact one, on issue 44's bounds:
/// the total within 0.1 %; every move of 1 mm^3 or more within 1 %; smaller moves within two
/// cell volumes; a move that removes nothing exactly 0.
struct MoveComparison {
  double exactTotal = 0.0, measuredTotal = 0.0;  ///< mm^3
  double worstBigPct = 0.0;      ///< worst relative error over moves of 1 mm^3 or more, %
  std::size_t worstBigMove = 0;  ///< its index
  double worstSmallCells = 0.0;  ///< worst error of the smaller moves, in cell volumes
  std::size_t worstSmallMove = 0;
  double worstZeroMm3 = 0.0;  ///< the most removed by a move that removes nothing
  std::size_t worstZeroMove = 0;
  std::size_t bigMoves = 0, bigWithinHalfPct = 0;
  /// Moves outside the bounds, one line each: "move 12 (line 15): exact 3.1 mm3, measured ...".
  std::vector<std::string> failures;
  double totalPct() const;
  bool passes() const { return failures.empty() && std::abs(totalPct()) <= 0.1; }
};

MoveComparison compareMoves(const Toolpath& path, const std::vector<double>& exact,
                            const std::vector<double>& measured, double cell);

}  // namespace engage::test
