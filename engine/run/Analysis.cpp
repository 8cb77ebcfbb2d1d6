#include "engine/run/Analysis.h"

#include "cutters/Error.h"
#include "engine/model/EngagementModel.h"
#include "engine/units/Quantity.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

namespace engage {
namespace {

/// One line of the report: a number with its dimension, or a text; shown the same way in the
/// text table and in the JSON object.
struct Row {
  std::string key;
  std::variant<double, std::string, bool> value;
  std::optional<Dimension> dim;
  std::string note;
};

class Report {
 public:
  explicit Report(UnitSystem sys) : sys_(sys) {}
  void number(const std::string& key, double internal, Dimension dim, std::string note = {}) {
    rows_.push_back({key, internal, dim, std::move(note)});
  }
  void ratio(const std::string& key, double value, std::string note = {}) {
    rows_.push_back({key, value, std::nullopt, std::move(note)});
  }
  void text(const std::string& key, std::string value, std::string note = {}) {
    rows_.push_back({key, std::move(value), std::nullopt, std::move(note)});
  }
  void flag(const std::string& key, bool value, std::string note = {}) {
    rows_.push_back({key, value, std::nullopt, std::move(note)});
  }

  void printText(std::ostream& out) const {
    for (const Row& r : rows_) {
      std::string v;
      if (const double* d = std::get_if<double>(&r.value))
        v = r.dim ? formatQuantity(*d, *r.dim, sys_) : formatNumber(*d);
      else if (const std::string* s = std::get_if<std::string>(&r.value))
        v = *s;
      else
        v = std::get<bool>(r.value) ? "yes" : "no";
      char line[512];
      std::snprintf(line, sizeof line, "%-28s %-22s", r.key.c_str(), v.c_str());
      std::string l = line;
      if (!r.note.empty()) l += " " + r.note;
      while (!l.empty() && l.back() == ' ')
        l.pop_back();
      out << l << '\n';
    }
  }

  nlohmann::ordered_json json() const {
    nlohmann::ordered_json j;
    nlohmann::ordered_json labels;
    for (const Row& r : rows_) {
      if (const double* d = std::get_if<double>(&r.value)) {
        const double shown = r.dim ? toDisplay(*d, *r.dim, sys_) : *d;
        if (std::isfinite(shown))
          j[r.key] = shown;
        else
          j[r.key] = nullptr;
        if (r.dim) labels[r.key] = std::string(unitLabel(*r.dim, sys_));
      } else if (const std::string* s = std::get_if<std::string>(&r.value)) {
        j[r.key] = *s;
      } else {
        j[r.key] = std::get<bool>(r.value);
      }
    }
    j["unit_labels"] = labels;
    return j;
  }

