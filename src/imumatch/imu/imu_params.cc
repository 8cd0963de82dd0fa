#include "imumatch/imu/imu_params.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "imumatch/core/error.h"

namespace imumatch {

void ImuParams::Check() const {
  // Upper bounds 1000x a consumer MEMS part's figures: beyond them the covariances that
  // propagate from these values are no longer meaningful (and can overflow).
  for (double v : {gyro_noise_density, gyro_random_walk, accel_noise_density, accel_random_walk}) {
    IMUMATCH_CHECK(std::isfinite(v) && v >= 0.0 && v <= 10.0,
                   "IMU noise parameters must be in [0, 10] (Kalibr units), got " << v);
  }
  IMUMATCH_CHECK(std::isfinite(rate_hz) && rate_hz > 0.0 && rate_hz <= 1e5,
                 "rate_hz must be in (0, 1e5], got " << rate_hz);
  IMUMATCH_CHECK(gravity_in_world.allFinite() && gravity_in_world.norm() <= 100.0,
                 "gravity must be finite and at most 100 m/s^2");
}

ImuParams ImuParams::EurocAdis16448() { return ImuParams{}; }

ImuParams ImuParams::ConsumerMems() {
  // Typical smartphone-grade MEMS IMU (e.g. BMI160/MPU-6000 data sheets, rounded up).
  ImuParams p;
  p.gyro_noise_density = 2.4e-3;  // ~0.14 deg/s/sqrt(Hz)
  p.gyro_random_walk = 2.0e-4;
  p.accel_noise_density = 1.9e-2;  // ~190 ug/sqrt(Hz)
  p.accel_random_walk = 2.0e-3;
  p.rate_hz = 200.0;
  return p;
}

ImuParams ImuParams::Ideal() {
  ImuParams p;
  p.gyro_noise_density = p.gyro_random_walk = p.accel_noise_density = p.accel_random_walk = 0.0;
  return p;
}

ImuParams ImuParams::FromName(std::string_view name) {
  std::string n(name);
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return std::tolower(c); });
  if (n == "euroc" || n == "adis16448") return EurocAdis16448();
  if (n == "mems" || n == "consumer") return ConsumerMems();
  if (n == "ideal" || n == "none") return Ideal();
  throw InvalidArgument("unknown IMU model '" + std::string(name) +
                        "' (expected one of: euroc, adis16448, mems, ideal)");
}

}  // namespace imumatch
