#pragma once

#include <string>
#include <string_view>

#include <Eigen/Core>

namespace imumatch {

// Everything that describes an IMU's noise, in one place (GTSAM's PreintegrationParams style).
// Continuous-time densities, as in Kalibr / EuRoC sensor.yaml. A discrete sample at rate f has
// white-noise standard deviation density * sqrt(f).
struct ImuParams {
  double gyro_noise_density = 1.6968e-4;  // rad/s/sqrt(Hz)   ("gyroscope_noise_density")
  double gyro_random_walk = 1.9393e-5;    // rad/s^2/sqrt(Hz) ("gyroscope_random_walk")
  double accel_noise_density = 2.0e-3;    // m/s^2/sqrt(Hz)   ("accelerometer_noise_density")
  double accel_random_walk = 3.0e-3;      // m/s^3/sqrt(Hz)   ("accelerometer_random_walk")
  double rate_hz = 200.0;                 // nominal sample rate
  // Gravity in the world frame (z up). The accelerometer measures specific force
  // f = R_world_from_imu^T * (a_world - gravity_in_world).
  Eigen::Vector3d gravity_in_world = Eigen::Vector3d(0.0, 0.0, -9.81);

  void Check() const;

  // Named models: "euroc" / "adis16448" (the EuRoC ADIS16448 figures above), "mems" (a consumer
  // MEMS phone-grade IMU, about 10x noisier), "ideal" (no noise, no bias drift).
  static ImuParams EurocAdis16448();
  static ImuParams ConsumerMems();
  static ImuParams Ideal();
  static ImuParams FromName(std::string_view name);  // throws InvalidArgument
};

// Gyroscope and accelerometer biases, in the IMU frame.
struct ImuBias {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // rad/s
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  // m/s^2
};

}  // namespace imumatch
