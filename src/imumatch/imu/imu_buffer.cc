#include "imumatch/imu/imu_buffer.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"

namespace imumatch {

void ImuBufferOptions::Check() const {
  IMUMATCH_CHECK(max_gap_ns > 0, "max_gap_ns=" << max_gap_ns);
}

ImuBuffer::ImuBuffer(ImuBufferOptions options) : options_(options) { options_.Check(); }

void ImuBuffer::Push(const ImuSample& sample, const std::string& source, int line) {
  if (!sample.gyro_rad_s.allFinite() || !sample.accel_m_s2.allFinite()) {
    throw InputError(source, line, "IMU sample has a non-finite value (NaN or inf)");
  }
  if (!samples_.empty() && sample.t_ns <= samples_.back().t_ns) {
    std::ostringstream msg;
    msg << (sample.t_ns == samples_.back().t_ns ? "duplicate" : "out-of-order") << " IMU timestamp "
        << FormatNsAsSeconds(sample.t_ns) << " s (previous sample at "
        << FormatNsAsSeconds(samples_.back().t_ns) << " s)";
    throw InputError(source, line, msg.str());
  }
  if (samples_.empty()) source_ = source;
  samples_.push_back(sample);
  lines_.push_back(line);
}

int64_t ImuBuffer::begin_ns() const {
  if (samples_.empty()) throw OutOfRange("IMU buffer is empty");
  return samples_.front().t_ns;
}

int64_t ImuBuffer::end_ns() const {
  if (samples_.empty()) throw OutOfRange("IMU buffer is empty");
  return samples_.back().t_ns;
}

size_t ImuBuffer::UpperIndex(int64_t t_ns) const {
  return static_cast<size_t>(
      std::upper_bound(samples_.begin(), samples_.end(), t_ns,
                       [](int64_t t, const ImuSample& s) { return t < s.t_ns; }) -
      samples_.begin());
}

namespace {
std::string Interval(int64_t a, int64_t b) {
  return "[" + FormatNsAsSeconds(a) + ", " + FormatNsAsSeconds(b) + "] s";
}
}  // namespace

ImuSample ImuBuffer::Interpolate(int64_t t_ns) const {
  if (samples_.empty() || t_ns < samples_.front().t_ns || t_ns > samples_.back().t_ns) {
    throw OutOfRange(
        "IMU query at " + FormatNsAsSeconds(t_ns) + " s is outside the buffered range" +
        (samples_.empty() ? std::string(" (empty)")
                          : " " + Interval(samples_.front().t_ns, samples_.back().t_ns)));
  }
  const size_t hi = UpperIndex(t_ns);
  if (hi == samples_.size()) return samples_.back();  // t_ns == end
  const ImuSample& b = samples_[hi];
  const ImuSample& a = samples_[hi - 1];
  if (a.t_ns == t_ns) return a;
  if (GapBefore(hi)) {
    throw OutOfRange(GapMessage(hi) + ": the IMU query at " + FormatNsAsSeconds(t_ns) +
                     " s falls in it");
  }
  const double alpha = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  ImuSample s;
  s.t_ns = t_ns;
  s.gyro_rad_s = (1.0 - alpha) * a.gyro_rad_s + alpha * b.gyro_rad_s;
  s.accel_m_s2 = (1.0 - alpha) * a.accel_m_s2 + alpha * b.accel_m_s2;
  return s;
}

std::vector<ImuSample> ImuBuffer::Slice(int64_t t0_ns, int64_t t1_ns) const {
  if (t1_ns <= t0_ns) {
    throw OutOfRange("IMU interval " + Interval(t0_ns, t1_ns) + " is empty or reversed");
  }
  std::vector<ImuSample> out;
  out.push_back(Interpolate(t0_ns));
  const ImuSample last = Interpolate(t1_ns);
  for (size_t i = UpperIndex(t0_ns); i < samples_.size() && samples_[i].t_ns < t1_ns; ++i) {
    // (The stretch from t0 to the first sample is not a gap: Interpolate(t0_ns) refused that.)
    if (GapBefore(i)) {
      throw OutOfRange(GapMessage(i) + " inside the requested interval " + Interval(t0_ns, t1_ns));
    }
    out.push_back(samples_[i]);
  }
  // Interpolate(t1_ns) has refused a t1 inside a gap, so the last stretch is not one.
  out.push_back(last);
  return out;
}

std::string ImuBuffer::Where(size_t i) const {
  if (source_.empty()) return "";
  if (i < lines_.size() && lines_[i] > 0) return source_ + ":" + std::to_string(lines_[i]) + ": ";
  return source_ + ": ";
}

bool ImuBuffer::GapBefore(size_t i) const {
  return i > 0 && samples_[i].t_ns - samples_[i - 1].t_ns > options_.max_gap_ns;
}

std::string ImuBuffer::GapMessage(size_t after) const {
  const int64_t a = samples_[after - 1].t_ns, b = samples_[after].t_ns;
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(1) << Where(after) << "IMU gap " << Interval(a, b) << " ("
      << static_cast<double>(b - a) * 1e-6 << " ms without a sample, more than the allowed "
      << static_cast<double>(options_.max_gap_ns) * 1e-6 << " ms)";
  return msg.str();
}

std::vector<ImuBuffer::Gap> ImuBuffer::Gaps() const {
  std::vector<Gap> gaps;
  for (size_t i = 1; i < samples_.size(); ++i) {
    if (GapBefore(i)) {
      gaps.push_back({samples_[i - 1].t_ns, samples_[i].t_ns, lines_[i]});
    }
  }
  return gaps;
}

int64_t ImuBuffer::GapFreeEnd(int64_t t0_ns, int64_t t1_ns) const {
  Interpolate(t0_ns);  // throws outside the range or inside a gap
  for (size_t i = UpperIndex(t0_ns); i < samples_.size() && samples_[i - 1].t_ns < t1_ns; ++i) {
    if (GapBefore(i)) {
      return std::min(t1_ns, samples_[i - 1].t_ns);
    }
  }
  return std::min(t1_ns, samples_.back().t_ns);
}

}  // namespace imumatch
