#include "engine/gcode/GcodeWriter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace engage {
namespace {

constexpr double kInch = 25.4;
constexpr double kTwoPi = 6.28318530717958647692;

/// A number with at most `decimals` decimals, trailing zeros removed ("12.5", "-3", "0").
std::string fmt(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0')
      s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

double unitOf(const Move& m) {
  return m.inch ? kInch : 1.0;
}
/// Coordinate decimals: 1e-7 mm, or 1e-8 in (2.5e-7 mm), far below the 1e-6 mm read-back
/// tolerance of a split point.
int coordinateDecimals(const Move& m) {
  return m.inch ? 8 : 7;
}

/// The F word value for `feed` (mm/min) on a piece of `length` mm of move m.
std::string fWord(const Move& m, double feed, double length) {
  switch (m.feedMode) {
    case FeedMode::InverseTime:
      return "F" + fmt(feed / length, 6);  // 1/min
    case FeedMode::UnitsPerRevolution:
      return "F" + fmt(feed / (unitOf(m) * std::abs(m.spindleRpm)), 6);
    case FeedMode::UnitsPerMinute:
      break;
  }
  return "F" + fmt(feed / unitOf(m), m.inch ? 3 : 2);
}

/// The F word of piece p of move m, the share `fraction` of the move: its feed, or where it
/// carries a scale, the move's own F scaled (G93: 1 / the piece's duration in minutes).
std::string pieceFWord(const Move& m, const FeedPiece& p, double fraction) {
  if (!(p.scale > 0.0)) return fWord(m, p.feed, moveLength(m) * fraction);
  if (m.feedMode == FeedMode::InverseTime) return "F" + fmt(p.scale / (m.minutes * fraction), 6);
  return fWord(m, m.feed * p.scale, moveLength(m) * fraction);
}

/// The line with the words of `remove` taken out (with the blanks after them) and `insert`
/// (space-separated words) put where the first removed word was, or after the last word
/// when nothing is removed.
std::string editLine(const std::string& text, const SourceBlock& block, const std::string& remove,
                     const std::string& insert) {
  const int n = static_cast<int>(text.size());
  std::vector<bool> drop(static_cast<std::size_t>(n), false);
  int insertAt = -1;
  int lastWordEnd = 0;
  for (const WordSpan& w : block.words) {
    lastWordEnd = std::max(lastWordEnd, w.end);
    if (remove.find(w.letter) == std::string::npos) continue;
    if (insertAt < 0) insertAt = w.begin;
    int e = w.end;
    while (e < n &&
           (text[static_cast<std::size_t>(e)] == ' ' || text[static_cast<std::size_t>(e)] == '\t'))
      ++e;
    for (int i = w.begin; i < e; ++i)
      drop[static_cast<std::size_t>(i)] = true;
  }
  const bool replacing = insertAt >= 0;
  if (!replacing) insertAt = lastWordEnd;
  std::string out;
  for (int i = 0; i <= n; ++i) {
    if (i == insertAt) {
      if (!replacing && !out.empty()) out += ' ';
      out += insert;
      const bool more = i < n && !(replacing ? false : text[static_cast<std::size_t>(i)] == ' ');
      if (replacing || more) out += ' ';
    }
    if (i < n && !drop[static_cast<std::size_t>(i)]) out += text[static_cast<std::size_t>(i)];
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == '\t'))
    out.pop_back();
  return out;
}

/// Writes pieces of one move as text, tracking the position as the program will read it
/// back (rounded), so that incremental words and relative centres add up exactly.
class PieceWriter {
 public:
  PieceWriter(const Move& m, const Toolpath& path)
      : m_(m), path_(path), u_(unitOf(m)), d_(coordinateDecimals(m)) {
    emitted_ = program(m.start);
    emittedRotary_ = m.rotaryStart;
  }

