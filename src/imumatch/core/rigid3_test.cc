#include "imumatch/core/rigid3.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

TEST(Rigid3, ComposeAndInverse) {
  const Rigid3d b_from_a(Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ())),
                         Eigen::Vector3d(1, 2, 3));
  const Rigid3d c_from_b(Eigen::Quaterniond(Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX())),
                         Eigen::Vector3d(-1, 0, 0.5));
  const Eigen::Vector3d p_in_a(0.3, -0.7, 2.0);
  const Eigen::Vector3d p_in_c = c_from_b * (b_from_a * p_in_a);
  EXPECT_LT(((c_from_b * b_from_a) * p_in_a - p_in_c).norm(), 1e-14);
  EXPECT_LT((b_from_a.Inverse() * (b_from_a * p_in_a) - p_in_a).norm(), 1e-14);
  // Hand-computed: rotate (0.3,-0.7,2) by 90 deg about z gives (0.7,0.3,2), plus (1,2,3).
  const Rigid3d quarter(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())),
                        Eigen::Vector3d(1, 2, 3));
  EXPECT_LT((quarter * p_in_a - Eigen::Vector3d(1.7, 2.3, 5.0)).norm(), 1e-14);
}

TEST(Rigid3, FromMatrixValidates) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 3) = 2.0;
  EXPECT_NEAR(Rigid3d::FromMatrix(m).translation.x(), 2.0, 1e-15);
  m(0, 0) = 2.0;
  EXPECT_THROW(Rigid3d::FromMatrix(m), InvalidArgument);
  m = Eigen::Matrix4d::Identity();
  m(2, 2) = -1.0;
  m(1, 1) = 1.0;
  EXPECT_THROW(Rigid3d::FromMatrix(m), InvalidArgument);  // det -1: a reflection
  m = Eigen::Matrix4d::Identity();
  m(3, 0) = 0.5;
  EXPECT_THROW(Rigid3d::FromMatrix(m), InvalidArgument);
}

TEST(Rigid3, RotationAngleAndInterpolation) {
  const Eigen::Quaterniond a(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond b(Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(RotationDistance(a, b), 0.6, 1e-12);
  const Rigid3d mid =
      Interpolate(Rigid3d(a, Eigen::Vector3d::Zero()), Rigid3d(b, Eigen::Vector3d(2, 0, 0)), 0.5);
  EXPECT_NEAR(RotationDistance(mid.rotation, Eigen::Quaterniond(
                                                 Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()))),
              0.0, 1e-12);
  EXPECT_NEAR(mid.translation.x(), 1.0, 1e-15);
}

}  // namespace
}  // namespace imumatch
