#pragma once
/// \file Machine.h
/// A machine description file (`--machine FILE`, JSON), so that a program runs as on the
/// machine it was written for: `G53 G0 Z0` retracts to the top of the machine's travel, not
/// onto the stock; G28/G30 go to the machine's stored positions; the program starts with
/// the tool where the machine leaves it, not at the program's origin (inside the stock's top).
///
///   {
///     "units": "mm",                    // of every number here: mm (default) or in
///     "work_offset": [0, 0, -120],      // G54's origin in machine coordinates
///     "g28": [0, 0, 0],                 // G28's and G30's positions (default: 0, 0, 0)
///     "g30": [-300, 0, 0],
///     "start": [0, 0, 0],               // the tool tip when the program starts, or "g28",
///                                       // "g30" (default: 0, 0, 0, the machine's home)
///     "travel": {"min": [-400, -300, -150], "max": [0, 0, 0],  // optional, as is each
///                "A": [-120, 30]},                 // rotary axis's, degrees
///     "kinematics": {"type": "table-ac",   // optional: the rotary axes' chain
///                    "rot_point": [0, 0, -50], "offset": [0, 0, 12], "tcp": false}
///   }
///
/// "kinematics" (engine/kinematics/Kinematics.h): "type" one of table-a, table-b (a 4th axis),
/// table-ac, table-bc (trunnions), head-bc, head-b-table-c; "rot_point" (table types) where the
/// table's axes cross, in the program's work coordinates; "offset" (trunnions) the tilt axis's
/// offset from C's; "pivot_length" (head types, required) from the head's pivot to the tool
/// tip; "tcp" whether the controller holds the tip (X, Y, Z are the tip on the part). Without
/// it, rotary motion is refused; with it, rotary words of axes the chain lacks are.
///
/// "travel": the joints' limits. X, Y, Z's are checked at every move's end and, where the
/// controller holds the tip while the rotary axes turn (its joints then move unevenly), at
/// every degree of the turn; a rotary axis's (degrees, whatever "units" says; it must hold 0,
/// where the axes start) at every move's ends.
///
/// Positions are machine coordinates. Every problem (unknown key, wrong shape, a start
/// outside the travel) is an Error naming the file and the key.

#include "engine/gcode/GcodeReader.h"

#include <string>

namespace engage {

MachineSetup readMachine(const std::string& path);

/// "linuxcnc" (or empty), "fanuc", "grbl"; throws ParameterError for anything else.
Dialect dialectOf(const std::string& name);

}  // namespace engage
