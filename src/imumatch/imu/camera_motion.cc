#include "imumatch/imu/camera_motion.h"

#include <cmath>

#include <Eigen/Cholesky>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {

void CameraMotionOptions::Check() const {
  for (double v : {velocity_sigma, attitude_sigma, gyro_bias_sigma, accel_bias_sigma}) {
    IMUMATCH_CHECK(std::isfinite(v) && v >= 0.0, "camera motion sigmas must be finite and >= 0");
  }
}

namespace {

// Perturbation vector layout: [dtheta_pim(3), dp_pim(3), dv_world(3), dphi_attitude(3)].
constexpr int kInputDim = 12;

Rigid3d ImuIFromImuJ(const ImuPreintegration& pim, const ImuStateAtFrame& s,
                     const Eigen::Vector3d& g, const Eigen::Matrix<double, kInputDim, 1>& e) {
  const double dt = pim.dt();
  const Eigen::Quaterniond r_i = s.world_from_imu.rotation * ExpSO3(e.segment<3>(9));
  const Eigen::Vector3d v_i = s.velocity_in_world + e.segment<3>(6);
  const Eigen::Quaterniond d_r = pim.delta_rotation * ExpSO3(e.segment<3>(0));
  const Eigen::Vector3d d_p = pim.delta_position + e.segment<3>(3);
  return Rigid3d(d_r, r_i.conjugate() * (v_i * dt + 0.5 * g * dt * dt) + d_p);
}

}  // namespace

CameraMotion ComputeCameraMotion(const ImuBuffer& buffer, int64_t t_a_ns, int64_t t_b_ns,
                                 const ImuStateAtFrame& state_a, const ImuParams& params,
                                 const Rigid3d& cam_from_imu, const CameraMotionOptions& options) {
  options.Check();
  params.Check();
  const std::vector<ImuSample> samples = buffer.Slice(t_a_ns, t_b_ns);
  CameraMotion out;
  out.t_a_ns = t_a_ns;
  out.t_b_ns = t_b_ns;
  const Rigid3d imu_from_cam = cam_from_imu.Inverse();

  if (options.mode == IntegrationMode::kPaper) {
    const Eigen::Vector3d v_in_imu =
        state_a.world_from_imu.rotation.conjugate() * state_a.velocity_in_world;
    const PaperIntegration p = IntegratePaper(samples, v_in_imu);
    out.cam_b_from_cam_a = cam_from_imu * p.imu_i_from_imu_j.Inverse() * imu_from_cam;
    return out;
  }

  const ImuPreintegration pim = Preintegrate(samples, state_a.bias, params, options.gyro_bias_sigma,
                                             options.accel_bias_sigma);
  const Eigen::Vector3d& g = params.gravity_in_world;
  const auto cam_b_from_cam_a = [&](const Eigen::Matrix<double, kInputDim, 1>& e) {
    return cam_from_imu * ImuIFromImuJ(pim, state_a, g, e).Inverse() * imu_from_cam;
  };
  const Eigen::Matrix<double, kInputDim, 1> zero = Eigen::Matrix<double, kInputDim, 1>::Zero();
  out.cam_b_from_cam_a = cam_b_from_cam_a(zero);

  // Input covariance: preintegration [theta, p] block (with cross terms), velocity, attitude.
  Eigen::Matrix<double, kInputDim, kInputDim> in =
      Eigen::Matrix<double, kInputDim, kInputDim>::Zero();
  in.block<3, 3>(0, 0) = pim.covariance.block<3, 3>(0, 0);
  in.block<3, 3>(0, 3) = pim.covariance.block<3, 3>(0, 6);
  in.block<3, 3>(3, 0) = pim.covariance.block<3, 3>(6, 0);
  in.block<3, 3>(3, 3) = pim.covariance.block<3, 3>(6, 6);
  in.block<3, 3>(6, 6) =
      Eigen::Matrix3d::Identity() * options.velocity_sigma * options.velocity_sigma;
  in.block<3, 3>(9, 9) =
      Eigen::Matrix3d::Identity() * options.attitude_sigma * options.attitude_sigma;

  // Numerical Jacobian of the output tangent [log(R' R^T); t' - t] (central differences; the map
  // is smooth and cheap, so this is exact to ~1e-9 and keeps the algebra in one place).
  Eigen::Matrix<double, 6, kInputDim> j;
  const double h = 1e-6;
  const Rigid3d& ref = out.cam_b_from_cam_a;
  for (int i = 0; i < kInputDim; ++i) {
    Eigen::Matrix<double, kInputDim, 1> e = zero;
    e(i) = h;
    const Rigid3d plus = cam_b_from_cam_a(e);
    e(i) = -h;
    const Rigid3d minus = cam_b_from_cam_a(e);
    j.block<3, 1>(0, i) = (LogSO3(plus.rotation * ref.rotation.conjugate()) -
                           LogSO3(minus.rotation * ref.rotation.conjugate())) /
                          (2 * h);
    j.block<3, 1>(3, i) = (plus.translation - minus.translation) / (2 * h);
  }
  out.covariance = j * in * j.transpose();
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  return out;
}

Eigen::Matrix<double, 6, 1> MotionPerturbation(const Rigid3d& motion, const Rigid3d& other) {
  Eigen::Matrix<double, 6, 1> d;
  d.head<3>() = LogSO3(other.rotation * motion.rotation.inverse());
  d.tail<3>() = other.translation - motion.translation;
  return d;
}

double SquaredMahalanobis(const CameraMotion& m, const Rigid3d& other) {
  const Eigen::Matrix<double, 6, 1> e = MotionPerturbation(m.cam_b_from_cam_a, other);
  return e.dot(m.covariance.ldlt().solve(e));
}

CameraMotion CameraMotionFromPoses(int64_t t_a_ns, const Rigid3d& world_from_cam_a, int64_t t_b_ns,
                                   const Rigid3d& world_from_cam_b) {
  CameraMotion out;
  out.t_a_ns = t_a_ns;
  out.t_b_ns = t_b_ns;
  out.cam_b_from_cam_a = world_from_cam_b.Inverse() * world_from_cam_a;
  return out;
}

}  // namespace imumatch
