/// \file EngageModule.cpp
/// The Python module `engage`: the second thin front end over the engine, for researchers who
/// work in notebooks. A run takes the same option names as the command line and a manifest
/// (OptionTable.h, with '_' for '-'), goes through the same pipeline, and gives its per-step
/// results as NumPy arrays in internal units (mm, mm/min, mm^3/min, s, rad), the summary as
/// a dict (in the run's report units, named under "unit_labels"), and writes the same files.
/// The analytic model (paper Eq 1-24) is callable directly. Errors are engage.Error with the
/// command line's messages.

#include "cutters/AptCutter.h"
#include "cutters/CrossSection.h"
#include "cutters/Error.h"
#include "cutters/Numbers.h"
#include "engine/gcode/GcodeReader.h"
#include "engine/model/EngagementModel.h"
#include "engine/run/Job.h"
#include "engine/run/OptionTable.h"
#include "engine/run/Output.h"
#include "engine/run/Pipeline.h"
#include "engine/run/RunOutputs.h"
#include "engine/run/StepsTable.h"
#include "engine/run/Summary.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace engage;

namespace {

/// A NumPy array of f(i) for i in [0, n).
template <typename T>
py::array_t<T> column(std::size_t n, const std::function<T(std::size_t)>& f) {
  py::array_t<T> a(static_cast<py::ssize_t>(n));
  auto v = a.template mutable_unchecked<1>();
  for (std::size_t i = 0; i < n; ++i)
    v(static_cast<py::ssize_t>(i)) = f(i);
  return a;
}

py::array textColumn(std::size_t n, const std::function<std::string(std::size_t)>& f) {
  std::vector<std::string> v(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = f(i);
  return py::array(py::cast(v));
}

const char* sideName(PathSide s) {
  return s == PathSide::Concave ? "concave" : s == PathSide::Convex ? "convex" : "straight";
}

PathShape pathShape(const std::string& side, double radius) {
  if (side == "straight") return {PathSide::Straight, 0.0};
  if (side == "concave") return {PathSide::Concave, radius};
  if (side == "convex") return {PathSide::Convex, radius};
  throw ParameterError("side: expected straight, concave or convex, found '" + side + "'");
}

/// The per-step columns, internal units in the names.
py::dict stepColumns(const RunResult& r) {
  const auto& s = r.sim.steps;
  const std::size_t n = s.size();
  py::dict d;
  d["step"] = column<long>(n, [](std::size_t i) { return static_cast<long>(i); });
  d["move"] = column<long>(n, [&](std::size_t i) { return static_cast<long>(s[i].move); });
  d["line"] = column<long>(n, [&](std::size_t i) { return static_cast<long>(s[i].line); });
  d["tool"] = column<long>(n, [&](std::size_t i) { return static_cast<long>(s[i].tool); });
  d["kind"] = textColumn(n, [&](std::size_t i) { return moveKindName(s[i].kind); });
  d["arc_length_mm"] = column<double>(n, [&](std::size_t i) { return s[i].arcLength; });
  d["length_mm"] = column<double>(n, [&](std::size_t i) { return s[i].length; });
  d["x_mm"] = column<double>(n, [&](std::size_t i) { return s[i].end.x(); });
  d["y_mm"] = column<double>(n, [&](std::size_t i) { return s[i].end.y(); });
  d["z_mm"] = column<double>(n, [&](std::size_t i) { return s[i].end.z(); });
  d["feed_mm_min"] = column<double>(n, [&](std::size_t i) { return s[i].feed; });
  d["dt_s"] = column<double>(n, [&](std::size_t i) { return s[i].dt; });
  d["removed_mm3"] = column<double>(n, [&](std::size_t i) { return s[i].removed; });
  d["mrr_mm3_min"] = column<double>(n, [&](std::size_t i) { return s[i].mrr; });
  d["width_mm"] = column<double>(n, [&](std::size_t i) { return s[i].width; });
  d["depth_mm"] = column<double>(n, [&](std::size_t i) { return s[i].depth; });
  d["engagement_rad"] = column<double>(n, [&](std::size_t i) { return s[i].engagementRad; });
  d["curvature_1_mm"] = column<double>(n, [&](std::size_t i) { return s[i].curvature; });
  d["path"] = textColumn(n, [&](std::size_t i) { return sideName(s[i].side); });
  d["mrr_exact_mm3_min"] = column<double>(n, [&](std::size_t i) { return s[i].mrrExact; });
  d["mrr_paper_mm3_min"] = column<double>(n, [&](std::size_t i) { return s[i].mrrPaper; });
  d["voxels_changed"] = column<long>(n, [&](std::size_t i) { return s[i].voxelsChanged; });
  if (r.job.scheduling()) {
    d["feed_scheduled_mm_min"] = column<double>(n, [&](std::size_t i) { return r.plan.feed[i]; });
    d["binding"] = textColumn(n, [&](std::size_t i) { return bindingName(r.plan.binding[i]); });
    d["mrr_scheduled_mm3_min"] =
        column<double>(n, [&](std::size_t i) { return s[i].mrr * feedScale(r, i); });
    d["acceleration_mm_s2"] =
        column<double>(n, [&](std::size_t i) { return scheduledAcceleration(r, i); });
  }
  if (!r.sim.loads.empty()) {
    // Cutting physics (engine/physics), internal units. The entry and exit angles as in
    // steps.csv: from the feed direction in the direction of rotation (a slot -pi/2 to pi/2).
    const auto& l = r.sim.loads;
    d["entry_rad"] =
        column<double>(n, [&](std::size_t i) { return fromFeedDirection(l[i].entry); });
    d["exit_rad"] = column<double>(n, [&](std::size_t i) { return fromFeedDirection(l[i].exit); });
    d["h_max_mm"] = column<double>(n, [&](std::size_t i) { return l[i].hMax; });
    d["h_mean_mm"] = column<double>(n, [&](std::size_t i) { return l[i].hMean; });
    d["fx_N"] = column<double>(n, [&](std::size_t i) { return l[i].force.x(); });
    d["fy_N"] = column<double>(n, [&](std::size_t i) { return l[i].force.y(); });
    d["fz_N"] = column<double>(n, [&](std::size_t i) { return l[i].force.z(); });
    d["f_peak_N"] = column<double>(n, [&](std::size_t i) { return l[i].peak; });
    d["torque_Nm"] = column<double>(n, [&](std::size_t i) { return l[i].torque; });
    d["power_W"] = column<double>(n, [&](std::size_t i) { return l[i].power; });
    if (r.job.scheduling()) {
      auto scaled = [&](std::size_t i) { return scaleLoad(l[i], feedScale(r, i)); };
      d["h_max_scheduled_mm"] = column<double>(n, [&](std::size_t i) { return scaled(i).hMax; });
      d["f_peak_scheduled_N"] = column<double>(n, [&](std::size_t i) { return scaled(i).peak; });
      d["torque_scheduled_Nm"] = column<double>(n, [&](std::size_t i) { return scaled(i).torque; });
      d["power_scheduled_W"] = column<double>(n, [&](std::size_t i) { return scaled(i).power; });
    }
  }
  if (r.crossChecked) {
    d[py::str("removed_" + std::string(stockModelName(r.job.otherModel())) + "_mm3")] =
        column<double>(n, [&](std::size_t i) { return r.cross.other.steps[i].removed; });
    d["cross_check_differs"] =
        column<bool>(n, [&](std::size_t i) { return r.cross.differs[i] != 0; });
  }
  return d;
}

/// The moves of a program as columns (mm, mm/min).
py::dict moveColumns(const Toolpath& p) {
  const auto& m = p.moves;
  const std::size_t n = m.size();
  py::dict d;
  d["kind"] = textColumn(n, [&](std::size_t i) { return moveKindName(m[i].kind); });
  d["line"] = column<long>(n, [&](std::size_t i) { return static_cast<long>(m[i].line); });
  for (int a = 0; a < 3; ++a) {
    const std::string axis(1, "xyz"[a]);
    d[py::str("start_" + axis + "_mm")] =
        column<double>(n, [&](std::size_t i) { return m[i].start[a]; });
    d[py::str("end_" + axis + "_mm")] =
        column<double>(n, [&](std::size_t i) { return m[i].end[a]; });
  }
  d["feed_mm_min"] = column<double>(n, [&](std::size_t i) { return m[i].feed; });
  d["spindle_rpm"] = column<double>(n, [&](std::size_t i) { return m[i].spindleRpm; });
  d["tool"] = column<long>(n, [&](std::size_t i) { return static_cast<long>(m[i].tool); });
  return d;
}

/// Option values from Python keyword arguments: '_' stands for '-', True/False for flags.
/// The command line's own options (out, quiet) are refused: a run writes nothing until
/// Result.write(folder), and shows no progress. (Unknown names are refused by makeJob.)
OptionValues optionValues(const py::kwargs& kwargs) {
  OptionValues v;
  for (const auto& [key, value] : kwargs) {
    std::string name = py::str(key);
    for (char& c : name)
      if (c == '_') c = '-';
    if (const OptionInfo* o = findJobOption(name); o && o->commandLineOnly)
      throw ParameterError(std::string(py::str(key)) +
                           "= is the command line's: in Python a run writes nothing until "
                           "result.write(folder), and shows no progress");
    if (py::isinstance<py::bool_>(value))
      v[name] = value.cast<bool>() ? "true" : "false";
    else
      v[name] = py::str(value);
  }
  return v;
}

RunResult runFromPython(const std::string& command, const py::kwargs& kwargs) {
  if (command != "simulate" && command != "schedule")
    throw ParameterError("command: expected simulate or schedule, found '" + command + "'");
  Job job = makeJob(command == "schedule" ? JobCommand::Schedule : JobCommand::Simulate,
                    optionValues(kwargs));
  py::gil_scoped_release release;
  return runJob(std::move(job));
}

void bindCutter(py::module_& m) {
  py::class_<AptCutter>(m, "Cutter",
                        "A generalized APT end mill (mm, rad). Build with the static methods.")
      .def_static("flat", &AptCutter::flat, py::arg("diameter"), py::arg("flute_length"),
                  py::arg("flutes") = 2)
      .def_static("ball", &AptCutter::ball, py::arg("diameter"), py::arg("flute_length"),
                  py::arg("flutes") = 2)
      .def_static("bull", &AptCutter::bull, py::arg("diameter"), py::arg("corner_radius"),
                  py::arg("flute_length"), py::arg("flutes") = 2)
      .def_static("taper", &AptCutter::taper, py::arg("tip_diameter"), py::arg("taper_angle_rad"),
                  py::arg("flute_length"), py::arg("flutes") = 2)
      .def_static("tapered_ball", &AptCutter::taperedBall, py::arg("ball_diameter"),
                  py::arg("taper_angle_rad"), py::arg("flute_length"), py::arg("flutes") = 2)
      .def_static("chamfer", &AptCutter::chamfer, py::arg("diameter"),
                  py::arg("included_angle_rad"), py::arg("flute_length"), py::arg("flutes") = 2)
      .def_property_readonly("radius", &AptCutter::radius, "r = D/2 at the tip's widest, mm")
      .def_property_readonly("max_radius", &AptCutter::maxRadius, "widest radius, mm")
      .def_property_readonly("height", &AptCutter::height, "cutting height h, mm")
      .def_property_readonly("flutes", &AptCutter::fluteCount)
      .def("radius_at", &AptCutter::radiusAt, py::arg("z"),
           "W(z): the cutter's radius at height z above the tip, mm");
}

void bindModel(py::module_& m) {
  m.def(
      "cross_section",
      [](const AptCutter& c, double s, double d) {
        const CrossSection x = exactCrossSection(c, s, d);
        return py::dict(py::arg("area_mm2") = x.area, py::arg("centroid_x_mm") = x.centroidX,
                        py::arg("centroid_z_mm") = x.centroidZ,
                        py::arg("cusp_height_mm") = x.cuspHeight);
      },
      py::arg("cutter"), py::arg("stepover"), py::arg("depth"),
      "Exact removed cross-section y_G of a straight pass and its centroid (paper Eq 1-11 "
      "as an exact integral), mm^2 and mm");
  m.def(
      "paper_cross_section",
      [](const AptCutter& c, double s, double d) {
        const PaperCrossSection x = paperCrossSection(c, s, d);
        return py::dict(py::arg("area_mm2") = x.area, py::arg("phi_rad") = x.phiRad,
                        py::arg("applies") = x.applies, py::arg("reason") = x.reason);
      },
      py::arg("cutter"), py::arg("stepover"), py::arg("depth"),
      "Paper Eq 2-3 as printed, with whether they describe this case");
  using Rate = double (EngagementModel::*)(double, const PathShape&) const;
  using Ratio = double (EngagementModel::*)(const PathShape&) const;
  auto rate = [](Rate f) {
    return [f](const EngagementModel& e, double v, const std::string& side, double radius) {
      return (e.*f)(v, pathShape(side, radius));
    };
  };
  auto ratio = [](Ratio f) {
    return [f](const EngagementModel& e, const std::string& side, double radius) {
      return (e.*f)(pathShape(side, radius));
    };
  };
  const auto side = py::arg("side") = "straight";
  const auto radius = py::arg("radius") = 0.0;
  py::class_<EngagementModel>(m, "Model",
                              "The analytic MRR model of one cutter at one stepover and depth "
                              "(paper Eq 6, 12-16, 21-23); side is straight, concave or convex, "
                              "radius the tool-centre path radius (mm)")
      .def(py::init<const AptCutter&, double, double>(), py::arg("cutter"), py::arg("stepover"),
           py::arg("depth"))
      .def("mrr", rate(&EngagementModel::mrr), py::arg("feed"), side, radius,
           "exact MRR, mm^3/min (Eq 6 when straight)")
      .def("mrr_paper", rate(&EngagementModel::mrrPaper), py::arg("feed"), side, radius,
           "MRR as the paper writes it (Eq 6, 15, 16), mm^3/min")
      .def("centroid_speed_ratio", ratio(&EngagementModel::centroidSpeedRatio), side, radius,
           "(rho +- x_bar) / rho (Pappus)")
      .def("centroid_speed_ratio_paper", ratio(&EngagementModel::centroidSpeedRatioPaper), side,
           radius, "Eq 12/13")
      .def("adaptive_feed", rate(&EngagementModel::adaptiveFeed), py::arg("target_mrr"), side,
           radius, "tip feed for a target MRR, exact, mm/min")
      .def("adaptive_feed_paper", rate(&EngagementModel::adaptiveFeedPaper), py::arg("target_mrr"),
           side, radius, "Eq 21-23, mm/min")
      .def("paper_centroid_distance", &EngagementModel::paperCentroidDistance, "the paper's m")
      .def_property_readonly("area_mm2", [](const EngagementModel& e) { return e.exact().area; });
}

void bindEquations(py::module_& m) {
  m.def("cutting_speed", &cuttingSpeed, py::arg("diameter"), py::arg("spindle_rpm"),
        "Eq 17: v = pi D N, mm/min");
  m.def("tangential_force", &tangentialForce, py::arg("mrr"), py::arg("specific_energy"),
        py::arg("cutting_speed"), "Eq 18: F = MRR E / v, N (E in J/mm^3, v in mm/min)");
  m.def("tangential_acceleration", &tangentialAcceleration, py::arg("feed0"), py::arg("feed1"),
        py::arg("arc_length"), "Eq 24: a = (f1^2 - f0^2) / (2 ds), mm/s^2");
}

void bindRun(py::module_& m) {
  py::class_<RunResult>(m, "Result", "What a run made")
      .def_property_readonly("steps", &stepColumns,
                             "per-step NumPy arrays by name; units in the names")
      .def_property_readonly(
          "summary",
          [](const RunResult& r) {
            return py::module_::import("json").attr("loads")(summaryJson(r));
          },
          "summary.json as a dict (report units, see unit_labels)")
      .def_property_readonly("removed_mm3", [](const RunResult& r) { return r.sim.removed; })
      .def_property_readonly(
          "warnings",
          [](const RunResult& r) {
            WrittenOutputs none;
            none.steps = false;
            return runWarnings(r, none);
          },
          "the run's warnings, as engage simulate prints them without 'warning: '")
      .def_property_readonly("refed_program", [](const RunResult& r) { return r.refed; })
      .def(
          "steps_csv", [](const RunResult& r) { return stepsTable(r); }, "steps.csv's text")
      .def(
          "write",
          [](const RunResult& r, const std::string& folder) {
            OutputDirectory dir(folder);
            writeRunOutputs(r, folder);
            dir.keep();
          },
          py::arg("folder"),
          "write steps.csv, summary.json, plots, removed.vdb, stock.vdb, stock.stl (and the "
          "re-fed program) into folder");
  m.def("run", &runFromPython, py::arg("command") = "simulate",
        "Run a job: run(command='simulate' or 'schedule', program=..., tool=..., "
        "diameter=..., stock=..., ...) with the options of engage simulate/schedule ('_' for "
        "'-'); values as on the command line ('6mm', 'box:0,0,-10,60,60,0') or numbers in the "
        "program's units");
  m.def(
      "options",
      [] {
        py::list l;
        for (const OptionInfo& o : jobOptions())
          l.append(py::dict(py::arg("name") = o.name, py::arg("default") = o.defaultText,
                            py::arg("help") = o.help, py::arg("schedule_only") = o.scheduleOnly,
                            py::arg("choices") = o.choices));
        return l;
      },
      "the job options, as the command line and manifests take them");
  m.def(
      "read_program",
      [](const std::string& path, const std::string& toolTable) {
        ReaderOptions ro;
        ro.toolTable = toolTable;
        return moveColumns(readProgram(path, ro));
      },
      py::arg("path"), py::arg("tool_table") = "",
      "the interpreted moves of a G-code program as NumPy arrays (mm, mm/min)");
}

}  // namespace

PYBIND11_MODULE(engage, m) {
  m.doc() = "engage: material-engagement simulator and adaptive feedrate scheduler for CNC milling";
  py::register_exception<Error>(m, "Error");
  bindCutter(m);
  bindModel(m);
  bindEquations(m);
  bindRun(m);
}
