#include "imumatch/core/so3.h"

#include <cmath>

#include <gtest/gtest.h>

namespace imumatch {
namespace {

TEST(So3, ExpMatchesAngleAxis) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  for (double angle : {0.0, 1e-9, 1e-4, 0.3, 1.5, 3.0}) {
    const Eigen::Quaterniond expected(Eigen::AngleAxisd(angle, axis));
    EXPECT_LT(expected.angularDistance(ExpSO3(angle * axis)), 1e-12) << angle;
  }
}

TEST(So3, LogInvertsExp) {
  for (const Eigen::Vector3d& w :
       {Eigen::Vector3d(0.1, -0.2, 0.3), Eigen::Vector3d(1e-9, 0, 0), Eigen::Vector3d(0, 3.1, 0)}) {
    EXPECT_LT((LogSO3(ExpSO3(w)) - w).norm(), 1e-10);
  }
}

TEST(So3, HatIsCrossProduct) {
  const Eigen::Vector3d a(1, 2, 3), b(-4, 0.5, 2);
  EXPECT_LT((Hat(a) * b - a.cross(b)).norm(), 1e-15);
}

TEST(So3, RightJacobianFirstOrder) {
  // Exp(w + dw) ~= Exp(w) Exp(Jr(w) dw) for small dw: check numerically.
  const Eigen::Vector3d w(0.4, -0.3, 0.8), dw(1e-6, -2e-6, 1.5e-6);
  const Eigen::Quaterniond lhs = ExpSO3(w + dw);
  const Eigen::Quaterniond rhs = ExpSO3(w) * ExpSO3(RightJacobianSO3(w) * dw);
  EXPECT_LT(lhs.angularDistance(rhs), 1e-11);
  EXPECT_LT((RightJacobianSO3(w) * RightJacobianInverseSO3(w) - Eigen::Matrix3d::Identity()).norm(),
            1e-12);
}

TEST(So3, EulerZYXComposition) {
  const Eigen::Quaterniond q = FromEulerZYX(0.1, 0.2, 0.3);
  const Eigen::Matrix3d expected = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()))
                                       .toRotationMatrix();
  EXPECT_LT((q.toRotationMatrix() - expected).norm(), 1e-14);
}

}  // namespace
}  // namespace imumatch
