#include "imumatch/frontend/pose_estimation.h"

#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

PinholeCamera Camera() {
  PinholeCamera c = PinholeCamera::KinectDefault();
  return c;
}

// Points 2-6 m in front of A seen from B = (R, t), with pixel noise and a share of outliers.
struct Scene {
  std::vector<Eigen::Vector3d> points_a;
  std::vector<Eigen::Vector2d> pixels_a, pixels_b;
};
Scene MakeScene(const Rigid3d& b_from_a, int n, double noise_px, double outlier_share) {
  const PinholeCamera c = Camera();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, noise_px);
  Scene s;
  while (static_cast<int>(s.points_a.size()) < n) {
    const Eigen::Vector2d uv(40 + 560 * u(rng), 40 + 400 * u(rng));
    const double z = 2.0 + 4.0 * u(rng);
    const Eigen::Vector3d p((uv.x() - c.cx) / c.fx * z, (uv.y() - c.cy) / c.fy * z, z);
    const Eigen::Vector3d q = b_from_a * p;
    Eigen::Vector2d pb(c.fx * q.x() / q.z() + c.cx, c.fy * q.y() / q.z() + c.cy);
    if (u(rng) < outlier_share) {
      pb = Eigen::Vector2d(640 * u(rng), 480 * u(rng));
    } else {
      pb += Eigen::Vector2d(gauss(rng), gauss(rng));
    }
    s.points_a.push_back(p);
    s.pixels_a.push_back(uv);
    s.pixels_b.push_back(pb);
  }
  return s;
}

Rigid3d TrueMotion() {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.01, -0.03, 0.02)), Eigen::Vector3d(0.05, -0.02, 0.08));
}

TEST(PoseEstimation, PnpRecoversThePoseThroughOutliers) {
  const Scene s = MakeScene(TrueMotion(), 200, 0.5, 0.3);
  const PixelUndistorter und(Camera());
  // A guess off by 2 deg and 5 cm (an IMU prediction after a poor velocity).
  const Rigid3d guess(ExpSO3(Eigen::Vector3d(0.02, -0.02, 0.0)) * TrueMotion().rotation,
                      TrueMotion().translation + Eigen::Vector3d(0.05, 0.0, 0.0));
  const PoseFit fit = FitPosePnp(s.points_a, s.pixels_b, und, guess, PoseFitOptions());
  ASSERT_TRUE(fit.ok) << fit.reason;
  EXPECT_LT(RotationDistance(fit.cam_b_from_cam_a.rotation, TrueMotion().rotation), 1e-3);
  EXPECT_LT((fit.cam_b_from_cam_a.translation - TrueMotion().translation).norm(), 5e-3);
  EXPECT_GT(fit.inliers, 120);
  EXPECT_LT(fit.inliers, 160);  // the 30 % outliers are out
  EXPECT_LT(fit.rms_px, 1.0);
}

TEST(PoseEstimation, EpipolarDirectionWithTheGyroRotation) {
  const Scene s = MakeScene(TrueMotion(), 200, 0.5, 0.3);
  const PixelUndistorter und(Camera());
  // The gyro's rotation (exact here); the IMU's translation 30 deg off in direction and 20 % off
  // in length: the fit keeps the length (the scale) and corrects the direction.
  const Eigen::Vector3d t = TrueMotion().translation;
  const Eigen::Vector3d wrong = 1.2 * (ExpSO3(Eigen::Vector3d(0.0, 0.5236, 0.0)) * t);
  const Rigid3d guess(TrueMotion().rotation, wrong);
  const PoseFit fit = FitPoseEpipolar(s.pixels_a, s.pixels_b, und, guess, PoseFitOptions());
  ASSERT_TRUE(fit.ok) << fit.reason;
  const Eigen::Vector3d got = fit.cam_b_from_cam_a.translation;
  EXPECT_NEAR(got.norm(), wrong.norm(), 1e-9);
  // 30 deg off before, within 3 deg after (the parallax is 5-25 px at 0.5 px noise).
  EXPECT_GT(got.normalized().dot(t.normalized()), std::cos(3.0 * M_PI / 180.0));
  // Exact correspondences: the exact direction.
  const Scene exact = MakeScene(TrueMotion(), 50, 0.0, 0.0);
  const PoseFit e = FitPoseEpipolar(exact.pixels_a, exact.pixels_b, und, guess, PoseFitOptions());
  ASSERT_TRUE(e.ok);
  EXPECT_GT(e.cam_b_from_cam_a.translation.normalized().dot(t.normalized()), 1.0 - 1e-9);
  // No baseline: the guess is kept and the fit says why.
  const PoseFit none = FitPoseEpipolar(s.pixels_a, s.pixels_b, und,
                                       Rigid3d(TrueMotion().rotation, Eigen::Vector3d::Zero()), {});
  EXPECT_FALSE(none.ok);
  EXPECT_NE(none.reason.find("no baseline"), std::string::npos);
}

TEST(PoseEstimation, TooFewCorrespondencesAndBadInput) {
  const Scene s = MakeScene(TrueMotion(), 5, 0.5, 0.0);
  const PixelUndistorter und(Camera());
  EXPECT_FALSE(FitPosePnp(s.points_a, s.pixels_b, und, Rigid3d(), {}).ok);
  EXPECT_THROW(FitPosePnp(s.points_a, {}, und, Rigid3d(), {}), InvalidArgument);
  PoseFitOptions bad;
  bad.ransac_px = -1.0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
