#include "engine/report/Plots.h"

#include "cutters/Error.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>

#include <filesystem>
#include <fstream>

namespace engage {
namespace {

std::string quoted(const std::string& s) {
  return "\"" + s + "\"";
}

/// The commands that draw one plot as PNG and SVG; adds the file names. engage runs the script
/// with `part` set to ".part" (temporary names, renamed when all are drawn); by hand it draws
/// the final names.
std::string bothFormats(const std::string& name, const std::string& body,
                        std::vector<std::string>& files) {
  std::string script;
  for (const char* fmt : {"png", "svg"}) {
    const std::string file = name + "." + fmt;
    script += "set terminal " + std::string(fmt[0] == 'p' ? "pngcairo" : "svg") + " size " +
              std::to_string(kPlotWidth) + "," + std::to_string(kPlotWidth / 2) +
              (fmt[0] == 'p' ? " font ',11'\n" : " dynamic font 'sans,11'\n") + "set output " +
              quoted(file) + ".part\n" + body + "unset output\n";
    files.push_back(file);
  }
  return script;
}

/// Run a shell command and wait for it; its wait status (-1 when it cannot start). Not
/// std::system, which ignores SIGINT in the whole process while the command runs: a Ctrl-C
/// then would not stop engage (apps/main.cpp).
int runShell(const std::string& command) {
  pid_t pid = 0;
  std::string sh = "/bin/sh", dashC = "-c", text = command;
  char* argv[] = {sh.data(), dashC.data(), text.data(), nullptr};
  if (posix_spawn(&pid, "/bin/sh", nullptr, nullptr, argv, environ) != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return status;
}

/// Run gnuplot on `script` in `dir`, then give the plots their names.
void runGnuplot(const std::filesystem::path& dir, const std::string& scriptName,
                const std::string& script, std::vector<std::string>& files,
                const std::string& definitions = "") {
  const std::filesystem::path scriptFile = dir / scriptName;
  {
    std::ofstream f(scriptFile);
    if (!f) throw Error("cannot write '" + scriptFile.string() + "'");
    f << script;
  }
  const std::string log = scriptName + ".log";
  const std::string command = "cd " + quoted(dir.string()) + " && gnuplot -e " +
                              quoted("part='.part'; " + definitions) + " " + quoted(scriptName) +
                              " 2> " + quoted(log);
  const int rc = runShell(command);
  if (rc != 0) {
    // Say what gnuplot said (its last line), and leave no half-drawn plot behind.
    std::string said;
    {
      std::ifstream in(dir / log);
      for (std::string line; std::getline(in, line);)
        if (!line.empty()) said = line;
    }
    std::error_code ec;
    for (const std::string& file : files)
      std::filesystem::remove(dir / (file + ".part"), ec);
    std::filesystem::remove(dir / log, ec);
    const bool missing = WIFEXITED(rc) && WEXITSTATUS(rc) == 127;
    throw Error(missing ? std::string("gnuplot is not installed (Debian's gnuplot-nox)")
                        : "gnuplot failed: " +
                              (said.empty() ? "exit status " + std::to_string(rc) : said));
  }
  for (const std::string& file : files)
    std::filesystem::rename(dir / (file + ".part"), dir / file);
  std::filesystem::remove(dir / log);
  files.push_back(scriptName);
}

}  // namespace

std::vector<std::string> drawCharts(const std::string& folder, const std::vector<Chart>& charts,
                                    const std::string& scriptName) {
  std::vector<std::string> files;
  std::string script =
      "if (!exists(\"part\")) part = ''\n"
      "set datafile separator ','\nset datafile columnheaders\nset grid\nset key outside top "
      "center horizontal\n";
  for (const Chart& c : charts) {
    std::string body =
        "set title " + quoted(c.title) + "\nset xlabel " + quoted(c.xlabel) + "\nset ylabel " +
        quoted(c.ylabel) + "\n" +
        (c.logX ? "set logscale x\nset autoscale xfix\n" : "unset logscale x\nset autoscale x\n") +
        "plot ";
    bool first = true;
    for (const Series& s : c.series) {
      body += std::string(first ? "" : ", ") + quoted(s.file) + " using (column(" + quoted(s.x) +
              ")):(column(" + quoted(s.y) + ")) with " + s.style + " title " + quoted(s.title);
      first = false;
    }
    for (const auto& [value, title] : c.lines) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.6g", value);
      body +=
          std::string(first ? "" : ", ") + buf + " with lines lw 2 lc 'red' title " + quoted(title);
      first = false;
    }
    script += bothFormats(c.name, body + "\n", files);
  }
  runGnuplot(folder, scriptName, script, files);
  return files;
}

std::vector<std::string> writePlots(const PlotSpec& p) {
  const std::filesystem::path dir(p.folder);
  const std::string L = p.length, F = p.feed, Q = p.rate;
  std::vector<std::string> files;
  // By hand, `gnuplot plots.gp` draws from all of steps.csv; engage may give it a shorter
  // table (PlotSpec::data).
  std::string script =
      "if (!exists(\"data\")) data = 'steps.csv'\n"
      "if (!exists(\"top\")) top = data\n"
      "if (!exists(\"part\")) part = ''\n"
      "set datafile separator ','\nset datafile columnheaders\nset grid\nset key outside top "
      "center horizontal\n";
  auto plot = [&](const std::string& name, const std::string& body) {
    script += bothFormats(name, body, files);
  };
  const std::string x = "\"arc_length_" + L + "\"";
  // Tool changes on the plots along the path (not on the top view).
  for (const auto& [at, label] : p.toolChanges) {
    char mark[256];
    std::snprintf(mark, sizeof mark,
                  "set arrow from %.9g, graph 0 to %.9g, graph 1 nohead dt 2 lc rgb 'gray40'\n"
                  "set label %s at %.9g, graph 0.96 offset 0.4,0 tc rgb 'gray25'\n",
                  at, at, quoted(label).c_str(), at);
    script += mark;
  }
  std::string mrr =
      "set title 'Material removal rate along the path'\nset xlabel 'arc length (" + p.lengthLabel +
      ")'\nset ylabel 'MRR (" + p.rateLabel + ")'\n" + "plot data using " + x + ":\"mrr_" + Q +
      "\" with lines lw 1.5 title 'measured (" + p.model + ")', " + "'' using " + x +
      ":\"mrr_exact_" + Q + "\" with lines lw 1 dt 2 title 'analytic, exact', " + "'' using " + x +
      ":\"mrr_paper_" + Q + "\" with lines lw 1 dt 3 title 'analytic, paper'";
  if (p.schedule)
    mrr += ", '' using " + x + ":\"mrr_scheduled_" + Q +
           "\" with lines lw 1.5 title 'measured, re-fed'";
  plot("mrr", mrr + "\n");
  if (p.schedule) {
    plot("feed", "set title 'Feed'\nset xlabel 'arc length (" + p.lengthLabel +
                     ")'\nset ylabel 'feed (" + p.feedLabel + ")'\nplot data using " + x +
                     ":\"feed_" + F + "\" with lines lw 1.5 title 'programmed', '' using " + x +
                     ":\"feed_scheduled_" + F + "\" with lines lw 1.5 title 'scheduled'\n");
    std::string acc =
        "set title 'Tangential acceleration between successive feeds (Eq 24)'\nset xlabel 'arc "
        "length (" +
        p.lengthLabel + ")'\nset ylabel 'acceleration (" + p.accelerationLabel +
        ")'\nplot data using " + x + ":\"acceleration_" + p.accelerationTag +
        "\" with lines lw 1.5 title 'scheduled'";
    if (p.accelerationLimit > 0) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.6g", p.accelerationLimit);
      acc += std::string(", ") + buf + " with lines lw 2 lc 'red' title 'limit', -" + buf +
             " with lines lw 2 lc 'red' notitle";
    }
    plot("acceleration", acc + "\n");
  }
  if (p.physics) {
    // One chart per quantity: at the programmed feeds, at the scheduled ones, the limit.
    auto physicsPlot = [&](const std::string& name, const std::string& title,
                           const std::string& column, const std::string& unit, double limit) {
      std::string body = "set title '" + title + " along the path'\nset xlabel 'arc length (" +
                         p.lengthLabel + ")'\nset ylabel '" + title + " (" + unit +
                         ")'\nplot data using " + x + ":\"" + column +
                         "\" with lines lw 1.5 title 'programmed feeds'";
      if (p.schedule) {
        const std::string scheduled =
            column.substr(0, column.rfind('_')) + "_scheduled" + column.substr(column.rfind('_'));
        body +=
            ", '' using " + x + ":\"" + scheduled + "\" with lines lw 1.5 title 'scheduled feeds'";
      }
      if (limit > 0) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.6g", limit);
        body += std::string(", ") + buf + " with lines lw 2 lc 'red' title 'limit'";
      }
      plot(name, body + "\n");
    };
    physicsPlot("chip", "largest chip thickness h_max", "h_max_" + L, p.lengthLabel, p.maxChip);
    physicsPlot("force", "peak cutting force", "f_peak_" + p.forceTag, p.forceLabel, p.maxForce);
    physicsPlot("power", "spindle power", "power_" + p.powerTag, p.powerLabel, p.maxPower);
  }
  script += "unset arrow\nunset label\n";
  plot("topview", "set title 'Top view, coloured by measured MRR (" + p.rateLabel +
                      ")'\nset size ratio -1\nset xlabel 'x (" + p.lengthLabel +
                      ")'\nset ylabel 'y (" + p.lengthLabel + ")'\nset palette rgb 33,13,10\n" +
                      "plot top using (strcol(\"kind\") eq \"rapid\" ? NaN : column(\"x_" + L +
                      "\")):\"y_" + L + "\":\"mrr_" + Q +
                      "\" with points pt 7 ps 0.4 lc palette notitle\nset size noratio\n");
  const bool shorter = p.data != "steps.csv" || p.topData != "steps.csv";
  runGnuplot(dir, "plots.gp", script, files,
             shorter ? "data='" + p.data + "'; top='" + p.topData + "'" : std::string());
  return files;
}

}  // namespace engage
