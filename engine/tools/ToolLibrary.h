#pragma once
/// \file ToolLibrary.h
/// Tool libraries as users keep them, read into one form: per tool number, the generalized APT
/// cutter (the part that cuts) and the non-cutting parts above it (shank, holder). Formats:
///
/// - LinuxCNC tool table (`T1 P1 D6 Z35 ;6mm flat 3 flutes`): D and the length; the shape and
///   the rest from the comment's words (see readLinuxcncTable in ToolLibrary.cpp and
///   docs/inputs.md).
/// - Fusion 360 tool library JSON (`{"data": [...]}`, as Fusion exports it): type, unit and the
///   geometry fields DC, RE, TA, SIG, tip-diameter, LCF, LB, OAL, SFDM, NOF; the holder's
///   segments; the number from post-process.number.
/// - FreeCAD tool bits (`.fctb`: shape + parameter) and tool libraries (`.fctl`: numbers and
///   the bits' paths, looked up beside the library and in ../Bit).
/// - CAMotics' tool table (the "tools" object of a .camotics project).
///
/// A tool whose geometry cannot be built (unknown type, a corner radius larger than the
/// radius, a taper that does not close, a missing unit) is kept with the reason, so that a
/// shop library with a probe or a thread mill in it still serves a program that does not load
/// those; using such a tool is an error that names the tool, the field and the file.
/// Units inside: mm and radians.

#include "cutters/AptCutter.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace engage {

/// One piece of a holder: a cone frustum `height` tall, from `lowerDiameter` at its bottom to
/// `upperDiameter` at its top, mm. Segments stack upward from the holder's face.
struct HolderSegment {
  double height = 0.0;
  double lowerDiameter = 0.0;
  double upperDiameter = 0.0;
};

/// One tool of a library.
struct ToolEntry {
  int number = 0;      ///< T number (Fusion: post-process.number; FreeCAD: nr)
  std::string name;    ///< description as the library gives it
  std::string origin;  ///< where it is defined: "file:line" or "file: tool 3"
  std::string kind;    ///< the library's own word for the type ("flat end mill", "ballend", ...)
  std::optional<AptCutter> cutter;    ///< the cutting part; empty when `problem` says why
  std::string problem;                ///< why there is no cutter ("" when there is one)
  double shankDiameter = 0.0;         ///< mm, 0 when the library does not say
  double stickout = 0.0;              ///< tip to the holder's face (Fusion LB), mm, 0 when not said
  double overallLength = 0.0;         ///< mm, 0 when not said
  std::vector<HolderSegment> holder;  ///< from the holder's face upward; empty: no holder
  std::string holderName;
};

/// A library read from one file.
struct ToolLibrary {
  std::string path;
  std::string format;  ///< "linuxcnc", "fusion360", "freecad", "camotics"
  std::vector<ToolEntry> tools;

  /// The entries numbered `number` (a vendor library may number several tools 1).
  std::vector<const ToolEntry*> numbered(int number) const;
  /// The cutter of tool `number`. Throws ParameterError naming the tool, the field and the
  /// file when there is no such tool, when several tools share the number, or when its
  /// geometry cannot be built.
  const ToolEntry& require(int number) const;
};

/// How to read a library.
struct ToolLibraryOptions {
  /// A LinuxCNC table's lengths and diameters are in inches (its machine's units).
  bool linuxcncInch = false;
};

/// The text of a tool library, tool bit or project file (64 MiB at most). Throws
/// ParameterError naming the file and `what` it was to be ("tool library", "CAMotics project")
/// for a folder, a file that cannot be read or one too large.
std::string readToolFile(const std::string& path, const std::string& what);

/// Read a library, its format told by its content: JSON with "data" (Fusion 360), with
/// "tools" (a .camotics project or a FreeCAD .fctl), with "shape" (one FreeCAD .fctb), else a
/// LinuxCNC table. Throws ParameterError for a file that cannot be read or parsed at all,
/// naming the file (and the line or the JSON error).
ToolLibrary readToolLibrary(const std::string& path, const ToolLibraryOptions& options = {});

/// The same from text; `path` names it in messages and locates a .fctl's bits.
ToolLibrary parseToolLibrary(const std::string& text, const std::string& path,
                             const ToolLibraryOptions& options = {});

}  // namespace engage
