#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

namespace imumatch {

// Timestamps are int64_t nanoseconds everywhere (named t_ns). Readers convert once, exactly.
constexpr int64_t kNsPerSecond = 1'000'000'000;

// Parses a decimal number of seconds ("1305031102.175304", "12", "-0.5", "1.5e3") into nanoseconds
// without going through a double when the text is plain decimal, so 19-digit timestamps stay exact.
// Digits beyond nanoseconds are rounded half away from zero. Throws InvalidArgument on bad text.
int64_t ParseSecondsToNs(std::string_view text);

// Parses an integer nanosecond timestamp ("1403715273262142976"). Throws InvalidArgument.
int64_t ParseNs(std::string_view text);

inline double NsToSeconds(int64_t t_ns) { return static_cast<double>(t_ns) * 1e-9; }
int64_t SecondsToNs(double seconds);  // Rounds to the nearest nanosecond.

// "1305031102.175304000": seconds with nine decimals, exact.
std::string FormatNsAsSeconds(int64_t t_ns);

// Wall time of a stage.
using SteadyClock = std::chrono::steady_clock;
inline double MsSince(SteadyClock::time_point t0) {
  return std::chrono::duration<double, std::milli>(SteadyClock::now() - t0).count();
}

}  // namespace imumatch
