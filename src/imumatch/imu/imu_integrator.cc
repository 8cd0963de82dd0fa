#include "imumatch/imu/imu_integrator.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <string>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"

namespace imumatch {

IntegrationMode ParseIntegrationMode(std::string_view name) {
  std::string n(name);
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return std::tolower(c); });
  if (n == "paper") return IntegrationMode::kPaper;
  if (n == "so3" || n == "default") return IntegrationMode::kSo3;
  throw InvalidArgument("unknown integration mode '" + std::string(name) +
                        "' (expected paper or so3)");
}

const char* ToString(IntegrationMode mode) {
  return mode == IntegrationMode::kPaper ? "paper" : "so3";
}

namespace {

void CheckSamples(const std::vector<ImuSample>& samples) {
  IMUMATCH_CHECK(samples.size() >= 2, "need at least two IMU samples, got " << samples.size());
  for (size_t k = 1; k < samples.size(); ++k) {
    IMUMATCH_CHECK(samples[k].t_ns > samples[k - 1].t_ns,
                   "IMU samples must be strictly increasing");
  }
}

}  // namespace

ImuPreintegration Preintegrate(const std::vector<ImuSample>& samples, const ImuBias& bias,
                               const ImuParams& params, double bias_sigma_gyro,
                               double bias_sigma_accel) {
  CheckSamples(samples);
  params.Check();
  using Mat3 = Eigen::Matrix3d;
  using Mat9 = Eigen::Matrix<double, 9, 9>;
  ImuPreintegration out;
  out.t0_ns = samples.front().t_ns;
  out.t1_ns = samples.back().t_ns;

  Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
  Eigen::Vector3d dv = Eigen::Vector3d::Zero(), dp = Eigen::Vector3d::Zero();
  Mat9 cov = Mat9::Zero();
  // Bias Jacobians (Forster et al. 2017, appendix B).
  Mat3 dr_dbg = Mat3::Zero(), dv_dbg = Mat3::Zero(), dv_dba = Mat3::Zero();
  Mat3 dp_dbg = Mat3::Zero(), dp_dba = Mat3::Zero();

  for (size_t k = 0; k + 1 < samples.size(); ++k) {
    const double dt = static_cast<double>(samples[k + 1].t_ns - samples[k].t_ns) * 1e-9;
    const Eigen::Vector3d w = 0.5 * (samples[k].gyro_rad_s + samples[k + 1].gyro_rad_s) - bias.gyro;
    const Eigen::Vector3d a0 = samples[k].accel_m_s2 - bias.accel;
    const Eigen::Vector3d a1 = samples[k + 1].accel_m_s2 - bias.accel;
    const Eigen::Quaterniond step = ExpSO3(w * dt);
    const Eigen::Quaterniond dq_next = (dq * step).normalized();
    const Mat3 r_k = dq.toRotationMatrix();
    // Midpoint rule: the specific force in frame i averaged over the step's two ends.
    const Eigen::Vector3d a_mid = 0.5 * (dq * a0 + dq_next * a1);
    const Eigen::Vector3d a_body = 0.5 * (a0 + a1);

    // Noise propagation on [dtheta, dv, dp].
    const Mat3 jr = RightJacobianSO3(w * dt);
    Mat9 a = Mat9::Identity();
    a.block<3, 3>(0, 0) = step.toRotationMatrix().transpose();
    a.block<3, 3>(3, 0) = -r_k * Hat(a_body) * dt;
    a.block<3, 3>(6, 0) = -0.5 * r_k * Hat(a_body) * dt * dt;
    a.block<3, 3>(6, 3) = Mat3::Identity() * dt;
    Eigen::Matrix<double, 9, 3> b = Eigen::Matrix<double, 9, 3>::Zero();
    b.block<3, 3>(0, 0) = jr * dt;
    Eigen::Matrix<double, 9, 3> c = Eigen::Matrix<double, 9, 3>::Zero();
    c.block<3, 3>(3, 0) = r_k * dt;
    c.block<3, 3>(6, 0) = 0.5 * r_k * dt * dt;
    const double gyro_var = params.gyro_noise_density * params.gyro_noise_density / dt;
    const double accel_var = params.accel_noise_density * params.accel_noise_density / dt;
    cov = a * cov * a.transpose() + gyro_var * b * b.transpose() + accel_var * c * c.transpose();

    // Bias Jacobians.
    dp_dba += dv_dba * dt - 0.5 * r_k * dt * dt;
    dp_dbg += dv_dbg * dt - 0.5 * r_k * Hat(a_body) * dr_dbg * dt * dt;
    dv_dba -= r_k * dt;
    dv_dbg -= r_k * Hat(a_body) * dr_dbg * dt;
    dr_dbg = step.toRotationMatrix().transpose() * dr_dbg - jr * dt;

    dp += dv * dt + 0.5 * a_mid * dt * dt;
    dv += a_mid * dt;
    dq = dq_next;
  }

  // Bias uncertainty: the estimate's own sigma plus the random walk over the interval.
  const double t = static_cast<double>(out.t1_ns - out.t0_ns) * 1e-9;
  const double sbg2 =
      bias_sigma_gyro * bias_sigma_gyro + params.gyro_random_walk * params.gyro_random_walk * t;
  const double sba2 =
      bias_sigma_accel * bias_sigma_accel + params.accel_random_walk * params.accel_random_walk * t;
  Eigen::Matrix<double, 9, 3> jg, ja;
  jg << dr_dbg, dv_dbg, dp_dbg;
  ja << Mat3::Zero(), dv_dba, dp_dba;
  cov += sbg2 * jg * jg.transpose() + sba2 * ja * ja.transpose();

  out.delta_rotation = dq;
  out.delta_velocity = dv;
  out.delta_position = dp;
  out.covariance = 0.5 * (cov + cov.transpose());
  return out;
}

