#include "imumatch/core/so3.h"

#include <cmath>

namespace imumatch {

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  if (theta < 1e-8) {
    // Second-order Taylor expansion, normalised.
    Eigen::Quaterniond q(1.0 - theta * theta / 8.0, 0.5 * omega.x(), 0.5 * omega.y(),
                         0.5 * omega.z());
    return q.normalized();
  }
  const double half = 0.5 * theta;
  const Eigen::Vector3d axis = omega / theta;
  const double s = std::sin(half);
  return Eigen::Quaterniond(std::cos(half), s * axis.x(), s * axis.y(), s * axis.z());
}

Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() *= -1.0;  // Shortest rotation.
  const double v = q.vec().norm();
  if (v < 1e-10) return 2.0 * q.vec() / q.w();
  const double theta = 2.0 * std::atan2(v, q.w());
  return theta / v * q.vec();
}

Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d w = Hat(omega);
  if (theta < 1e-5) return Eigen::Matrix3d::Identity() - 0.5 * w + w * w / 6.0;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(theta)) / t2 * w +
         (theta - std::sin(theta)) / (t2 * theta) * w * w;
}

Eigen::Matrix3d RightJacobianInverseSO3(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d w = Hat(omega);
  if (theta < 1e-5) return Eigen::Matrix3d::Identity() + 0.5 * w + w * w / 12.0;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + 0.5 * w +
         (1.0 / t2 - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta))) * w * w;
}

Eigen::Quaterniond FromEulerZYX(double roll, double pitch, double yaw) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

}  // namespace imumatch