 private:
  UnitSystem sys_;
  std::vector<Row> rows_;
};

PathSide parseSide(const std::string& side) {
  if (side == "concave") return PathSide::Concave;
  if (side == "convex") return PathSide::Convex;
  throw ParameterError("--side: expected concave or convex, found '" + side + "'");
}

std::string sweepTable(const AnalyzeOptions& o) {
  std::ostringstream os;
  // The paper's Fig 8 set-up unless overridden: D = 1 in, d = 0.3 in, s = 0.5 in, 100 ipm.
  const std::string diameterText = o.tool.diameter.empty() ? "1in" : o.tool.diameter;
  const std::string depthText = o.depth.empty() ? "0.3in" : o.depth;
  const std::string stepoverText = o.stepover.empty() ? "0.5in" : o.stepover;
  const std::string feedText = o.feed.empty() ? "100ipm" : o.feed;
  const UnitSystem sys = chooseUnitSystem(o.units, {{diameterText, Dimension::Length},
                                                    {stepoverText, Dimension::Length},
                                                    {depthText, Dimension::Length},
                                                    {feedText, Dimension::Feed}});
  const double D = parseQuantity(diameterText, Dimension::Length, sys, "--diameter").value;
  const double d = parseQuantity(depthText, Dimension::Length, sys, "--depth").value;
  const double s = parseQuantity(stepoverText, Dimension::Length, sys, "--stepover").value;
  const double feed = parseQuantity(feedText, Dimension::Feed, sys, "--feed").value;
  const auto fluteText =
      optionalQuantity(o.tool.fluteLength, Dimension::Length, sys, "--flute-length");
  const double h = fluteText.value_or(3.0 * D);

  const std::string L(unitTag(Dimension::Length, sys));
  const std::string A(unitTag(Dimension::Area, sys));
  const std::string Q(unitTag(Dimension::VolumeRate, sys));
  os << "corner_radius_over_D,path_radius_over_D,path_radius_" << L << ",area_" << A
     << ",area_paper_" << A << ",paper_applies,centroid_x_" << L << ",centroid_z_" << L
     << ",mrr_linear_" << Q << ",mrr_concave_" << Q << ",mrr_concave_paper_" << Q << ",mrr_convex_"
     << Q << ",mrr_convex_paper_" << Q << '\n';
  const double cornerRatios[] = {0.0, 0.1, 0.2, 0.3, 0.4, 0.5};
  const double radiusRatios[] = {1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 7.5, 10, 15, 20, 30, 40, 50};
  auto out = [&](double v, Dimension dim) { return formatNumber(toDisplay(v, dim, sys)); };
  for (double k : cornerRatios) {
    const AptCutter cutter = k == 0.0   ? AptCutter::flat(D, h)
                             : k == 0.5 ? AptCutter::ball(D, h)
                                        : AptCutter::bull(D, k * D, h);
    const EngagementModel model(cutter, s, d);
    for (double q : radiusRatios) {
      const PathShape concave{PathSide::Concave, q * D};
      const PathShape convex{PathSide::Convex, q * D};
      os << formatNumber(k) << ',' << formatNumber(q) << ',' << out(q * D, Dimension::Length) << ','
         << out(model.exact().area, Dimension::Area) << ','
         << out(model.paper().area, Dimension::Area) << ','
         << (model.paper().applies ? "yes" : "no") << ','
         << out(model.exact().centroidX, Dimension::Length) << ','
         << out(model.exact().centroidZ, Dimension::Length) << ','
         << out(model.mrr(feed, {}), Dimension::VolumeRate) << ','
         << out(model.mrr(feed, concave), Dimension::VolumeRate) << ','
         << out(model.mrrPaper(feed, concave), Dimension::VolumeRate) << ','
         << out(model.mrr(feed, convex), Dimension::VolumeRate) << ','
         << out(model.mrrPaper(feed, convex), Dimension::VolumeRate) << '\n';
    }
  }
  return os.str();
}

}  // namespace

std::string analyzeReport(const AnalyzeOptions& o) {
  if (o.sweep) return sweepTable(o);
  std::ostringstream os;
  if (o.tool.tool.empty() || o.tool.diameter.empty())
    throw ParameterError("analyze needs --tool and --diameter (or --sweep-radius)");
  if (o.stepover.empty()) throw ParameterError("analyze needs --stepover");
  if (o.depth.empty()) throw ParameterError("analyze needs --depth");
  if (o.feed.empty()) throw ParameterError("analyze needs --feed");
  if (o.pathRadius.empty() != o.side.empty())
    throw ParameterError("--path-radius and --side go together");
  if (o.specificEnergy.empty() != o.spindle.empty())
    throw ParameterError("--specific-energy and --spindle go together (force needs both)");
  if (!o.transition.empty() && (o.targetMrr.empty() || o.pathRadius.empty()))
    throw ParameterError("--transition needs --target-mrr and --path-radius");

  const UnitSystem sys = chooseUnitSystem(o.units, {{o.tool.diameter, Dimension::Length},
                                                    {o.stepover, Dimension::Length},
                                                    {o.depth, Dimension::Length},
                                                    {o.feed, Dimension::Feed},
                                                    {o.pathRadius, Dimension::Length},
                                                    {o.targetMrr, Dimension::VolumeRate}});
  const AptCutter cutter = buildCutter(o.tool, sys);
  const double s = parseQuantity(o.stepover, Dimension::Length, sys, "--stepover").value;
  const double d = parseQuantity(o.depth, Dimension::Length, sys, "--depth").value;
  const double feed = parseQuantity(o.feed, Dimension::Feed, sys, "--feed").value;
  if (!(feed > 0.0)) throw ParameterError("--feed must be positive");
  const auto pathRadius = optionalQuantity(o.pathRadius, Dimension::Length, sys, "--path-radius");
  const auto target = optionalQuantity(o.targetMrr, Dimension::VolumeRate, sys, "--target-mrr");
  if (target && !(*target > 0.0)) throw ParameterError("--target-mrr must be positive");
  const auto energy =
      optionalQuantity(o.specificEnergy, Dimension::SpecificEnergy, sys, "--specific-energy");
  const auto spindle = optionalQuantity(o.spindle, Dimension::SpindleSpeed, sys, "--spindle");
  const auto transition = optionalQuantity(o.transition, Dimension::Length, sys, "--transition");

  const EngagementModel model(cutter, s, d);
  PathShape path;
  if (pathRadius) path = PathShape{parseSide(o.side), *pathRadius};
  const PathShape straight;

  Report r(sys);
  r.text("units", std::string(systemName(sys)));
  r.text("cutter", describeCutter(cutter, sys));
  r.number("stepover", s, Dimension::Length);
  r.number("depth", d, Dimension::Length);
  r.number("feed", feed, Dimension::Feed, "at the tool tip");
  const CrossSection& x = model.exact();
  const PaperCrossSection& p = model.paper();
  r.number("area", x.area, Dimension::Area, "exact integral of min(2W(z), s) over the depth");
  r.number("centroid_x", x.centroidX, Dimension::Length, "from the cutter axis toward the stock");
  r.number("centroid_z", x.centroidZ, Dimension::Length, "above the tool tip");
  r.number("cusp_height", x.cuspHeight, Dimension::Length,
           "ridge between this pass and the previous one");
  r.number("area_paper", p.area, Dimension::Area, "paper Eq 2-3 as printed");
  r.flag("paper_applies", p.applies, p.reason);
  r.number("mrr_linear", model.mrr(feed, straight), Dimension::VolumeRate, "Eq 6, exact area");
  r.number("mrr_linear_paper", model.mrrPaper(feed, straight), Dimension::VolumeRate,
           "Eq 6 with the Eq 2-3 area");
  if (pathRadius) {
    r.text("side", o.side);
    r.number("path_radius", path.radius, Dimension::Length, "tool-centre path");
    r.number("paper_R", model.paperPathRadius(path), Dimension::Length,
             "paper's R: contact-point path, rho " +
                 std::string(path.side == PathSide::Concave ? "+" : "-") + " r");
    r.number("paper_m", model.paperCentroidDistance(), Dimension::Length,
             "paper's m: contact point (r, 0) to centroid");
    r.ratio("centroid_speed_ratio", model.centroidSpeedRatio(path),
            "exact V_c / V_f = (rho " + std::string(path.side == PathSide::Concave ? "+" : "-") +
                " centroid_x) / rho");
    r.ratio("centroid_speed_ratio_paper", model.centroidSpeedRatioPaper(path),
            path.side == PathSide::Concave ? "Eq 12: (R - m)/(R - r)" : "Eq 13: (R + m)/(R + r)");
    r.number("mrr_curved", model.mrr(feed, path), Dimension::VolumeRate,
             "exact: area x speed of the centroid");
    r.number("mrr_curved_paper", model.mrrPaper(feed, path), Dimension::VolumeRate,
             path.side == PathSide::Concave ? "Eq 16" : "Eq 15");
  }
  if (energy) {
    const double v = cuttingSpeed(2.0 * cutter.radius(), *spindle);
    r.number("spindle", *spindle, Dimension::SpindleSpeed);
    r.number("specific_energy", *energy, Dimension::SpecificEnergy);
    r.number("cutting_speed", v, Dimension::SurfaceSpeed, "Eq 17: pi D N");
    r.number("force_linear", tangentialForce(model.mrr(feed, straight), *energy, v),
             Dimension::Force, "Eq 18: MRR E / v");
    if (pathRadius) {
      r.number("force_curved", tangentialForce(model.mrr(feed, path), *energy, v), Dimension::Force,
               "exact MRR in Eq 18");
      r.number("force_curved_paper", tangentialForce(model.mrrPaper(feed, path), *energy, v),
               Dimension::Force, path.side == PathSide::Concave ? "Eq 20" : "Eq 19");
    }
  }
  if (target) {
    r.number("target_mrr", *target, Dimension::VolumeRate);
    const double linear = model.adaptiveFeed(*target, straight);
    r.number("feed_adaptive_linear", linear, Dimension::Feed, "Eq 23");
    r.number("feed_adaptive_linear_paper", model.adaptiveFeedPaper(*target, straight),
             Dimension::Feed, "Eq 23 with the Eq 2-3 area");
    if (pathRadius) {
      const double curved = model.adaptiveFeed(*target, path);
      r.number("feed_adaptive_curved", curved, Dimension::Feed, "exact");
      r.number("feed_adaptive_curved_paper", model.adaptiveFeedPaper(*target, path),
               Dimension::Feed, path.side == PathSide::Concave ? "Eq 22" : "Eq 21");
      if (transition) {
        r.number("transition", *transition, Dimension::Length,
                 "arc length to go from the linear to the curved adaptive feed");
        r.number("acceleration_transition", tangentialAcceleration(linear, curved, *transition),
                 Dimension::Acceleration, "Eq 24");
        r.number("time_transition", transitionTime(linear, curved, *transition), Dimension::Time,
                 "Eq 24");
      }
    }
  }
  if (o.json)
    os << r.json().dump(2) << '\n';
  else
    r.printText(os);
  return os.str();
}

}  // namespace engage
