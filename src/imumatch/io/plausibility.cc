#include "imumatch/io/plausibility.h"

#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"

namespace imumatch::plausibility {
namespace {

std::string Vec(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return out.str();
}

void CheckNorm(const Eigen::Vector3d& v, double limit, const char* what, const char* unit,
               const std::string& file, int line) {
  if (!(v.allFinite() && v.norm() <= limit)) {
    std::ostringstream msg;
    msg << what << " " << Vec(v) << " " << unit << " is not plausible (|" << what
        << "| must be <= " << limit << " " << unit << ")";
    throw InputError(file, line, msg.str());
  }
}

}  // namespace

void CheckTimestamp(int64_t t_ns, const std::string& file, int line) {
  if (t_ns > kMaxAbsTimestampNs || t_ns < -kMaxAbsTimestampNs) {
    throw InputError(file, line,
                     "timestamp " + FormatNsAsSeconds(t_ns) +
                         " s is not plausible (|t| must be <= 4e9 s, the year 2096 as Unix time)");
  }
}

void CheckTimestampStep(int64_t previous_t_ns, int previous_line, int64_t t_ns,
                        const std::string& file, int line) {
  if (previous_line == 0) return;
  // Both are within +-4e9 s (CheckTimestamp), so the difference cannot overflow.
  if (t_ns - previous_t_ns > kMaxTimestampStepNs) {
    throw InputError(file, line,
                     "timestamp " + FormatNsAsSeconds(t_ns) + " s jumps " +
                         FormatNsAsSeconds(t_ns - previous_t_ns) + " s after line " +
                         std::to_string(previous_line) +
                         " (more than the 3600 s a recording may pause between rows)");
  }
}

void CheckImu(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2,
              const std::string& file, int line) {
  CheckNorm(gyro_rad_s, kMaxGyroRadS, "gyro", "rad/s", file, line);
  CheckAccel(accel_m_s2, file, line);
}

void CheckAccel(const Eigen::Vector3d& accel_m_s2, const std::string& file, int line) {
  CheckNorm(accel_m_s2, kMaxAccelMs2, "accel", "m/s^2", file, line);
}

void CheckPosition(const Eigen::Vector3d& p_m, const std::string& file, int line) {
  CheckNorm(p_m, kMaxPositionM, "position", "m", file, line);
}

void CheckVelocity(const Eigen::Vector3d& v_m_s, const std::string& file, int line) {
  CheckNorm(v_m_s, kMaxVelocityMs, "velocity", "m/s", file, line);
}

void CheckImageSize(int64_t width, int64_t height, const std::string& file) {
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide ||
      width * height > kMaxImagePixels) {
    throw InputError(file, "image size " + std::to_string(width) + "x" + std::to_string(height) +
                               " is not plausible (at most " + std::to_string(kMaxImageSide) +
                               " a side and " + std::to_string(kMaxImagePixels) + " pixels)");
  }
}

}  // namespace imumatch::plausibility
