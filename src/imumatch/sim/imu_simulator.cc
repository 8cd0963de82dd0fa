#include "imumatch/sim/imu_simulator.h"

#include <cmath>
#include <random>

#include "imumatch/core/error.h"

namespace imumatch {

void ImuSimulatorOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= 1e5, "rate_hz=" << rate_hz);
  IMUMATCH_CHECK(initial_bias.gyro.allFinite() && initial_bias.accel.allFinite(),
                 "initial bias is not finite");
}

std::vector<ImuSample> SimulateImu(const Trajectory& trajectory, const ImuParams& params,
                                   const ImuSimulatorOptions& options) {
  params.Check();
  options.Check();
  const double t_start = trajectory.StartTime();
  const double t_end = trajectory.EndTime();
  IMUMATCH_CHECK(t_end > t_start, "trajectory has an empty time span");
  const int64_t period_ns = static_cast<int64_t>(std::llround(1e9 / options.rate_hz));
  const double dt = static_cast<double>(period_ns) * 1e-9;
  const int64_t start_ns = static_cast<int64_t>(std::llround(t_start * 1e9));
  const int64_t n =
      static_cast<int64_t>(std::floor((t_end - t_start) * 1e9 / period_ns + 1e-9)) + 1;

  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto gaussian3 = [&]() { return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)); };
  const double gyro_sigma = params.gyro_noise_density / std::sqrt(dt);
  const double accel_sigma = params.accel_noise_density / std::sqrt(dt);
  const double gyro_walk = params.gyro_random_walk * std::sqrt(dt);
  const double accel_walk = params.accel_random_walk * std::sqrt(dt);

  const Eigen::Quaterniond body_r_imu = options.body_from_imu.rotation;
  const Eigen::Vector3d lever_in_body = options.body_from_imu.translation;
  const bool has_lever = lever_in_body.squaredNorm() > 0.0;
  ImuBias bias = options.initial_bias;

  std::vector<ImuSample> out;
  out.reserve(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) {
    const int64_t rel_ns = start_ns + k * period_ns;
    const double t = static_cast<double>(rel_ns) * 1e-9;
    const Rigid3d world_from_body = trajectory.WorldFromBody(t);
    const Eigen::Vector3d w_body = trajectory.AngularVelocityInBody(t);
    Eigen::Vector3d a_imu_world = trajectory.AccelerationInWorld(t);
    if (has_lever) {
      // a_imu = a_body + R (alpha x l + w x (w x l)); alpha by a central difference (h = 1e-5 s).
      const double h = 1e-5;
      const Eigen::Vector3d alpha =
          (trajectory.AngularVelocityInBody(t + h) - trajectory.AngularVelocityInBody(t - h)) /
          (2 * h);
      a_imu_world += world_from_body.rotation *
                     (alpha.cross(lever_in_body) + w_body.cross(w_body.cross(lever_in_body)));
    }
    const Eigen::Quaterniond world_r_imu = world_from_body.rotation * body_r_imu;
    ImuSample s;
    s.t_ns = options.t0_ns + rel_ns;
    s.gyro_rad_s = body_r_imu.conjugate() * w_body + bias.gyro;
    s.accel_m_s2 = world_r_imu.conjugate() * (a_imu_world - params.gravity_in_world) + bias.accel;
    if (options.add_noise) {
      s.gyro_rad_s += gyro_sigma * gaussian3();
      s.accel_m_s2 += accel_sigma * gaussian3();
    }
    if (options.add_bias_walk) {
      bias.gyro += gyro_walk * gaussian3();
      bias.accel += accel_walk * gaussian3();
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace imumatch