  /// Words (without F) for the piece from the current position to fraction `t`.
  std::string words(double t0, double t1, bool last) {
    const Eigen::Vector3d endMachine = last ? m_.end : pointAt(m_, t1);
    const Eigen::Vector3d end = rounded(program(endMachine));
    std::string w;
    static const char kAxis[3] = {'X', 'Y', 'Z'};
    const PlaneAxes ax = planeAxes(m_.plane);
    for (int a = 0; a < 3; ++a) {
      const bool inPlane = m_.kind == MoveKind::Arc && (a == ax.a || a == ax.b);
      const double delta = end[a] - emitted_[a];
      if (std::abs(delta) < 0.5 * std::pow(10.0, -d_) && !inPlane) continue;
      w += (w.empty() ? "" : " ") + std::string(1, kAxis[a]) +
           fmt(m_.incremental ? delta : end[a], d_);
    }
    // The rotary axes the move turns, degrees, interpolated with X, Y, Z as the move is; under
    // G43.5 the tool's axis they give, in the program's frame.
    static const char kRotary[3] = {'A', 'B', 'C'};
    if (m_.axisVector && turnsRotary(m_)) {
      const Eigen::Vector3d abc =
          last ? m_.rotaryEnd
               : Eigen::Vector3d(m_.rotaryStart + t1 * (m_.rotaryEnd - m_.rotaryStart));
      Eigen::Vector3d axis = path_.kinematics.axis(abc);
      if (const FeatureFrame* f = path_.frameOf(m_)) axis = f->turn.transpose() * axis;
      for (int a = 0; a < 3; ++a)
        w += (w.empty() ? "" : " ") + std::string(1, "IJK"[a]) + fmt(axis[a], kAxisDecimals);
    }
    for (int a = 0; a < 3 && !m_.axisVector; ++a) {
      if (m_.rotaryStart[a] == m_.rotaryEnd[a]) continue;
      const double at = std::stod(fmt(
          last ? m_.rotaryEnd[a] : m_.rotaryStart[a] + t1 * (m_.rotaryEnd[a] - m_.rotaryStart[a]),
          kRotaryDecimals));
      w += (w.empty() ? "" : " ") + std::string(1, kRotary[a]) +
           fmt(m_.incremental ? at - emittedRotary_[a] : at, kRotaryDecimals);
      emittedRotary_[a] = at;
    }
    if (m_.kind == MoveKind::Arc) {
      const Eigen::Vector3d c = program(m_.center);
      const double ca = m_.absoluteArcCenters ? c[ax.a] : c[ax.a] - emitted_[ax.a];
      const double cb = m_.absoluteArcCenters ? c[ax.b] : c[ax.b] - emitted_[ax.b];
      w += " " + std::string(1, ax.ia) + fmt(ca, d_) + " " + std::string(1, ax.ib) + fmt(cb, d_);
      const double sweep = std::abs(arcSweep(m_)) * (t1 - t0);
      const int turns = std::max(1, static_cast<int>(std::ceil(sweep / kTwoPi - 1e-9)));
      if (turns > 1) w += " P" + std::to_string(turns);
    }
    emitted_ = end;
    return w;
  }

 private:
  Eigen::Vector3d program(const Eigen::Vector3d& machine) const {
    return (machine - m_.workOffset) / u_;
  }
  Eigen::Vector3d rounded(const Eigen::Vector3d& p) const {
    Eigen::Vector3d r;
    for (int a = 0; a < 3; ++a)
      r[a] = std::stod(fmt(p[a], d_));
    return r;
  }

  /// Degrees to 1e-7: 1.7e-7 mm of a point 100 mm from the axis.
  static constexpr int kRotaryDecimals = 7;
  /// A unit axis's components to 1e-9: 1e-7 mm of a point 100 mm along it.
  static constexpr int kAxisDecimals = 9;

  const Move& m_;
  const Toolpath& path_;
  double u_;
  int d_;
  Eigen::Vector3d emitted_;
  Eigen::Vector3d emittedRotary_;
};

std::string motionWord(const Move& m) {
  if (m.kind == MoveKind::Arc) return m.turns > 0 ? "G3" : "G2";
  return "G1";
}

bool sameFeed(double a, double b) {
  return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b));
}

