#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "imumatch/core/types.h"

namespace imumatch {

struct ImuBufferOptions {
  // A gap between consecutive samples longer than this makes queries over it fail (OutOfRange).
  int64_t max_gap_ns = 50'000'000;  // 50 ms (10 samples at 200 Hz)
  void Check() const;
};

// A time-ordered IMU stream. Push() validates each sample; queries interpolate linearly between
// samples so any timestamp inside the buffered range can be asked for.
class ImuBuffer {
 public:
  explicit ImuBuffer(ImuBufferOptions options = {});

  // Appends a sample. Throws InputError(source, line, ...) for a timestamp not strictly after the
  // previous one (out of order or duplicate) or a non-finite value. source/line name where the
  // sample came from (a reader passes its file and line; 0 when unknown).
  void Push(const ImuSample& sample, const std::string& source = "imu", int line = 0);

  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }
  const std::vector<ImuSample>& samples() const { return samples_; }
  int64_t begin_ns() const;  // throws OutOfRange when empty
  int64_t end_ns() const;

  // Sample at t_ns by linear interpolation. Throws OutOfRange outside [begin, end] or inside a gap.
  ImuSample Interpolate(int64_t t_ns) const;

  // The samples covering [t0_ns, t1_ns]: interpolated samples exactly at t0 and t1 plus every
  // buffered sample strictly between. Throws OutOfRange when the interval is not covered, is empty
  // (t1 <= t0), or contains a gap longer than max_gap_ns.
  std::vector<ImuSample> Slice(int64_t t0_ns, int64_t t1_ns) const;

  // A stretch between consecutive samples longer than max_gap_ns: no query may cross it. line is
  // the source line of the sample after the gap (0 when the samples came without lines).
  struct Gap {
    int64_t begin_ns = 0, end_ns = 0;
    int line = 0;
  };
  std::vector<Gap> Gaps() const;
  // The end of the gap-free stretch from t0_ns towards t1_ns: t1_ns, or the start of the first
  // gap after t0_ns (a still period or an integration can use the samples up to it). Throws
  // OutOfRange when t0_ns is outside the buffered range or inside a gap.
  int64_t GapFreeEnd(int64_t t0_ns, int64_t t1_ns) const;
  // Where the samples came from (the source of the first Push), and "source:line: " for the
  // sample at index i when its line is known ("source: " otherwise); errors about the samples
  // start with it.
  const std::string& source() const { return source_; }
  std::string Where(size_t i) const;

  const ImuBufferOptions& options() const { return options_; }

 private:
  size_t UpperIndex(int64_t t_ns) const;  // first sample with t > t_ns
  bool GapBefore(size_t i) const;         // samples i - 1 and i are farther apart than max_gap_ns
  std::string GapMessage(size_t after) const;
  ImuBufferOptions options_;
  std::vector<ImuSample> samples_;
  std::vector<int> lines_;  // per sample, 0 when unknown
  std::string source_;
};

}  // namespace imumatch
