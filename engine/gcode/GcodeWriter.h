#pragma once
/// \file GcodeWriter.h
/// Writes a program back with new feeds, changing nothing else: comments, non-motion lines,
/// units and distance modes stay as they were. A move whose feed changes along its length is
/// split where the feed changes: lines into lines, arcs and helices into sub-arcs (I/J/K
/// centres in the move's own arc-centre mode, P turns where a piece exceeds a full turn),
/// with the rotary axes' A/B/C words at the split points where the move turns them.
/// Where an edited feed would leak into later lines through the modal F, the next feed move
/// gets its original F back explicitly.
///
/// Lines that ran more than once (loops, subroutines) and moves from subroutine files cannot
/// be edited in place: asking for it throws Error naming the line. Canned cycles and splines
/// take one new feed per line (no splitting).

#include "cutters/Error.h"
#include "engine/gcode/Toolpath.h"

#include <string>
#include <vector>

namespace engage {

/// One piece of a move's new feed: from the previous piece's end up to fraction `until` of
/// the move (0 < until <= 1; the fraction of its words' interpolation, which for a move that
/// turns rotary axes is not the fraction of the tip's travel), at `feed` mm/min.
///
/// A move that turns rotary axes has no one tip speed its F word sets: its pieces carry
/// `scale`, the rate of all its axes over the programmed one (`feed` is then the lowest tip
/// speed on the part the piece runs at, for reading only). The piece's F word is the move's
/// own times `scale`; under inverse time (G93), 1 / the piece's duration.
struct FeedPiece {
  double until = 1.0;
  double feed = 0.0;
  double scale = 0.0;  ///< > 0: the piece's rate over the programmed one (see above)
};

/// New feeds: one entry per move of the tool path; an empty entry keeps the move as it was.
using FeedPlan = std::vector<std::vector<FeedPiece>>;

/// The program text (as read: `source` is the main file's content) with `plan` applied.
/// Throws Error for a plan that does not fit the tool path or cannot be written in place.
std::string writeProgram(const std::string& source, const Toolpath& path, const FeedPlan& plan);

}  // namespace engage