/// Which moves the plan really changes (a single piece at the original feed changes
/// nothing); the plan checked against the path (pieces in order, positive feeds, no rapids,
/// no feed of spindle-synchronised or probing motion). Throws Error naming the move.
std::vector<bool> changedMoves(const Toolpath& path, const FeedPlan& plan) {
  std::vector<bool> changes(path.moves.size(), false);
  for (std::size_t i = 0; i < plan.size(); ++i) {
    const auto& pieces = plan[i];
    if (pieces.empty()) continue;
    const Move& m = path.moves[i];
    double previous = 0.0;
    for (const FeedPiece& p : pieces) {
      if (!(p.until > previous && p.until <= 1.0 + 1e-12))
        throw Error("feed plan of move " + std::to_string(i + 1) + " (line " +
                    std::to_string(m.line) +
                    "): pieces must end at increasing fractions in (0, 1]");
      // (A scaled piece of a move whose tip stands still has no tip feed.)
      if (!(std::isfinite(p.feed) && (p.feed > 0.0 || p.scale > 0.0)) ||
          !(std::isfinite(p.scale) && p.scale >= 0.0))
        throw Error("feed plan of move " + std::to_string(i + 1) + " (line " +
                    std::to_string(m.line) + "): feeds must be positive");
      previous = p.until;
    }
    if (std::abs(pieces.back().until - 1.0) > 1e-9)
      throw Error("feed plan of move " + std::to_string(i + 1) + " (line " +
                  std::to_string(m.line) + "): the last piece must end at the move's end");
    if (m.kind == MoveKind::Rapid)
      throw Error("feed plan of move " + std::to_string(i + 1) + " (line " +
                  std::to_string(m.line) + "): a rapid has no feed");
    if (turnsRotary(m) != (pieces.front().scale > 0.0))
      throw Error("feed plan of move " + std::to_string(i + 1) + " (line " +
                  std::to_string(m.line) +
                  "): a move that turns rotary axes takes scaled pieces, others feeds");
    changes[i] = !(pieces.size() == 1 && (turnsRotary(m) ? sameFeed(pieces[0].scale, 1.0)
                                                         : sameFeed(pieces[0].feed, m.feed)));
    if (changes[i] && m.fixedFeed())
      throw Error(path.files[static_cast<std::size_t>(m.file)] + ":" + std::to_string(m.line) +
                  ": the feed of spindle-synchronised motion (G33, G33.1) or probing (G38.x) "
                  "is not the F word's; engage cannot change it");
  }
  return changes;
}

/// In-place editing needs execution in line order, once per line, all in the main file:
/// throws Error naming the line that runs again or the other file.
void refuseUnorderedLines(const Toolpath& path) {
  int lastLine = 0;
  for (const SourceBlock& b : path.blocks) {
    if (b.file != 0)
      throw Error("the program calls subroutines in other files (" +
                  path.files[static_cast<std::size_t>(b.file)] +
                  "): engage cannot re-feed it in place");
    if (b.line <= lastLine)
      throw Error(path.files[0] + ":" + std::to_string(b.line) +
                  ": this line runs again after line " + std::to_string(lastLine) +
                  " (a loop or subroutine): engage cannot re-feed such a program in place");
    lastLine = b.line;
  }
}

/// The lines of `source` (without their line endings).
std::vector<std::string> sourceLines(const std::string& source) {
  std::vector<std::string> lines;
  for (std::size_t start = 0; start < source.size();) {
    std::size_t end = source.find('\n', start);
    if (end == std::string::npos) end = source.size();
    std::string l = source.substr(start, end - start);
    if (!l.empty() && l.back() == '\r') l.pop_back();
    lines.push_back(l);
    start = end + 1;
  }
  return lines;
}

}  // namespace

