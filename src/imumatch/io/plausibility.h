#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "imumatch/camera/pinhole_camera.h"

// Plausibility bounds on recorded data, stated once. A value outside them is bad *data*: the
// readers throw InputError naming the file and line (exit code 3 in the CLI), never an
// InvalidArgument (a bad option). They also bound the work and memory that input can ask for.

namespace imumatch::plausibility {

// Timestamps: |t| <= 4e9 s (until the year 2096 as Unix time), so that any difference of two
// timestamps fits in int64 nanoseconds.
inline constexpr int64_t kMaxAbsTimestampNs = 4'000'000'000'000'000'000;
// Consecutive rows of one file (IMU, trajectory, image list) at most one hour apart: a longer
// step is a typo or a clock jump, and would make the spline fit and the IMU simulation of the
// span unbounded.
inline constexpr int64_t kMaxTimestampStepNs = 3'600'000'000'000;
// Inertial measurements: far above any MEMS or tactical IMU's range (ADIS16448: 17.5 rad/s,
// 176 m/s^2), far below nonsense.
inline constexpr double kMaxGyroRadS = 100.0;
inline constexpr double kMaxAccelMs2 = 1000.0;
// Positions (m) and velocities (m/s) of ground truth: a 1000 km world, under Mach 3.
inline constexpr double kMaxPositionM = 1e6;
inline constexpr double kMaxVelocityMs = 1000.0;
// Images: at most 32768 pixels a side and 2^27 (134 M) pixels, checked from the file header
// before decoding.
inline constexpr int kMaxImageSide = PinholeCamera::kMaxSide;
inline constexpr int64_t kMaxImagePixels = int64_t{1} << 27;

void CheckTimestamp(int64_t t_ns, const std::string& file, int line);
void CheckTimestampStep(int64_t previous_t_ns, int previous_line, int64_t t_ns,
                        const std::string& file, int line);
void CheckImu(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2,
              const std::string& file, int line);
void CheckAccel(const Eigen::Vector3d& accel_m_s2, const std::string& file, int line);
void CheckPosition(const Eigen::Vector3d& p_m, const std::string& file, int line);
void CheckVelocity(const Eigen::Vector3d& v_m_s, const std::string& file, int line);
void CheckImageSize(int64_t width, int64_t height, const std::string& file);

}  // namespace imumatch::plausibility
