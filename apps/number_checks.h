#pragma once

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

// CLI11 validators for the commands' numeric options: the value must be a finite number inside an
// interval. A value outside is a usage error naming the option and the interval
// ("--ratio: 0 is not in (0, 1]"), said before any file is read. An option left at its default
// is not checked, so a default outside the interval can keep meaning "automatic".
namespace imumatch::apps {

inline constexpr double kNoBound = std::numeric_limits<double>::infinity();

// lo / hi may be -kNoBound / kNoBound; *_open says whether that end is excluded.
inline CLI::Validator NumberIn(double lo, bool lo_open, double hi, bool hi_open) {
  std::ostringstream interval;
  interval << (lo_open ? "(" : "[");
  if (std::isinf(lo)) {
    interval << "-inf";
  } else {
    interval << lo;
  }
  interval << ", ";
  if (std::isinf(hi)) {
    interval << "inf";
  } else {
    interval << hi;
  }
  interval << (hi_open ? ")" : "]");
  const std::string text = interval.str();
  return CLI::Validator(
      [lo, lo_open, hi, hi_open, text](std::string& value) -> std::string {
        const char* begin = value.c_str();
        char* end = nullptr;
        errno = 0;
        const double v = std::strtod(begin, &end);
        if (end == begin || *end != '\0') return "'" + value + "' is not a number";
        if (!std::isfinite(v) || errno == ERANGE) return value + " is not a finite number";
        const bool above = lo_open ? v > lo : v >= lo;
        const bool below = hi_open ? v < hi : v <= hi;
        if (!above || !below) return value + " is not in " + text;
        return std::string();
      },
      "NUMBER in " + text);
}

// (0, inf): a length, a duration, a rate.
inline CLI::Validator PositiveFinite() { return NumberIn(0.0, true, kNoBound, true); }
// [0, inf).
inline CLI::Validator NonNegativeFinite() { return NumberIn(0.0, false, kNoBound, true); }

}  // namespace imumatch::apps
