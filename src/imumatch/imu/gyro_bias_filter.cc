#include "imumatch/imu/gyro_bias_filter.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/imu/imu_integrator.h"

namespace imumatch {

void GyroBiasFilterOptions::Check() const {
  IMUMATCH_CHECK(
      std::isfinite(unknown_bias_sigma) && unknown_bias_sigma > 0.0,
      "GyroBiasFilterOptions.unknown_bias_sigma must be > 0, got " << unknown_bias_sigma);
  IMUMATCH_CHECK(std::isfinite(scale_sigma) && scale_sigma >= 0.0,
                 "GyroBiasFilterOptions.scale_sigma must be >= 0, got " << scale_sigma);
  IMUMATCH_CHECK(std::isfinite(gate_chi2) && gate_chi2 > 0.0,
                 "GyroBiasFilterOptions.gate_chi2 must be > 0, got " << gate_chi2);
}

GyroBiasFilter::GyroBiasFilter(const Eigen::Vector3d& bias, double sigma, double random_walk,
                               int64_t t_ns, const GyroBiasFilterOptions& options)
    : options_(options),
      bias_(bias),
      covariance_(Eigen::Matrix3d::Identity() * sigma * sigma),
      random_walk_(random_walk),
      t_ns_(t_ns) {
  options_.Check();
  IMUMATCH_CHECK(bias.allFinite(), "gyro bias is not finite");
  IMUMATCH_CHECK(std::isfinite(sigma) && sigma >= 0.0,
                 "gyro bias sigma must be >= 0, got " << sigma);
  IMUMATCH_CHECK(std::isfinite(random_walk) && random_walk >= 0.0,
                 "gyro random walk must be >= 0, got " << random_walk);
}

Eigen::Matrix3d GyroBiasFilter::CovarianceAt(int64_t t_ns) const {
  const double since = std::max(0.0, NsToSeconds(t_ns - t_ns_));
  return covariance_ + Eigen::Matrix3d::Identity() * random_walk_ * random_walk_ * since;
}

double GyroBiasFilter::SigmaAt(int64_t t_ns) const {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(CovarianceAt(t_ns),
                                                           Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

bool GyroBiasFilter::Update(const std::vector<ImuSample>& samples, const ImuParams& params,
                            const Eigen::Quaterniond& measured_imu_a_from_imu_b,
                            const Eigen::Matrix3d& measured_covariance) {
  IMUMATCH_CHECK(samples.size() >= 2, "a gyro bias update needs at least 2 IMU samples");
  IMUMATCH_CHECK(samples.front().t_ns >= t_ns_,
                 "gyro bias update over samples from t = " << samples.front().t_ns
                                                           << " ns, before the last update at "
                                                           << t_ns_ << " ns");
  IMUMATCH_CHECK(measured_covariance.allFinite() &&
                     measured_covariance.isApprox(measured_covariance.transpose(), 1e-9),
                 "measured rotation covariance is not finite and symmetric");
  const Eigen::LLT<Eigen::Matrix3d> measured_llt(measured_covariance);
  IMUMATCH_CHECK(measured_llt.info() == Eigen::Success,
                 "measured rotation covariance is not positive definite");
  IMUMATCH_CHECK(std::isfinite(measured_imu_a_from_imu_b.norm()) &&
                     std::fabs(measured_imu_a_from_imu_b.norm() - 1.0) < 1e-6,
                 "measured rotation is not a unit quaternion");

  // The bias's uncertainty at the interval's start.
  const Eigen::Matrix3d p = CovarianceAt(samples.front().t_ns);
  ImuBias bias;
  bias.gyro = bias_;
  const ImuPreintegration pim = Preintegrate(samples, bias, params);
  const Eigen::Quaterniond predicted_inverse = pim.delta_rotation.conjugate();
  const Eigen::Vector3d r = LogSO3(predicted_inverse * measured_imu_a_from_imu_b);
  // J by central differences (the map is smooth; h far above rounding, far below any bias).
  Eigen::Matrix3d j;
  const double h = 1e-4;
  for (int i = 0; i < 3; ++i) {
    ImuBias plus = bias, minus = bias;
    plus.gyro[i] += h;
    minus.gyro[i] -= h;
    const Eigen::Quaterniond rp = Preintegrate(samples, plus, params).delta_rotation;
    const Eigen::Quaterniond rm = Preintegrate(samples, minus, params).delta_rotation;
    j.col(i) = (LogSO3(predicted_inverse * rp) - LogSO3(predicted_inverse * rm)) / (2.0 * h);
  }
  // The gyro's white noise over the interval (the preintegration's rotation block, no bias part)
  // and its scale-factor error for this rotation.
  const double scale_error = options_.scale_sigma * LogSO3(pim.delta_rotation).norm();
  const Eigen::Matrix3d noise = measured_covariance + pim.covariance.block<3, 3>(0, 0) +
                                Eigen::Matrix3d::Identity() * scale_error * scale_error;
  const Eigen::Matrix3d s = j * p * j.transpose() + noise;
  const Eigen::LDLT<Eigen::Matrix3d> s_ldlt(s);
  if (s_ldlt.info() != Eigen::Success || !s_ldlt.isPositive()) {
    ++rejected_;
    return false;
  }
  last_chi2_ = r.dot(s_ldlt.solve(r));
  if (!std::isfinite(last_chi2_) || last_chi2_ > options_.gate_chi2) {
    ++rejected_;
    return false;
  }
  // K = P J^T S^-1; Joseph form keeps P symmetric positive definite.
  const Eigen::Matrix3d k = s_ldlt.solve(j * p).transpose();
  bias_ += k * r;
  const Eigen::Matrix3d ikj = Eigen::Matrix3d::Identity() - k * j;
  covariance_ = ikj * p * ikj.transpose() + k * noise * k.transpose();
  covariance_ = 0.5 * (covariance_ + covariance_.transpose()).eval();
  t_ns_ = samples.front().t_ns;
  ++updates_;
  return true;
}

std::string GyroBiasFilter::Summary(int64_t t_ns) const {
  std::ostringstream out;
  out << std::scientific << std::setprecision(2) << bias_.x() << " " << bias_.y() << " "
      << bias_.z() << " rad/s (+- " << SigmaAt(t_ns) << "), " << updates_ << " updates, "
      << rejected_ << " rejected by the gate";
  return out.str();
}

}  // namespace imumatch
