#pragma once
/// \file Numbers.h
/// The constants and the number formatting that every library shares, in one place.

#include <string>

namespace engage {

/// pi.
constexpr double kPi = 3.14159265358979323846;
/// Degrees per radian.
constexpr double kDegPerRad = 180.0 / kPi;

/// `value` as printf's "%.6g" prints it, without the locale: "0" for zero (never "-0"), "nan"
/// for NaN, "inf" and "-inf". The one formatter of numbers in messages and text outputs.
std::string formatNumber(double value);

}  // namespace engage
