#pragma once
/// \file MovesTable.h
/// The interpreted moves of a program as CSV (`engage moves`): per move (per point of a
/// spline) its source line, kind, end point, arc centre, plane and turns, and feed; mm and
/// mm/min, machine coordinates. On a machine with rotary kinematics, also the rotary axes'
/// positions at the move's end (degrees) and an inverse-time (G93) move's duration (minutes;
/// its feed column is the XYZ speed that takes).

#include "engine/gcode/Toolpath.h"

#include <string>

namespace engage {

/// The table's text, header first.
std::string movesTable(const Toolpath& path);

}  // namespace engage
