#include "imumatch/sim/motions.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

class MotionDerivativesTest : public ::testing::TestWithParam<std::string> {};

// The analytic derivatives match central finite differences of the pose.
TEST_P(MotionDerivativesTest, AnalyticDerivativesMatchFiniteDifferences) {
  const MotionOptions options;
  const auto traj = MakeMotion(GetParam(), options);
  ASSERT_NEAR(traj->EndTime(), 3.0, 1e-12);
  const double h = 1e-5;
  for (double t = 0.05; t < traj->EndTime(); t += 0.0937) {
    const Rigid3d before = traj->WorldFromBody(t - h);
    const Rigid3d after = traj->WorldFromBody(t + h);
    const Eigen::Vector3d fd_velocity = (after.translation - before.translation) / (2 * h);
    EXPECT_LT((traj->VelocityInWorld(t) - fd_velocity).norm(), 1e-7) << "t=" << t;
    const Eigen::Vector3d fd_accel =
        (traj->VelocityInWorld(t + h) - traj->VelocityInWorld(t - h)) / (2 * h);
    EXPECT_LT((traj->AccelerationInWorld(t) - fd_accel).norm(), 1e-6) << "t=" << t;
    const Eigen::Vector3d fd_omega = LogSO3(before.rotation.conjugate() * after.rotation) / (2 * h);
    EXPECT_LT((traj->AngularVelocityInBody(t) - fd_omega).norm(), 1e-6) << "t=" << t;
  }
  // Still at both ends (IMU initialisation from a still start).
  for (double t : {0.0, 0.25, traj->EndTime() - 0.2, traj->EndTime()}) {
    EXPECT_LT(traj->VelocityInWorld(t).norm(), 1e-12) << "t=" << t;
    EXPECT_LT(traj->AccelerationInWorld(t).norm(), 1e-12) << "t=" << t;
    EXPECT_LT(traj->AngularVelocityInBody(t).norm(), 1e-12) << "t=" << t;
  }
  const Rigid3d start = traj->WorldFromBody(0.0);
  EXPECT_LT(RotationDistance(start.rotation, options.world_from_body_start.rotation), 1e-12);
  EXPECT_LT((start.translation - options.world_from_body_start.translation).norm(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(AllMotions, MotionDerivativesTest, ::testing::ValuesIn(MotionNames()));

Rigid3d CamBFromCamA(const Trajectory& traj, double t_a, double t_b) {
  const Rigid3d body_from_cam = SyntheticCamFromImu().Inverse();
  const Rigid3d world_from_cam_a = traj.WorldFromBody(t_a) * body_from_cam;
  const Rigid3d world_from_cam_b = traj.WorldFromBody(t_b) * body_from_cam;
  return world_from_cam_b.Inverse() * world_from_cam_a;
}

TEST(MotionsTest, Front1mMovesOneMetreAlongTheOpticalAxis) {
  const MotionOptions options;
  for (const char* name : {"front1m", "back1m"}) {
    const auto traj = MakeMotion(name, options);
    const Rigid3d b_from_a =
        CamBFromCamA(*traj, options.MotionStartTime(), options.MotionEndTime());
    const double sign = std::string(name) == "front1m" ? 1.0 : -1.0;
    // A point in front of camera A is 1 m closer to camera B.
    EXPECT_LT((b_from_a.translation - Eigen::Vector3d(0, 0, -sign)).norm(), 1e-12) << name;
    EXPECT_LT(RotationAngle(b_from_a.rotation), 1e-12) << name;
    // Halfway in time is halfway in distance (symmetric profile).
    const double t_mid = 0.5 * (options.MotionStartTime() + options.MotionEndTime());
    EXPECT_NEAR(CamBFromCamA(*traj, options.MotionStartTime(), t_mid).translation.z(), -0.5 * sign,
                1e-12);
  }
}

TEST(MotionsTest, Left30TurnsThirtyDegreesAboutTheVertical) {
  const MotionOptions options;
  for (const char* name : {"left30", "right30"}) {
    const auto traj = MakeMotion(name, options);
    const Rigid3d a = traj->WorldFromBody(options.MotionStartTime());
    const Rigid3d b = traj->WorldFromBody(options.MotionEndTime());
    const Eigen::Vector3d rotvec = LogSO3(a.rotation.conjugate() * b.rotation);
    const double sign = std::string(name) == "left30" ? 1.0 : -1.0;
    // Body z is world up for the level start pose; left = counter-clockwise from above.
    EXPECT_LT((rotvec - Eigen::Vector3d(0, 0, sign * 30.0 * kPi / 180.0)).norm(), 1e-12) << name;
    EXPECT_LT((b.translation - a.translation).norm(), 1e-12) << name;
    // The camera turns by the same 30 degrees, about its own -y axis (up).
    const Rigid3d cam = CamBFromCamA(*traj, options.MotionStartTime(), options.MotionEndTime());
    const Eigen::Vector3d cam_rotvec = LogSO3(cam.rotation);
    EXPECT_LT((cam_rotvec - Eigen::Vector3d(0, sign * 30.0 * kPi / 180.0, 0)).norm(), 1e-12);
  }
}

TEST(MotionsTest, MinimumJerkProfile) {
  EXPECT_DOUBLE_EQ(MinimumJerk(0.0), 0.0);
  EXPECT_DOUBLE_EQ(MinimumJerk(1.0), 1.0);
  EXPECT_DOUBLE_EQ(MinimumJerk(0.5), 0.5);
  EXPECT_DOUBLE_EQ(MinimumJerk(0.5, 1), 1.875);  // peak velocity 15/8
  EXPECT_DOUBLE_EQ(MinimumJerk(0.25), 10 * 0.015625 - 15 * 0.00390625 + 6 * 0.0009765625);
  EXPECT_DOUBLE_EQ(MinimumJerk(-1.0, 1), 0.0);
  EXPECT_DOUBLE_EQ(MinimumJerk(2.0), 1.0);
  EXPECT_THROW(MinimumJerk(0.5, 3), InvalidArgument);
}

TEST(MotionsTest, ShakeAndFastRotationHaveTheAdvertisedSize) {
  const MotionOptions options;
  const auto shake = MakeMotion("shake", options);
  const auto fast = MakeMotion("fast_rotation", options);
  double max_offset = 0.0, max_angle = 0.0, max_rate = 0.0;
  const Rigid3d start = options.world_from_body_start;
  for (double t = 0.0; t <= 3.0; t += 0.01) {
    const Rigid3d pose = shake->WorldFromBody(t);
    max_offset = std::max(max_offset, (pose.translation - start.translation).norm());
    max_angle = std::max(max_angle, RotationDistance(pose.rotation, start.rotation));
    max_rate = std::max(max_rate, std::abs(fast->AngularVelocityInBody(t).z()));
  }
  EXPECT_GT(max_offset, 0.01);
  EXPECT_LT(max_offset, 0.08);
  EXPECT_GT(max_angle, 2.0 * kPi / 180.0);
  EXPECT_LT(max_angle, 10.0 * kPi / 180.0);
  EXPECT_GT(max_rate, 150.0 * kPi / 180.0);
  EXPECT_LT(max_rate, 220.0 * kPi / 180.0);
}

TEST(MotionsTest, CamFromImuAxes) {
  const Rigid3d cam_from_imu = SyntheticCamFromImu();
  const Eigen::Matrix3d r = cam_from_imu.RotationMatrix();
  EXPECT_LT((r * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_LT((r * Eigen::Vector3d::UnitY() + Eigen::Vector3d::UnitX()).norm(), 1e-15);
  EXPECT_LT((r * Eigen::Vector3d::UnitZ() + Eigen::Vector3d::UnitY()).norm(), 1e-15);
  EXPECT_NEAR(cam_from_imu.translation.norm(), 0.0229, 1e-3);
}

TEST(MotionsTest, RejectsUnknownNamesAndBadOptions) {
  try {
    MakeMotion("sideways", MotionOptions());
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("sideways"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("front1m"), std::string::npos);
  }
  MotionOptions bad;
  bad.duration_s = 0.0;
  EXPECT_THROW(MakeMotion("front1m", bad), InvalidArgument);
  bad = MotionOptions();
  bad.still_before_s = -1.0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
