#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "imumatch/core/rigid3.h"
#include "imumatch/core/types.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_params.h"

namespace imumatch {

enum class IntegrationMode {
  // The seed method, for reproduction only: Euler angles summed (angles += gyro*dt), velocity
  // v += a*dt and displacement dr += v*dt + a*dt^2/2 with the raw accelerometer: no gravity
  // removal, no bias.
  kPaper,
  // Default: rotation on SO(3) with the exponential map (midpoint rule), bias subtracted, gravity
  // removed, endpoints interpolated at the frame timestamps, noise covariance propagated.
  kSo3,
};
IntegrationMode ParseIntegrationMode(std::string_view name);  // "paper" | "so3"
const char* ToString(IntegrationMode mode);

// Preintegrated IMU measurements between t0 and t1 (Forster et al. 2017), in the IMU frame at t0
// ("i"), independent of the initial velocity and gravity:
//   R_j = R_i * delta_rotation
//   v_j = v_i + g*dt + R_i * delta_velocity
//   p_j = p_i + v_i*dt + g*dt^2/2 + R_i * delta_position
struct ImuPreintegration {
  int64_t t0_ns = 0;
  int64_t t1_ns = 0;
  Eigen::Quaterniond delta_rotation = Eigen::Quaterniond::Identity();  // imu_i_from_imu_j
  Eigen::Vector3d delta_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d delta_position = Eigen::Vector3d::Zero();
  // Covariance of [dtheta, dv, dp] (rotation error on the right: R_true = R * Exp(dtheta)) from the
  // white noise of the samples, plus the bias uncertainty given in the call.
  Eigen::Matrix<double, 9, 9> covariance = Eigen::Matrix<double, 9, 9>::Zero();
  double dt() const { return NsToSecondsDelta(); }

 private:
  double NsToSecondsDelta() const { return static_cast<double>(t1_ns - t0_ns) * 1e-9; }
};

// Integrates samples (as returned by ImuBuffer::Slice: first at t0, last at t1) with the given
// bias. bias_sigma_* are the 1-sigma uncertainties of the bias estimate (added to the covariance).
ImuPreintegration Preintegrate(const std::vector<ImuSample>& samples, const ImuBias& bias,
                               const ImuParams& params, double bias_sigma_gyro = 0.0,
                               double bias_sigma_accel = 0.0);

// Navigation state of the IMU in the world (z up, gravity = params.gravity_in_world).
struct NavState {
  int64_t t_ns = 0;
  Rigid3d world_from_imu;
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();
};

// Propagates a NavState through a preintegration (equations above).
NavState Propagate(const NavState& state_i, const ImuPreintegration& pim,
                   const Eigen::Vector3d& gravity_in_world);

// The seed method's "camera status solving" for one interval: Euler angles summed and the
// displacement dr = sum(v*dt + a*dt^2/2) with v += a*dt starting from initial_velocity_in_imu,
// raw accelerometer (gravity included), no bias. Returns imu_i_from_imu_j (rotation from the summed
// Euler angles, translation = the summed displacement) and the velocity at the end (in the IMU
// frame at t0, as the paper does not rotate it).
struct PaperIntegration {
  Rigid3d imu_i_from_imu_j;
  Eigen::Vector3d velocity_end = Eigen::Vector3d::Zero();
};
PaperIntegration IntegratePaper(const std::vector<ImuSample>& samples,
                                const Eigen::Vector3d& initial_velocity_in_imu);

// A still period tells the gyro bias (mean gyro) and the direction of gravity in the IMU frame
// (minus the mean specific force). Stillness is judged on the means of four consecutive blocks of
// the period, so zero-mean vibration (a drone's rotors) is accepted but real motion is not: throws
// InvalidArgument when a block's mean gyro differs from the overall mean by more than
// max_gyro_drift (rad/s) or its mean specific force by more than max_accel_drift (m/s^2), or when
// the period has fewer than 20 samples. A gap in the log (ImuBuffer::Gaps) ends the period early:
// the samples before it are used (end_ns says where the period ended).
struct StillInitialization {
  ImuBias bias;  // gyro bias estimated; accel bias zero (not observable)
  Eigen::Vector3d gravity_in_imu = Eigen::Vector3d::Zero();  // points down, norm = |g|
  Rigid3d world_from_imu;        // roll/pitch from gravity, yaw zero, origin zero
  double gyro_bias_sigma = 0.0;  // standard error of the gyro bias estimate (rad/s)
  int num_samples = 0;
  int64_t end_ns = 0;  // the period's end: t1_ns, or the start of the first gap before it
};
StillInitialization InitializeFromStill(const ImuBuffer& buffer, int64_t t0_ns, int64_t t1_ns,
                                        const ImuParams& params, double max_gyro_drift = 0.02,
                                        double max_accel_drift = 0.3);

}  // namespace imumatch
