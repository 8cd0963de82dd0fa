#pragma once

#include <cstdint>
#include <vector>

#include "imumatch/core/rigid3.h"
#include "imumatch/core/types.h"
#include "imumatch/imu/imu_params.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {

struct ImuSimulatorOptions {
  double rate_hz = 200.0;
  bool add_noise = true;      // white noise: density / sqrt(dt) per sample
  bool add_bias_walk = true;  // bias random walk: random_walk * sqrt(dt) per sample
  ImuBias initial_bias;       // constant offset at the start
  uint64_t seed = 42;
  // Pose of the IMU in the trajectory's body frame. The trajectory describes the body; the IMU
  // measures its own motion, so a lever arm adds centripetal and tangential terms (the angular
  // acceleration comes from a central difference of the angular velocity, error ~1e-10).
  Rigid3d body_from_imu;
  int64_t t0_ns = 0;  // timestamp of trajectory time 0
  void Check() const;
};

// Samples an IMU from a trajectory: gyro = angular velocity of the IMU in its frame + bias + noise;
// accel = R_world_from_imu^T (a_imu_in_world - gravity) + bias + noise. Samples at
// t = StartTime() + k/rate up to EndTime().
std::vector<ImuSample> SimulateImu(const Trajectory& trajectory, const ImuParams& params,
                                   const ImuSimulatorOptions& options);

}  // namespace imumatch
