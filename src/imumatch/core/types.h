#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "imumatch/core/rigid3.h"

namespace imumatch {

// One IMU measurement in the IMU frame: angular rate (rad/s) and specific force (m/s^2, includes
// the reaction to gravity: a still IMU with z up reads about +9.81 on z).
struct ImuSample {
  int64_t t_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

// A timestamped pose: world_from_body at t_ns (TUM trajectory convention: camera-to-world).
struct StampedPose {
  int64_t t_ns = 0;
  Rigid3d world_from_body;
};
}  // namespace imumatch
