#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_params.h"

namespace imumatch {

// The offset between the camera's and the IMU's clocks, measured from the rotations the camera
// saw between frames.
//
// A camera and an IMU that are not triggered by one clock (a USB camera, a phone, a rig without
// hardware synchronisation) timestamp the same instant differently: t_imu = t_cam + offset, a few
// to tens of milliseconds, which Kalibr calls timeshift_cam_imu. The guided matcher integrates the
// gyro over [t_a + offset, t_b + offset]; read over [t_a, t_b] instead, the rotation it predicts
// is off by about (w(t_b) - w(t_a)) x offset, 0.2 deg for 20 ms of a 10 deg/s change of the
// angular velocity, which the search windows absorb at the cost of their size.
//
// Each observation is a rotation measured between two camera times (the motion fitted to a
// pair's matches: ImuRotationFromFit) with its covariance. For each candidate offset on a grid the
// gyro is integrated over the shifted intervals (the midpoint rule, as Preintegrate) and compared
// with the observations:
//   r_i(offset) = Log(dR_gyro(t_a + offset, t_b + offset; b + db)^T dR_i),
// weighted by the observation's covariance plus the gyro's white noise over the interval
// (gyro_noise_density^2 x dt) and its scale-factor error, and truncated at gate_chi2 (a fit
// locked onto a moving object does not pull the offset). A constant correction db of the given
// gyro bias is solved with the offset (a bias error turns each rotation by -dt db; an offset by
// the angular velocity's change over the pair: the two separate when the angular velocity
// varies). The offset is the grid's minimum refined by a parabola; its sigma is the parabola's
// (one parameter: the cost rises by 1 at 1 sigma). Real fits state their covariance
// optimistically: the covariances are scaled by the observations' scatter at a first search's
// offset (their median normalised squared residual against a chi-square's, robust to the
// outliers) and the search runs again with them. That sigma still takes the fits as independent;
// consecutive pairs' fits are not (they share a frame, and a scene's errors last over many
// frames), so a block jackknife measures it as well: the offset found again without each of
// jackknife_blocks runs of consecutive observations (in the order given), their spread giving the
// estimate's variance. The larger sigma stands.
// The most grid steps on each side of zero that TimeOffsetOptions may ask for.
constexpr double kMaxTimeOffsetSteps = 10000.0;

struct TimeOffsetOptions {
  double max_offset_s = 0.05;  // the grid spans [-max, max]
  double step_s = 0.0005;      // at most max_offset_s / 4 and at least max_offset_s / 10000
  double gate_chi2 = 16.27;    // 3 dof, probability 0.999
  double scale_sigma = 0.01;   // as GyroBiasFilterOptions::scale_sigma
  int min_observations = 10;   // at least 4: the offset and a 3-axis bias correction
  // The offset counts as measured when its sigma is at most this (else the rotations did not
  // vary enough to show it).
  double max_sigma_s = 0.005;
  // Not measured when a second minimum of the cost, beyond 3 sigmas of the lowest, lies within
  // this of it (a chi-square difference: 4 is two sigmas of one parameter); 0: never.
  double ambiguity_chi2 = 4.0;
  // Runs of consecutive observations the jackknife leaves out in turn (at most half the
  // observations); 0: the parabola's sigma alone.
  int jackknife_blocks = 10;
  void Check() const;  // throws InvalidArgument
};

// A rotation imu_a_from_imu_b measured between two camera times, with its covariance (3x3, right
// perturbation, as GyroBiasFilter::Update takes it).
struct RotationObservation {
  int64_t t_a_ns = 0;
  int64_t t_b_ns = 0;
  Eigen::Quaterniond imu_a_from_imu_b = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
};

struct TimeOffsetEstimate {
  bool measured = false;           // sigma_s <= max_sigma_s with enough observations
  std::string reason;              // why not measured
  double offset_s = 0.0;           // t_imu = t_cam + offset_s
  double sigma_s = 0.0;            // the larger of the parabola's and the jackknife's
  double jackknife_sigma_s = 0.0;  // 0 when not computed
  Eigen::Vector3d gyro_bias_correction = Eigen::Vector3d::Zero();  // db at the offset (rad/s)
  int observations = 0;       // usable: their intervals lie in the log at every offset of the grid
  int inliers = 0;            // within the gate at the offset
  double cost_at_zero = 0.0;  // truncated cost at offset 0 and at offset_s
  double cost = 0.0;
  // "+9.8 ms (+- 0.4 ms, 183 of 190 fitted rotations)" or the reason, for reports. offset_s and
  // sigma_s mean nothing when !measured (reports write them as null).
  std::string Summary() const;
};

// An offset as reports print it: milliseconds to one decimal with their sign, "+9.8 ms"; "+0.0 ms"
// for what rounds to zero (not "-0.0").
std::string FormatOffsetMs(double seconds);

// When an estimate is worth acting on: it is measured, at least min_offset_s away from zero (a
// few milliseconds move a rotation between frames by less than the keypoints' noise) and farther
// than min_sigmas of its sigma.
struct TimeOffsetAdviceOptions {
  double min_offset_s = 0.002;
  double min_sigmas = 3.0;
};
// Advice to set timeshift_cam_imu to applied_shift_s + the offset (seconds to 0.1 ms), with why,
// when the estimate is worth acting on (TimeOffsetAdviceOptions); else empty.
std::string TimeOffsetAdvice(const TimeOffsetEstimate& estimate, double applied_shift_s,
                             const TimeOffsetAdviceOptions& options = {});

// Why an observation cannot be used: t_b not after t_a, a covariance that is not finite, symmetric
// and positive definite, or a quaternion that is not unit; empty when it can.
std::string RotationObservationProblem(const RotationObservation& observation);

// Throws InvalidArgument for invalid options or observations (t_b <= t_a, a covariance that is not
// finite and symmetric positive definite, a quaternion that is not unit); observations whose
// shifted intervals leave the log or cross a gap at some offset of the grid are not used. Not
// measured (with the reason) when fewer than min_observations are usable, when the cost changes
// by less than 1 over the whole grid, when its minimum lies at the grid's edge (also with a run of
// the observations left out), when a second minimum is nearly as low (ambiguity_chi2), or when
// the sigma exceeds max_sigma_s.
// TryEstimateTimeOffset: the same, an error turned into an estimate not measured, with the
// error as its reason (for reports that must not stop on it).
TimeOffsetEstimate TryEstimateTimeOffset(const ImuBuffer& imu, const ImuParams& params,
                                         const Eigen::Vector3d& gyro_bias,
                                         const std::vector<RotationObservation>& observations,
                                         const TimeOffsetOptions& options = {});
TimeOffsetEstimate EstimateTimeOffset(const ImuBuffer& imu, const ImuParams& params,
                                      const Eigen::Vector3d& gyro_bias,
                                      const std::vector<RotationObservation>& observations,
                                      const TimeOffsetOptions& options = {});

}  // namespace imumatch
