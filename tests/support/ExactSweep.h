#pragma once
/// \file ExactSweep.h
/// An exact reference for per-move removed volumes, independent of both stock models (issue 18):
/// a box of stock minus, move by move, the swept solid of a convex cutter along a straight move,
/// which is the convex hull of the cutter's copies at the move's two ends. The booleans are
/// CGAL's corefinement on an exact-constructions kernel (no rounding in the booleans); the only
/// approximation is the cutter itself, a polyhedron inscribed in it (facetDeviation). CGAL is
/// included only in ExactSweep.cpp, so that this header stays light.

#include "cutters/AptCutter.h"
#include "engine/gcode/Toolpath.h"

#include <vector>

namespace engage::test {

/// How finely the cutter is faceted: each horizontal section of the profile is a regular
/// polygon of `ringVertices` vertices on the circle; each arc of the profile is cut into
/// chords of at most `arcDegrees`. Every vertex lies on the true cutter, so the faceted cutter
/// is inside it, nowhere deeper than facetDeviation().
struct Faceting {
  int ringVertices = 256;
  double arcDegrees = 2.0;
};

/// The most the faceted cutter's surface lies inside the true cutter's, mm: the larger of
/// R (1 - cos(pi / ringVertices)) over its largest radius R and r_arc (1 - cos(arc step / 2))
/// over its arcs (a chord's sag).
double facetDeviation(const AptCutter& cutter, const Faceting& faceting = {});

/// Per move of `path`, the volume (mm^3) that move i's cutter `cutterOfMove[i]` removes from
/// what remains of the box `stock` after the moves before it (every move's hull has both its end
/// copies, the first move's start included). Every move must be a straight line (Rapid or
/// Line), and one cutter given per move: std::invalid_argument otherwise. Cutters are taken
/// convex (the hull of their profile's points). With ENGAGE_EXACT_TRACE set in the environment,
/// each move's volume is printed to stderr as it is computed (the ball's take minutes).
std::vector<double> exactRemovals(const Toolpath& path, const std::vector<AptCutter>& cutterOfMove,
                                  const Box3& stock, const Faceting& faceting = {});

}  // namespace engage::test
