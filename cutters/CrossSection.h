#pragma once
/// \file CrossSection.h
/// The cutting cross-section y_G of a straight pass (paper §3, Eq 1-5 and 7-11).
///
/// Set-up: the cutter's tip is at depth d below the top of the stock; the previous pass ran at
/// the same depth, parallel, offset by the stepover s away from the uncut stock. In the plane
/// normal to the feed direction, x is measured from the current cutter axis toward the uncut
/// stock and z upward from the tip. At height z the current cutter covers [-W(z), W(z)] and the
/// previous pass covered [-s - W(z), -s + W(z)], so the removed width is
///     w(z) = min(2 W(z), s)   on   x in [W(z) - w(z), W(z)].
/// (Material beyond the previous pass, x < -s - W, was cleared by earlier passes.)
///
/// Two forms:
///  - exactCrossSection integrates w(z) over [0, d] in closed form, piece by piece of the
///    profile (lines and the corner arc), giving the area and both centroid coordinates for
///    every APT cutter, any stepover and any depth.
///  - paperCrossSection evaluates Eq 2-3 literally and says whether they apply. They are exact
///    when the bottom is flat (delta = 0) and either s <= 2e with 2W >= s over the depth, or
///    2e < s <= 2r with the cusp of the corner arc (height r_tc (1 - sin phi)) below d and on
///    the arc (phi >= beta). They are wrong for conical bottoms (chamfer, delta > 0), for a
///    depth below the cusp height, for s > 2r (arccos undefined) and where the stepover meets
///    a taper side instead of the corner arc.

#include "cutters/AptCutter.h"

#include <string>

namespace engage {

/// Exact removed cross-section of a straight pass. Lengths mm, area mm^2.
struct CrossSection {
  double area = 0.0;       ///< y_G, mm^2
  double centroidX = 0.0;  ///< mm from the cutter axis toward the uncut stock
  double centroidZ = 0.0;  ///< mm above the tip
  /// Height above the tip of the ridge left between this pass and the previous one, mm:
  /// below it the passes do not overlap (w = 2W). 0 when the passes overlap down to the tip;
  /// equal to d when they do not overlap at all over the depth.
  double cuspHeight = 0.0;
};

/// Eq 2-3 as printed, with the verdict on whether they describe this case.
struct PaperCrossSection {
  double area = 0.0;     ///< Eq 2 or Eq 3, mm^2; NaN where the formula is undefined
  double phiRad = 0.0;   ///< phi = acos((s - 2e) / (2 r_tc)); NaN when s <= 2e or undefined
  bool applies = false;  ///< true when Eq 2-3 equal the exact area for this case
  std::string reason;    ///< why they do not apply (empty when they do)
};

/// Exact area and centroid of the removed cross-section for stepover s and depth d (mm).
/// Throws ParameterError when s or d is not positive and finite, or d exceeds the cutting
/// height h.
CrossSection exactCrossSection(const AptCutter& cutter, double stepover, double depth);

/// Eq 2-3 literally (r_tc, e and d of the cutter; beta and delta do not enter them).
/// Throws ParameterError as exactCrossSection.
PaperCrossSection paperCrossSection(const AptCutter& cutter, double stepover, double depth);

}  // namespace engage
