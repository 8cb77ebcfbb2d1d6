#include "engine/run/OptionTable.h"

namespace engage {
namespace {

OptionInfo quantity(const char* name, OptionGroup group, Dimension d, const char* help) {
  OptionInfo o;
  o.name = name;
  o.kind = OptionKind::Quantity;
  o.group = group;
  o.dimension = d;
  o.help = help;
  return o;
}

OptionInfo choice(const char* name, OptionGroup group, std::vector<std::string> choices,
                  const char* defaultText, const char* help) {
  OptionInfo o;
  o.name = name;
  o.kind = OptionKind::Choice;
  o.group = group;
  o.choices = std::move(choices);
  o.defaultText = defaultText;
  o.help = help;
  return o;
}

OptionInfo plain(const char* name, OptionKind kind, OptionGroup group, const char* defaultText,
                 const char* help) {
  OptionInfo o;
  o.name = name;
  o.kind = kind;
  o.group = group;
  o.defaultText = defaultText;
  o.help = help;
  return o;
}

OptionInfo scheduleOnly(OptionInfo o) {
  o.scheduleOnly = true;
  return o;
}

OptionInfo commandLineOnly(OptionInfo o) {
  o.commandLineOnly = true;
  return o;
}

/// The table: one entry per option, in help order (one function, as it is one list).
std::vector<OptionInfo> makeTable() {
  using D = Dimension;
  using G = OptionGroup;
  using K = OptionKind;
  return {
      choice("tool", G::Tool, {"flat", "ball", "bull", "taper", "tapered-ball", "chamfer", "apt"},
             "", "cutter: flat, ball, bull, taper, tapered-ball, chamfer, apt"),
      quantity("diameter", G::Tool, D::Length,
               "cutter diameter D (tip diameter of a taper, ball diameter of a tapered ball), "
               "e.g. 12mm"),
      plain("tools", K::Text, G::Tool, "",
            "tool library giving each T number its cutter: LinuxCNC table, Fusion 360 JSON, "
            "FreeCAD .fctl/.fctb, CAMotics project (--tool then names the tool in the spindle "
            "before the program's first tool change)"),
      quantity("corner-radius", G::Tool, D::Length, "corner radius r_tc (bull, apt)"),
      quantity("taper-angle", G::Tool, D::Angle,
               "side angle beta to the tool axis (taper, tapered-ball, apt), e.g. 30deg"),
      quantity("tip-angle", G::Tool, D::Angle, "included tip angle (chamfer), e.g. 90deg"),
      quantity("bottom-angle", G::Tool, D::Angle,
               "lower-line angle delta above the horizontal (apt)"),
      quantity("flute-length", G::Tool, D::Length,
               "cutting height h above the tip (default 3 D, at least the cone of a chamfer)"),
      plain("flutes", K::Count, G::Tool, "2", "number of flutes"),
      quantity("shank-diameter", G::Tool, D::Length,
               "--tool's shank diameter (default: the cutter's), checked for collisions up to "
               "--stickout"),
      quantity("stickout", G::Tool, D::Length,
               "--tool's length out of the holder, tip to holder face: the shank above the "
               "flutes and the --holder above it must never meet material"),
      plain("holder", K::Text, G::Tool, "",
            "--tool's holder from its face up, segments DIAMETERxHEIGHT or "
            "LOWER-UPPERxHEIGHT, e.g. 22x10,28-40x30 (needs --stickout)"),
      plain("stock", K::Text, G::Stock, "",
            "box:X0,Y0,Z0,X1,Y1,Z1 (program units), a closed STL/OBJ/PLY mesh (mm) or an earlier "
            "run's stock.vdb; schedule's --model analytic runs without one"),
      plain("part", K::Text, G::Stock, "",
            "the part the program was made for: a closed STL/OBJ/PLY mesh (mm) or a .vdb level "
            "set, in the program's frame; the final stock is compared with it (gouges, "
            "leftovers, deviation.vdb; exit status 7 where a gouge is deeper than --tolerance)"),
      quantity("tolerance", G::Stock, D::Length,
               "with --part: a gouge counts where the part's material is removed deeper than "
               "this (default 0.05mm; 0.002in for an inch program)"),
      quantity("allowance", G::Stock, D::Length,
               "with --part: a leftover counts where material is left thicker than this on "
               "the part (default 0.05mm; 0.002in for an inch program; a roughing program's "
               "stock to leave)"),
      choice("stock-model", G::Stock, {"voxel", "dexel"}, "",
             "dexel (vertical rays; the default) or voxel (volume fractions; the default for a "
             "program that tilts the tool, through a --machine file's kinematics)"),
      quantity("voxel", G::Simulation, D::Length,
               "dexel ray spacing or voxel size (default: a twentieth of the diameter the "
               "tools engage at the program's depths)"),
      quantity("step", G::Simulation, D::Length, "longest step (default: 2.5 x --voxel)"),
      quantity("stepover", G::Simulation, D::Length,
               "stepover for the analytic model (default: measured width)"),
      quantity("depth", G::Simulation, D::Length,
               "depth of cut for the analytic model (default: measured depth)"),
      choice("units", G::Output, {"mm", "in", "inch"}, "",
             "report units: mm or in (default: the program's)"),
      plain("tool-table", K::Text, G::Simulation, "", "LinuxCNC tool table for G43"),
      choice("tool-table-units", G::Simulation, {"mm", "in", "inch"}, "",
             "units of a LinuxCNC tool table's numbers: mm or in (default: the program's, its "
             "first G20/G21, else the start-up units)"),
      choice("startup-units", G::Simulation, {"mm", "in", "inch"}, "",
             "the machine's units at start-up, for a program that sets neither G20 nor G21 "
             "(default: the machine file's startup_units, else mm)"),
      choice("dialect", G::Simulation, {"linuxcnc", "fanuc", "haas", "grbl"}, "linuxcnc",
             "the controller the program is for: linuxcnc; fanuc (M98 P with the count in its "
             "leading digits, G65 macro calls, IF/WHILE/GOTO, #0 vacant, system variables); "
             "haas (fanuc's, with #10000-#10999 and M97 local subprograms); grbl (ignores an "
             "arc's off-plane centre word)"),
      choice("cutter-comp", G::Simulation, {"control", "wear"}, "control",
             "what a G41/G42 D register holds: control (the tool's radius from --tools or "
             "--tool-table: the control offsets the part's outline) or wear (only the wear: the "
             "CAM's path is already the tool centre's, its \"wear\" compensation)"),
      plain("machine", K::Text, G::Simulation, "",
            "machine description (JSON: work offset, G28/G30, start position, travel) so that "
            "G53, G28 and G30 go where the machine puts them"),
      plain("start", K::Text, G::Simulation, "",
            "where the tool tip is when the program starts, X,Y,Z in the program's units "
            "and coordinates (default: the --machine file's start, else the program's origin, "
            "raised to the stock's top where that is above it)"),
      plain("block-delete", K::Flag, G::Simulation, "",
            "skip the lines that start with '/' (the controller's block delete switch on)"),
      plain("max-moves", K::Count, G::Simulation, "10000000",
            "most moves a program may make (a loop that never ends is refused at this)"),
      plain("max-steps", K::Count, G::Simulation, "5000000",
            "most steps a run may make (about 150 bytes each)"),
      plain("max-memory", K::Text, G::Simulation, "",
            "memory the run may use, e.g. 8GB: a run whose estimate (stock, steps, moves, "
            "outputs) is larger is refused before it starts (default: what this process may "
            "use: the available memory, the cgroup's limit, ulimit -v)"),
      plain("material", K::Text, G::Simulation, "",
            "workpiece material, for the chip thickness, forces, torque and power of every "
            "step: a bundled name (aluminium-7075-t6, steel-c45, stainless-304, ti-6al-4v) or "
            "a material .json file"),
      choice("force-model", G::Simulation, {"linear", "kienzle"}, "",
             "force model of --material: linear (edge-force coefficients) or kienzle "
             "(default: the file's choice)"),
      quantity("helix", G::Simulation, D::Angle,
               "helix angle of the flutes, for the peak force (default 30deg)"),
      plain("cross-check", K::Flag, G::Simulation, "",
            "also run the other stock model and report the steps where they disagree"),
      plain("cross-check-tolerance", K::Fraction, G::Simulation, "0.03",
            "relative per-step difference allowed by --cross-check"),
      commandLineOnly(plain("out", K::Text, G::Output, "out", "output folder")),
      choice("outputs", G::Output, {"all", "tables", "summary"}, "all",
             "files to write: all; tables (steps.csv, summary.json, report.html without its 3D "
             "view); summary (summary.json); schedule writes the re-fed program with each"),
      plain("stl-triangles", K::Count, G::Output, "2000000",
            "stock.stl with at most about this many triangles (nearly flat areas merged, and "
            "where that is not enough a coarser grid: every 2nd, 4th, ... ray of a dexel "
            "stock, voxels averaged in blocks of 2, 4 or 8); 0: every cell of the grid"),
      plain("no-report", K::Flag, G::Output, "",
            "do not write report.html (the run's summary, plots and 3D view in one page)"),
      commandLineOnly(plain("quiet", K::Flag, G::Output, "", "no progress on the terminal")),
      scheduleOnly(plain("target-mrr", K::Text, G::Schedule, "auto",
                         "target MRR, e.g. 18000mm3/min, or auto")),
      scheduleOnly(quantity("feed-min", G::Schedule, D::Feed,
                            "lowest feed to command (default: a tenth of each move's programmed "
                            "feed, or --feed-max if lower)")),
      scheduleOnly(
          plain("allow-unmet", K::Flag, G::Schedule, "",
                "write the re-fed program even where a load limit (--max-chip, --max-force, "
                "--max-torque, --max-power) holds only below the lowest feed (otherwise "
                "refused, exit status 6)")),
      scheduleOnly(quantity("feed-max", G::Schedule, D::Feed,
                            "highest feed to command (default: twice the programmed)")),
      scheduleOnly(quantity("air-feed", G::Schedule, D::Feed,
                            "feed where nothing is cut (default: the programmed)")),
      scheduleOnly(quantity("accel", G::Schedule, D::Acceleration,
                            "tangential acceleration limit, e.g. 2000mm/s2 or 0.3g (0: none)")),
      scheduleOnly(
          quantity("jerk", G::Schedule, D::Jerk,
                   "jerk limit, e.g. 50000mm/s3: room for the controller's S-curves (0: none)")),
      scheduleOnly(
          quantity("rapid-feed", G::Schedule, D::Feed,
                   "the machine's rapid feed, to time rapids in the cycle time, e.g. 15000mm/min")),
      scheduleOnly(
          plain("min-change", K::Fraction, G::Schedule, "0.05", "relative step between F levels")),
      scheduleOnly(quantity("min-segment", G::Schedule, D::Length,
                            "shortest run of one feed along the path (0: one step)")),
      scheduleOnly(quantity(
          "force-limit", G::Schedule, D::Force,
          "tangential force to hold instead of an MRR (with --specific-energy, --spindle)")),
      scheduleOnly(quantity("specific-energy", G::Schedule, D::SpecificEnergy,
                            "specific cutting energy, e.g. 0.7J/mm3")),
      quantity("spindle", G::Schedule, D::SpindleSpeed,
               "spindle speed, e.g. 12000rpm, where the program's spindle is stopped or has no S "
               "word: for --material (and schedule's --force-limit)"),
      scheduleOnly(quantity("max-chip", G::Schedule, D::Length,
                            "largest chip thickness h_max to allow, e.g. 0.05mm (with "
                            "--material; constant chip load: the usual high-speed target)")),
      scheduleOnly(quantity("max-force", G::Schedule, D::Force,
                            "largest peak cutting force to allow, e.g. 400N (with --material)")),
      scheduleOnly(quantity("max-torque", G::Schedule, D::Torque,
                            "largest spindle torque to allow, e.g. 5Nm (with --material)")),
      scheduleOnly(quantity("max-power", G::Schedule, D::Power,
                            "largest spindle power to allow, e.g. 3kW (with --material)")),
      scheduleOnly(
          choice("material-side", G::Schedule, {"right", "left"}, "",
                 "without --stock: the stock's side of the path (default right: climb, M3)")),
      scheduleOnly(choice("model", G::Schedule, {"measured", "analytic"}, "measured",
                          "schedule from the measured MRR or the analytic model")),
  };
}

}  // namespace

const std::vector<OptionInfo>& jobOptions() {
  static const std::vector<OptionInfo> table = makeTable();
  return table;
}

const OptionInfo* findJobOption(const std::string& name) {
  for (const OptionInfo& o : jobOptions())
    if (o.name == name) return &o;
  return nullptr;
}

bool appliesTo(const OptionInfo& option, JobCommand command) {
  return !option.scheduleOnly || command == JobCommand::Schedule;
}

const char* commandName(JobCommand command) {
  return command == JobCommand::Schedule ? "schedule" : "simulate";
}

}  // namespace engage
