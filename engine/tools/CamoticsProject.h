#pragma once
/// \file CamoticsProject.h
/// A CAMotics project (`.camotics`, JSON) as CAMotics 1.2 reads it: its tool table, its
/// workpiece (a box in mm, or "automatic": bounds guessed from the cutting moves with a margin)
/// and its program files, run one after the other. engage runs such a project as it is, so
/// that CAMotics users need not translate anything by hand.

#include "cutters/AptCutter.h"
#include "engine/gcode/Toolpath.h"
#include "engine/tools/ToolLibrary.h"

#include <functional>
#include <string>
#include <vector>

namespace engage {

struct CamoticsProject {
  std::string path;
  std::vector<std::string> files;  ///< the programs, resolved against the project's folder
  ToolLibrary tools;               ///< the "tools" table (format "camotics")
  bool automatic = false;          ///< workpiece bounds guessed from the path
  double marginPercent = 0.0;      ///< of the automatic bounds' size
  Box3 bounds;                     ///< the workpiece box, mm (when not automatic)
};

/// True for a path CAMotics would open as a project (`.camotics`, any case).
bool isCamoticsProject(const std::string& path);

/// Read a project. Throws ParameterError naming the file and the field: not JSON, no
/// "files", a TPL program (CAMotics' JavaScript tool-path language, which engage does not
/// run), a missing program, a workpiece without bounds.
CamoticsProject readCamoticsProject(const std::string& path);

/// CAMotics' automatic workpiece (project/Workpiece.cpp, Workpiece::update): the union of the
/// boxes each cutting move's tool sweeps (max radius around the path; from the tip, a
/// ball-nose from one radius below it, up to the tool's length), its top lowered to Z0 when it
/// reaches below Z0, at least 2 mm thick, grown by `marginPercent` of its size on every side
/// but the top. mm. `cutterOf` gives each move's cutter.
Box3 camoticsAutomaticWorkpiece(const Toolpath& path,
                                const std::function<const AptCutter&(int tool)>& cutterOf,
                                double marginPercent);

}  // namespace engage
