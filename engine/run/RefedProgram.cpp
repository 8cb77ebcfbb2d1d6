#include "engine/run/RefedProgram.h"

#include "engine/run/Output.h"

#include "engine/units/Quantity.h"

#include <cctype>

namespace engage {

std::string withScheduleHeader(const std::string& program, const Job& job) {
  const ScheduleOptions& o = job.schedule;
  auto q = [&](double v, Dimension d) { return formatQuantity(v, d, job.units); };
  std::string held;
  auto add = [&](const std::string& what) { held += (held.empty() ? "" : ", ") + what; };
  if (o.mrrTarget)
    add("target MRR " +
        (o.targetMrr > 0.0 ? q(o.targetMrr, Dimension::VolumeRate) : std::string("auto")));
  if (o.maxChip > 0.0) add("chip <= " + q(o.maxChip, Dimension::Length));
  if (o.maxForce > 0.0) add("peak force <= " + q(o.maxForce, Dimension::Force));
  if (o.maxTorque > 0.0) add("torque <= " + q(o.maxTorque, Dimension::Torque));
  if (o.maxPower > 0.0) add("power <= " + q(o.maxPower, Dimension::Power));
  add("feed " +
      (o.feedMin > 0.0 ? q(o.feedMin, Dimension::Feed) : std::string("0.1 x programmed")) + " to " +
      (o.feedMax > 0.0 ? q(o.feedMax, Dimension::Feed) : std::string("2 x programmed")));
  if (o.acceleration > 0.0) add("acceleration <= " + q(o.acceleration, Dimension::Acceleration));
  if (o.jerk > 0.0) add("jerk <= " + q(o.jerk, Dimension::Jerk));
  const std::string header = "(feeds re-scheduled by engage: " + held + ")";
  // After a leading '%' line and a program number line: they must stay first.
  std::size_t at = 0;
  for (int kept = 0; kept < 2 && at < program.size(); ++kept) {
    const std::size_t end = program.find('\n', at);
    const std::string line =
        program.substr(at, end == std::string::npos ? std::string::npos : end - at);
    std::size_t k = line.find_first_not_of(" \t");
    if (k == std::string::npos) break;
    const bool percent = line[k] == '%';
    const bool number = (line[k] == 'O' || line[k] == 'o') && k + 1 < line.size() &&
                        std::isdigit(static_cast<unsigned char>(line[k + 1]));
    if (!percent && !number) break;
    if (end == std::string::npos) return program + "\n" + header + "\n";
    at = end + 1;
  }
  const bool crlf = program.find("\r\n") != std::string::npos;
  return program.substr(0, at) + header + (crlf ? "\r\n" : "\n") + program.substr(at);
}

std::filesystem::path refedProgramPath(const RunResult& result, const std::filesystem::path& dir) {
  return dir / std::filesystem::path(result.job.mainProgram()).filename();
}

void writeRefedProgram(const RunResult& result, const std::filesystem::path& dir) {
  if (result.job.scheduling()) writeAtomically(refedProgramPath(result, dir), result.refed);
}

}  // namespace engage
