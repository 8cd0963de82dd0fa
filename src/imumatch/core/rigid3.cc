#include "imumatch/core/rigid3.h"

#include <cmath>

#include "imumatch/core/error.h"

namespace imumatch {

Rigid3d Rigid3d::FromMatrix(const Eigen::Matrix4d& m, double tol) {
  IMUMATCH_CHECK(m.allFinite(), "transform has non-finite entries");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  IMUMATCH_CHECK((r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < tol,
                 "rotation block is not orthonormal");
  IMUMATCH_CHECK(r.determinant() > 0, "rotation block has determinant " << r.determinant());
  IMUMATCH_CHECK((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() < tol,
                 "last row is not 0 0 0 1");
  // Re-orthonormalise through the quaternion.
  return Rigid3d(Eigen::Quaterniond(r).normalized(), m.topRightCorner<3, 1>());
}

double RotationAngle(const Eigen::Quaterniond& q) {
  const Eigen::Quaterniond n = q.normalized();
  const double v = n.vec().norm();
  return 2.0 * std::atan2(v, std::abs(n.w()));
}

double RotationDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return RotationAngle(a.conjugate() * b);
}

Rigid3d Interpolate(const Rigid3d& a, const Rigid3d& b, double alpha) {
  return Rigid3d(a.rotation.slerp(alpha, b.rotation),
                 (1.0 - alpha) * a.translation + alpha * b.translation);
}

}  // namespace imumatch
