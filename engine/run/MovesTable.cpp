#include "engine/run/MovesTable.h"

#include "engine/sim/ToolPoses.h"

#include <cstdio>
#include <string>
#include <string_view>

namespace engage {

std::string movesTable(const Toolpath& path) {
  // A rotary machine's moves, and a tilted work plane's, say where the tool is on the part
  // apart from their words.
  const bool rotary = path.kinematics.rotary() || !path.frames.empty();
  std::string out = rotary ? "line,kind,x,y,z,a_deg,b_deg,c_deg,tip_x,tip_y,tip_z,axis_i,axis_j,"
                             "axis_k,cx,cy,cz,plane,turns,feed_mm_min,minutes\n"
                           : "line,kind,x,y,z,cx,cy,cz,plane,turns,feed_mm_min\n";
  char buf[256];
  // A value with six decimals and its comma; one that rounds to zero is written 0.000000,
  // whatever its sign (a joint at -1e-13 after a read-back).
  auto add = [&](double v) {
    std::snprintf(buf, sizeof buf, "%.6f,", v);
    out += std::string_view(buf) == "-0.000000," ? "0.000000," : buf;
  };
  auto row = [&](const Move& m, const Eigen::Vector3d& p) {
    out += std::to_string(m.line) + "," + moveKindName(m.kind) + ",";
    for (int a = 0; a < 3; ++a)
      add(p[a]);
    if (rotary) {
      for (int a = 0; a < 3; ++a)
        add(m.rotaryEnd[a]);
      const ToolPose pose = movePose(m, path.kinematics, path.frameOf(m), p, m.rotaryEnd);
      for (int a = 0; a < 3; ++a)
        add(pose.tip[a]);
      for (int a = 0; a < 3; ++a)
        add(pose.axis[a]);
    }
    if (m.kind == MoveKind::Arc) {
      for (int a = 0; a < 3; ++a)
        add(m.center[a]);
      out += std::string(planeName(m.plane)) + "," + std::to_string(m.turns) + ",";
    } else {
      out += ",,,,,";
    }
    if (m.kind != MoveKind::Rapid) {
      std::snprintf(buf, sizeof buf, "%.6g", m.feed);
      out += buf;
    }
    if (rotary) {
      out += ',';
      if (m.feedMode == FeedMode::InverseTime && m.minutes > 0.0) {
        std::snprintf(buf, sizeof buf, "%.6g", m.minutes);
        out += buf;
      }
    }
    out += '\n';
  };
  for (const Move& m : path.moves) {
    if (m.kind == MoveKind::Spline) {
      for (const Eigen::Vector3d& p : m.points)
        row(m, p);
    } else {
      row(m, m.end);
    }
  }
  return out;
}

}  // namespace engage
