#pragma once
/// \file MovesTable.h
/// The interpreted moves of a program as CSV (`engage moves`): per move (per point of a
/// spline) its source line, kind, end point, arc centre, plane and turns, and feed; mm and
/// mm/min, machine coordinates.

#include "engine/gcode/Toolpath.h"

#include <string>

namespace engage {

/// The table's text, header first.
std::string movesTable(const Toolpath& path);

}  // namespace engage