NavState Propagate(const NavState& s, const ImuPreintegration& pim, const Eigen::Vector3d& g) {
  IMUMATCH_CHECK(s.t_ns == pim.t0_ns, "state time does not match the preintegration start");
  const double dt = pim.dt();
  NavState out;
  out.t_ns = pim.t1_ns;
  const Eigen::Quaterniond& r_i = s.world_from_imu.rotation;
  out.world_from_imu.rotation = (r_i * pim.delta_rotation).normalized();
  out.velocity_in_world = s.velocity_in_world + g * dt + r_i * pim.delta_velocity;
  out.world_from_imu.translation = s.world_from_imu.translation + s.velocity_in_world * dt +
                                   0.5 * g * dt * dt + r_i * pim.delta_position;
  return out;
}

PaperIntegration IntegratePaper(const std::vector<ImuSample>& samples,
                                const Eigen::Vector3d& initial_velocity_in_imu) {
  CheckSamples(samples);
  Eigen::Vector3d angles = Eigen::Vector3d::Zero();  // roll, pitch, yaw summed
  Eigen::Vector3d v = initial_velocity_in_imu;
  Eigen::Vector3d dr = Eigen::Vector3d::Zero();
  for (size_t k = 0; k + 1 < samples.size(); ++k) {
    const double dt = static_cast<double>(samples[k + 1].t_ns - samples[k].t_ns) * 1e-9;
    angles += samples[k].gyro_rad_s * dt;
    const Eigen::Vector3d& a = samples[k].accel_m_s2;
    dr += v * dt + 0.5 * a * dt * dt;
    v += a * dt;
  }
  PaperIntegration out;
  out.imu_i_from_imu_j = Rigid3d(FromEulerZYX(angles.x(), angles.y(), angles.z()), dr);
  out.velocity_end = v;
  return out;
}

StillInitialization InitializeFromStill(const ImuBuffer& buffer, int64_t t0_ns, int64_t t1_ns,
                                        const ImuParams& params, double max_gyro_drift,
                                        double max_accel_drift) {
  params.Check();
  // Plain messages (no "check ... failed"): callers show them to users in notes.
  if (t1_ns <= t0_ns) throw InvalidArgument("no still period was asked for (its length is 0)");
  const int64_t end_ns = buffer.GapFreeEnd(t0_ns, t1_ns);
  if (end_ns <= t0_ns) {
    throw InvalidArgument("the still period ends at once: an IMU gap follows " +
                          FormatNsAsSeconds(t0_ns) + " s");
  }
  const std::vector<ImuSample> samples = buffer.Slice(t0_ns, end_ns);
  const int n = static_cast<int>(samples.size());
  if (n < 20) {
    throw InvalidArgument(
        "a still period needs at least 20 IMU samples, got " + std::to_string(n) +
        (end_ns < t1_ns ? " before an IMU gap at " + FormatNsAsSeconds(end_ns) + " s" : ""));
  }
  Eigen::Vector3d mg = Eigen::Vector3d::Zero(), ma = Eigen::Vector3d::Zero();
  for (const ImuSample& s : samples) {
    mg += s.gyro_rad_s;
    ma += s.accel_m_s2;
  }
  mg /= n;
  ma /= n;
  double gyro_drift = 0.0, accel_drift = 0.0;
  constexpr int kBlocks = 4;
  for (int b = 0; b < kBlocks; ++b) {
    const int lo = b * n / kBlocks, hi = (b + 1) * n / kBlocks;
    Eigen::Vector3d bg = Eigen::Vector3d::Zero(), ba = Eigen::Vector3d::Zero();
    for (int k = lo; k < hi; ++k) {
      bg += samples[k].gyro_rad_s;
      ba += samples[k].accel_m_s2;
    }
    gyro_drift = std::max(gyro_drift, (bg / (hi - lo) - mg).cwiseAbs().maxCoeff());
    accel_drift = std::max(accel_drift, (ba / (hi - lo) - ma).cwiseAbs().maxCoeff());
  }
  if (!(gyro_drift <= max_gyro_drift && accel_drift <= max_accel_drift)) {
    std::ostringstream msg;
    msg << "the IMU does not look still: block means of the gyro move by " << gyro_drift
        << " rad/s (at most " << max_gyro_drift << ") and of the accelerometer by " << accel_drift
        << " m/s^2 (at most " << max_accel_drift << ")";
    throw InvalidArgument(msg.str());
  }
  if (!(ma.norm() > 1.0)) {
    throw InvalidArgument("the mean specific force is too small to tell gravity's direction");
  }
  double gyro_var = 0.0;
  for (const ImuSample& s : samples) gyro_var += (s.gyro_rad_s - mg).squaredNorm() / 3.0;
  gyro_var /= (n - 1);
  StillInitialization init;
  init.bias.gyro = mg;
  init.gravity_in_imu = -ma.normalized() * params.gravity_in_world.norm();
  init.world_from_imu.rotation =
      Eigen::Quaterniond::FromTwoVectors(init.gravity_in_imu, params.gravity_in_world).normalized();
  // Standard error of the mean; vibration is correlated, so never below the white-noise figure.
  init.gyro_bias_sigma =
      std::max(std::sqrt(gyro_var), params.gyro_noise_density * std::sqrt(params.rate_hz)) /
      std::sqrt(static_cast<double>(n));
  init.num_samples = n;
  init.end_ns = end_ns;
  return init;
}

}  // namespace imumatch
