#include "engine/run/MovesTable.h"

#include "engine/sim/ToolPoses.h"

#include <cstdio>

namespace engage {

std::string movesTable(const Toolpath& path) {
  // A rotary machine's moves, and a tilted work plane's, say where the tool is on the part
  // apart from their words.
  const bool rotary = path.kinematics.rotary() || !path.frames.empty();
  std::string out = rotary ? "line,kind,x,y,z,a_deg,b_deg,c_deg,tip_x,tip_y,tip_z,axis_i,axis_j,"
                             "axis_k,cx,cy,cz,plane,turns,feed_mm_min,minutes\n"
                           : "line,kind,x,y,z,cx,cy,cz,plane,turns,feed_mm_min\n";
  char buf[256];
  auto row = [&](const Move& m, const Eigen::Vector3d& p) {
    std::snprintf(buf, sizeof buf, "%d,%s,%.6f,%.6f,%.6f,", m.line, moveKindName(m.kind), p.x(),
                  p.y(), p.z());
    out += buf;
    if (rotary) {
      std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,", m.rotaryEnd.x(), m.rotaryEnd.y(),
                    m.rotaryEnd.z());
      out += buf;
      const ToolPose pose = movePose(m, path.kinematics, path.frameOf(m), p, m.rotaryEnd);
      std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,", pose.tip.x(), pose.tip.y(),
                    pose.tip.z(), pose.axis.x(), pose.axis.y(), pose.axis.z());
      out += buf;
    }
    if (m.kind == MoveKind::Arc) {
      std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%s,%d,", m.center.x(), m.center.y(),
                    m.center.z(), planeName(m.plane), m.turns);
      out += buf;
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
