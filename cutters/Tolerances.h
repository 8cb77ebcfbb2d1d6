#pragma once
/// \file Tolerances.h
/// Named geometric tolerances of the cutter and cross-section code. Never compare computed
/// doubles with ==; compare against one of these.

namespace engage::tol {

/// Absolute length tolerance for consistency checks of cutter parameters, mm.
/// 1e-9 mm is far below any machining tolerance and well above double round-off for tools
/// up to a few metres.
inline constexpr double kLengthMm = 1e-9;

/// Relative tolerance for checking a user-supplied derived parameter (e, h_tc) against the
/// value implied by the others: 1e-6 accepts values typed with six significant digits.
inline constexpr double kParameterRelative = 1e-6;

/// Angle tolerance, radians (parallel/perpendicular decisions).
inline constexpr double kAngleRad = 1e-12;

}  // namespace engage::tol