std::string writeProgram(const std::string& source, const Toolpath& path, const FeedPlan& plan) {
  if (plan.size() != path.moves.size())
    throw Error("feed plan has " + std::to_string(plan.size()) + " entries for " +
                std::to_string(path.moves.size()) + " moves");

  const std::vector<bool> changes = changedMoves(path, plan);
  const bool anyChange = std::find(changes.begin(), changes.end(), true) != changes.end();
  if (!anyChange) return source;

  refuseUnorderedLines(path);
  std::vector<std::vector<std::size_t>> movesOfBlock(path.blocks.size());
  for (std::size_t i = 0; i < path.moves.size(); ++i)
    movesOfBlock[static_cast<std::size_t>(path.moves[i].block)].push_back(i);
  std::map<int, std::size_t> blockOfLine;
  for (std::size_t b = 0; b < path.blocks.size(); ++b)
    blockOfLine[path.blocks[b].line] = b;

  // Lines, keeping the file's line ending and its final newline (or lack of one).
  const std::string eol = source.find("\r\n") != std::string::npos ? "\r\n" : "\n";
  const std::vector<std::string> lines = sourceLines(source);
  const bool finalNewline = !source.empty() && source.back() == '\n';

  std::string out;
  bool dirty = false;  // the output's modal F may differ from the original's
  for (std::size_t li = 0; li < lines.size(); ++li) {
    const std::string& text = lines[li];
    const auto found = blockOfLine.find(static_cast<int>(li + 1));
    std::vector<std::string> emitted{text};
    if (found != blockOfLine.end()) {
      const SourceBlock& block = path.blocks[found->second];
      std::vector<std::size_t> feedMoves;
      for (std::size_t i : movesOfBlock[found->second])
        if (path.moves[i].kind != MoveKind::Rapid) feedMoves.push_back(i);
      bool changed = false;
      for (std::size_t i : feedMoves)
        changed = changed || changes[i];
      // G33's feed is K x S, not the modal F: its line keeps no F word of ours, and the
      // original F is restored on the next line that feeds by F.
      const bool spindleFeed =
          !feedMoves.empty() && path.moves[feedMoves.front()].feedSource == FeedSource::Spindle;
      const Move* lead = feedMoves.empty() ? nullptr : &path.moves[feedMoves.front()];
      // An inverse-time line carries its own F: no earlier edit leaks into it. (An edited one
      // leaks into the next units-per-minute line that gives none, as the modal F.)
      const bool leak = dirty && lead && lead->feedMode != FeedMode::InverseTime;
      if (lead && !spindleFeed && (changed || leak)) {
        const Move& first = *lead;
        if (feedMoves.size() > 1 || first.kind == MoveKind::Spline) {
          // Canned cycles and splines: one F for the line.
          double feed =
              changes[feedMoves.front()] ? plan[feedMoves.front()].front().feed : first.feed;
          for (std::size_t i : feedMoves) {
            const double f = changes[i] ? plan[i].front().feed : path.moves[i].feed;
            if ((changes[i] && plan[i].size() > 1) || !sameFeed(f, feed))
              throw Error(path.files[0] + ":" + std::to_string(block.line) +
                          ": a canned cycle or spline line takes one feed; the plan splits it");
          }
          emitted = {editLine(text, block, "F", fWord(first, feed, moveLength(first)))};
          dirty = changed;
        } else if (!changes[feedMoves.front()] || plan[feedMoves.front()].size() == 1) {
          const FeedPiece piece = changes[feedMoves.front()] ? plan[feedMoves.front()].front()
                                                             : FeedPiece{1.0, first.feed, 0.0};
          emitted = {editLine(text, block, "F", pieceFWord(first, piece, 1.0))};
          dirty = changes[feedMoves.front()];
        } else {
          // Split a line or an arc where its feed changes.
          const auto& pieces = plan[feedMoves.front()];
          PieceWriter writer(first, path);
          emitted.clear();
          double t0 = 0.0;
          for (std::size_t k = 0; k < pieces.size(); ++k) {
            const bool last = k + 1 == pieces.size();
            const double t1 = last ? 1.0 : pieces[k].until;
            const std::string words =
                writer.words(t0, t1, last) + " " + pieceFWord(first, pieces[k], t1 - t0);
            if (k == 0)
              emitted.push_back(editLine(text, block, "XYZABCIJKRPF@^", words));
            else
              emitted.push_back(motionWord(first) + " " + words);
            t0 = t1;
          }
          dirty = true;
        }
      }
    }
    for (std::size_t k = 0; k < emitted.size(); ++k) {
      out += emitted[k];
      if (li + 1 < lines.size() || k + 1 < emitted.size() || finalNewline) out += eol;
    }
  }
  return out;
}

}  // namespace engage
