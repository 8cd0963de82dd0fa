#include "imumatch/frontend/rotation_from_fit.h"

#include "imumatch/core/error.h"

namespace imumatch {

std::optional<ImuRotationMeasurement> ImuRotationFromFit(const MotionRefit& refit,
                                                         const Rigid3d& cam_from_imu) {
  if (!refit.rotation_from_matches_ok) return std::nullopt;
  // R_cam_true = Exp(theta) R_cam; R_imu (b from a) = R_ic R_cam R_ci, so R_imu_true =
  // Exp(R_ic theta) R_imu and imu_a_from_imu_b_true = imu_a_from_imu_b Exp(-R_ic theta).
  const Eigen::Quaterniond imu_from_cam = cam_from_imu.rotation.conjugate();
  const Eigen::Quaterniond imu_b_from_imu_a =
      imu_from_cam * refit.rotation_from_matches * cam_from_imu.rotation;
  ImuRotationMeasurement out;
  out.imu_a_from_imu_b = imu_b_from_imu_a.conjugate().normalized();
  const Eigen::Matrix3d r_ic = imu_from_cam.toRotationMatrix();
  out.covariance = r_ic * refit.rotation_from_matches_covariance * r_ic.transpose();
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  return out;
}

std::optional<RotationObservation> RotationObservationFromFit(const MotionRefit& refit,
                                                              const Rigid3d& cam_from_imu,
                                                              int64_t t_a_ns, int64_t t_b_ns) {
  const std::optional<ImuRotationMeasurement> measured = ImuRotationFromFit(refit, cam_from_imu);
  if (!measured) return std::nullopt;
  RotationObservation observed{t_a_ns, t_b_ns, measured->imu_a_from_imu_b, measured->covariance};
  // What EstimateTimeOffset would refuse is left out here.
  if (!RotationObservationProblem(observed).empty()) return std::nullopt;
  return observed;
}

bool UpdateGyroBiasFromFit(const MotionRefit& refit, const Rigid3d& cam_from_imu,
                           const ImuBuffer& imu, const ImuParams& params, int64_t t_a_ns,
                           int64_t t_b_ns, GyroBiasFilter* filter) {
  IMUMATCH_CHECK(filter != nullptr, "UpdateGyroBiasFromFit needs a filter");
  const std::optional<ImuRotationMeasurement> measured = ImuRotationFromFit(refit, cam_from_imu);
  if (!measured) return false;
  try {
    return filter->Update(imu.Slice(t_a_ns, t_b_ns), params, measured->imu_a_from_imu_b,
                          measured->covariance);
  } catch (const Error&) {
    return false;
  }
}

}  // namespace imumatch
