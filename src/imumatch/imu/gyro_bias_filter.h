#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_params.h"

namespace imumatch {

// A Kalman filter on the gyro bias, fed with rotations that another sensor (the camera: the
// motion fitted to a pair's matches) measured between two IMU times. A visual-inertial estimator
// keeps the bias this way; a front end without a back end needs it when the log does not start
// still, and the bias also wanders (gyro_random_walk) after a still start.
//
// State: the bias b (rad/s, IMU frame) and its 3x3 covariance P. Between updates P grows by
// gyro_random_walk^2 per second. A measured rotation imu_a_from_imu_b over [t_a, t_b] is compared
// with the samples' preintegration at the current bias, dR(b):
//   r = Log(dR(b)^T dR_measured) = J db + n,   J = d Log(dR(b)^T dR(b + db)) / d db
// (J about -dt I for a short interval; computed by integrating the samples again with the bias
// perturbed), with n's covariance the measurement's plus the gyro white noise's over the
// interval. Updates whose r is beyond the chi-square gate (3 dof) of its predicted covariance are
// rejected (a fit locked onto a moving object, a wrong structure).
struct GyroBiasFilterOptions {
  // 1-sigma per axis of the bias when nothing is known about it (no still start): 0.1 rad/s
  // (5.7 deg/s) covers the turn-on bias of consumer MEMS gyros; EuRoC's ADIS16448 reads
  // 0.078 rad/s about z at rest in MH_05.
  double unknown_bias_sigma = 0.1;
  // The gyro's scale-factor and axis-misalignment error, relative (1-sigma): a rotation of angle
  // a is known to scale_sigma x a on every axis, beyond the white noise. MEMS datasheets give
  // 0.5-2 % (the ADIS16448's sensitivity tolerance is 1 %); over 50 ms of flight (up to 1.9 deg)
  // that is up to 3e-4 rad, as much as a fitted rotation's own error, and not a bias.
  double scale_sigma = 0.01;
  // Chi-square gate on the normalised residual, 3 dof (16.27: probability 0.999).
  double gate_chi2 = 16.27;
  void Check() const;  // throws InvalidArgument
};

class GyroBiasFilter {
 public:
  // Starts at bias (rad/s) with an isotropic 1-sigma (rad/s) at t_ns; random_walk is the gyro's
  // rate random walk (rad/s^2/sqrt(Hz), ImuParams::gyro_random_walk).
  GyroBiasFilter(const Eigen::Vector3d& bias, double sigma, double random_walk, int64_t t_ns,
                 const GyroBiasFilterOptions& options = {});

  const Eigen::Vector3d& bias() const { return bias_; }
  // The covariance propagated to t_ns (no earlier than the last update's time).
  Eigen::Matrix3d CovarianceAt(int64_t t_ns) const;
  // The largest 1-sigma of CovarianceAt(t_ns) (rad/s): an isotropic bound for
  // CameraMotionOptions::gyro_bias_sigma.
  double SigmaAt(int64_t t_ns) const;

  // One measurement: samples as ImuBuffer::Slice(t_a, t_b) returns them, the measured rotation
  // imu_a_from_imu_b and its covariance (3x3, right perturbation: dR_true = dR_measured Exp(e)).
  // Returns false (and leaves the state) when the residual fails the gate or the measurement is
  // degenerate; true when it was used. Throws InvalidArgument for fewer than 2 samples, samples
  // before the last update, or a covariance that is not finite and symmetric positive definite.
  bool Update(const std::vector<ImuSample>& samples, const ImuParams& params,
              const Eigen::Quaterniond& measured_imu_a_from_imu_b,
              const Eigen::Matrix3d& measured_covariance);

  // "b_x b_y b_z rad/s (+- sigma), N updates, M rejected by the gate" with the sigma at t_ns
  // (SigmaAt), for reports.
  std::string Summary(int64_t t_ns) const;

  int updates() const { return updates_; }
  int rejected() const { return rejected_; }
  // The last residual's squared Mahalanobis distance (gate statistic), 0 before any.
  double last_chi2() const { return last_chi2_; }

 private:
  GyroBiasFilterOptions options_;
  Eigen::Vector3d bias_;
  Eigen::Matrix3d covariance_;
  double random_walk_;
  int64_t t_ns_;
  int updates_ = 0;
  int rejected_ = 0;
  double last_chi2_ = 0.0;
};

}  // namespace imumatch
