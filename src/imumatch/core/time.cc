#include "imumatch/core/time.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

[[noreturn]] void Bad(std::string_view text, const char* what) {
  throw InvalidArgument("cannot parse '" + std::string(text) + "' as " + what);
}

}  // namespace

int64_t ParseSecondsToNs(std::string_view text) {
  const std::string_view s = Trim(text);
  if (s.empty()) Bad(text, "seconds");
  if (s.find_first_of("eEnN") != std::string_view::npos) {
    // Exponent form or nan/inf: go through strtod, then check.
    const std::string copy(s);
    char* end = nullptr;
    const double v = std::strtod(copy.c_str(), &end);
    if (end != copy.c_str() + copy.size() || !std::isfinite(v) || std::abs(v) > 9.2e9) {
      Bad(text, "seconds");
    }
    return SecondsToNs(v);
  }
  size_t i = 0;
  bool negative = false;
  if (s[i] == '+' || s[i] == '-') {
    negative = s[i] == '-';
    ++i;
  }
  int64_t whole = 0;
  size_t whole_digits = 0;
  for (; i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])); ++i, ++whole_digits) {
    if (whole > (std::numeric_limits<int64_t>::max() / kNsPerSecond - 9) / 10) Bad(text, "seconds");
    whole = whole * 10 + (s[i] - '0');
  }
  int64_t frac = 0;
  size_t frac_digits = 0;
  bool round_up = false;
  if (i < s.size() && s[i] == '.') {
    ++i;
    for (; i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])); ++i, ++frac_digits) {
      if (frac_digits < 9) {
        frac = frac * 10 + (s[i] - '0');
      } else if (frac_digits == 9) {
        round_up = s[i] >= '5';
      }
    }
  }
  if (i != s.size() || whole_digits + frac_digits == 0) Bad(text, "seconds");
  for (size_t d = frac_digits; d < 9; ++d) frac *= 10;
  int64_t ns = whole * kNsPerSecond + frac + (round_up ? 1 : 0);
  return negative ? -ns : ns;
}

int64_t ParseNs(std::string_view text) {
  const std::string_view s = Trim(text);
  if (s.empty()) Bad(text, "nanoseconds");
  size_t i = 0;
  bool negative = false;
  if (s[0] == '+' || s[0] == '-') {
    negative = s[0] == '-';
    i = 1;
  }
  if (i == s.size()) Bad(text, "nanoseconds");
  int64_t v = 0;
  for (; i < s.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(s[i]))) Bad(text, "nanoseconds");
    if (v > (std::numeric_limits<int64_t>::max() - 9) / 10) Bad(text, "nanoseconds");
    v = v * 10 + (s[i] - '0');
  }
  return negative ? -v : v;
}

int64_t SecondsToNs(double seconds) {
  if (!std::isfinite(seconds) || std::abs(seconds) > 9.2e9) {
    throw InvalidArgument("seconds value out of the int64 nanosecond range");
  }
  return static_cast<int64_t>(std::llround(seconds * 1e9));
}

std::string FormatNsAsSeconds(int64_t t_ns) {
  const bool negative = t_ns < 0;
  const uint64_t a =
      negative ? static_cast<uint64_t>(-(t_ns + 1)) + 1 : static_cast<uint64_t>(t_ns);
  std::string frac = std::to_string(a % kNsPerSecond);
  frac.insert(0, 9 - frac.size(), '0');
  return (negative ? "-" : "") + std::to_string(a / kNsPerSecond) + "." + frac;
}

}  // namespace imumatch
