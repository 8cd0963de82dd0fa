#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "imumatch/core/rigid3.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/imu/imu_params.h"

namespace imumatch {

// The camera's motion between two frames A (t_a) and B (t_b), as the predictor needs it.
//   p_in_cam_b = cam_b_from_cam_a * p_in_cam_a
// covariance: 6x6 of the perturbation [dtheta; dt] with
//   R_true = Exp(dtheta) * R,  t_true = t + dt   (both in camera B coordinates).
struct CameraMotion {
  int64_t t_a_ns = 0;
  int64_t t_b_ns = 0;
  Rigid3d cam_b_from_cam_a;
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

struct CameraMotionOptions {
  IntegrationMode mode = IntegrationMode::kSo3;
  // 1-sigma uncertainty of the velocity at t_a (m/s, per axis, world frame) and of the
  // roll/pitch (gravity direction, rad). Added to the propagated covariance.
  double velocity_sigma = 0.05;
  double attitude_sigma = 0.01;
  // 1-sigma of the bias estimates.
  double gyro_bias_sigma = 0.002;
  double accel_bias_sigma = 0.05;
  void Check() const;
};

// What the IMU pipeline knows at frame A besides the raw samples: the IMU's attitude in the world
// (only roll/pitch matter: gravity direction), its velocity, and the current bias estimate.
struct ImuStateAtFrame {
  Rigid3d world_from_imu;
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();
  ImuBias bias;
};

// Integrates the buffered IMU samples over [t_a, t_b] and expresses the motion in the camera frame
// through the extrinsics cam_from_imu. In kPaper mode the state's velocity (rotated into the IMU
// frame) seeds the paper's v, attitude and bias are ignored, and the covariance is left zero.
CameraMotion ComputeCameraMotion(const ImuBuffer& buffer, int64_t t_a_ns, int64_t t_b_ns,
                                 const ImuStateAtFrame& state_a, const ImuParams& params,
                                 const Rigid3d& cam_from_imu, const CameraMotionOptions& options);

// The perturbation [dtheta; dt] that takes `motion` to `other` in CameraMotion's convention:
// other.R = Exp(dtheta) motion.R, other.t = motion.t + dt.
Eigen::Matrix<double, 6, 1> MotionPerturbation(const Rigid3d& motion, const Rigid3d& other);
// The squared Mahalanobis distance of `other` from m.cam_b_from_cam_a under m.covariance (6 dof:
// median 5.35, beyond 22.46 one time in a thousand when other is drawn from it).
double SquaredMahalanobis(const CameraMotion& m, const Rigid3d& other);

// The exact camera motion between two camera poses (e.g. ground truth): cam_b_from_world *
// world_from_cam_a, with zero covariance.
CameraMotion CameraMotionFromPoses(int64_t t_a_ns, const Rigid3d& world_from_cam_a, int64_t t_b_ns,
                                   const Rigid3d& world_from_cam_b);

}  // namespace imumatch
