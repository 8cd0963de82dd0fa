#pragma once

#include <cstdint>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "imumatch/core/rigid3.h"
#include "imumatch/frontend/motion_refit.h"
#include "imumatch/imu/gyro_bias_filter.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_params.h"
#include "imumatch/imu/time_offset.h"

// What a motion fit tells the IMU: the rotation its matches measure (RefitMotion with
// MotionRefitOptions::measure_rotation, or MeasureRotationFromMatches), expressed for the IMU, as
// a gyro bias filter's measurement and as an observation of the camera's clock offset.
namespace imumatch {

// The rotation of the IMU between the pair's frames that a fit's matches measure, for a gyro bias
// filter (GyroBiasFilter::Update): MotionRefit::rotation_from_matches, the matches' residuals
// minimised with the prior's translation information only (the prior's rotation is the gyro's,
// which the filter has already; the epipolar residuals do not see the translation's length),
// expressed for the IMU through cam_from_imu: imu_a_from_imu_b and its covariance (right
// perturbation). nullopt when rotation_from_matches is not set.
struct ImuRotationMeasurement {
  Eigen::Quaterniond imu_a_from_imu_b = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};
std::optional<ImuRotationMeasurement> ImuRotationFromFit(const MotionRefit& refit,
                                                         const Rigid3d& cam_from_imu);

// The same as an observation of the camera's clock offset (EstimateTimeOffset) between the
// frames' camera times t_a_ns < t_b_ns; nullopt when there is no measured rotation or its
// covariance is not finite and positive definite (a degenerate fit: left out rather than let it
// make the whole estimate fail).
std::optional<RotationObservation> RotationObservationFromFit(const MotionRefit& refit,
                                                              const Rigid3d& cam_from_imu,
                                                              int64_t t_a_ns, int64_t t_b_ns);

// Feeds the rotation refit measured between t_a_ns and t_b_ns (ImuRotationFromFit) to filter,
// with the IMU samples of that interval. Returns false when there was nothing to feed (no
// measured rotation) or the interval is one the filter cannot use (across an IMU gap, before its
// last update); otherwise GyroBiasFilter::Update's own result (false when its gate refused it).
bool UpdateGyroBiasFromFit(const MotionRefit& refit, const Rigid3d& cam_from_imu,
                           const ImuBuffer& imu, const ImuParams& params, int64_t t_a_ns,
                           int64_t t_b_ns, GyroBiasFilter* filter);

}  // namespace imumatch
