#include "cutters/Numbers.h"

#include <charconv>
#include <cmath>
#include <system_error>

namespace engage {

std::string formatNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (value == 0.0) return "0";  // and not "-0"
  // The standard defines to_chars' general format with a precision as printf's %.6g; this
  // avoids the locale and the format string, which a long run's steps.csv pays for.
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, 6);
  return ec == std::errc() ? std::string(buf, end) : std::string("nan");
}

}  // namespace engage
