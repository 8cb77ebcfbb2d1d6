#include "engine/run/MovesTable.h"

#include <cstdio>

namespace engage {

std::string movesTable(const Toolpath& path) {
  const bool rotary = path.kinematics.rotary();
  std::string out = rotary ? "line,kind,x,y,z,a_deg,b_deg,c_deg,cx,cy,cz,plane,turns,feed_mm_min,"
                             "minutes\n"
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
