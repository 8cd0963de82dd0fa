#include "imumatch/sim/synthetic_sequence.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/imu/imu_integrator.h"

namespace imumatch {
namespace {

const Scene& CoarseScene() {
  static const Scene scene = [] {
    SceneOptions options;
    options.texel_size_m = 0.02;  // fast to build; these tests check geometry and timing
    return Scene(options);
  }();
  return scene;
}

PinholeCamera SmallCamera(int width) { return PinholeCamera::KinectDefault().ScaledToWidth(width); }

TEST(SyntheticSequenceTest, SeedPairFramesAndImuAgree) {
  SyntheticSequenceOptions options;
  options.motion = "left30";
  options.frame_times_s = {options.motion_options.MotionStartTime(),
                           options.motion_options.MotionEndTime()};
  options.camera = SmallCamera(160);
  options.imu_model = "ideal";
  options.t0_ns = 1'000'000'000;
  const SyntheticSequence seq = MakeSyntheticSequence(options, CoarseScene());
  ASSERT_EQ(seq.frames.size(), 2u);
  EXPECT_EQ(seq.frames[0].t_ns, 1'500'000'000);
  EXPECT_EQ(seq.frames[1].t_ns, 3'500'000'000);
  for (const SyntheticFrame& f : seq.frames) {
    EXPECT_EQ(f.rgb.type(), CV_8UC3);
    EXPECT_EQ(f.depth.type(), CV_16U);
    EXPECT_EQ(f.rgb.size(), cv::Size(160, 120));
    EXPECT_EQ(f.depth.size(), cv::Size(160, 120));
    EXPECT_LT(f.imu_velocity_in_world.norm(), 1e-12);  // still at both ends of the seed motion
    const Rigid3d cam_from_imu = f.world_from_cam.Inverse() * f.world_from_imu;
    EXPECT_LT((cam_from_imu.translation - SyntheticCamFromImu().translation).norm(), 1e-12);
    // Depth at the centre = the analytic ray cast.
    const double z =
        AnalyticDepth(CoarseScene(), seq.camera, f.world_from_cam, Eigen::Vector2d(79, 59));
    EXPECT_NEAR(f.depth.at<uint16_t>(59, 79), z * 5000.0, 0.5 + 1e-6);
  }
  const Rigid3d b_from_a = seq.frames[1].world_from_cam.Inverse() * seq.frames[0].world_from_cam;
  EXPECT_NEAR(RotationAngle(b_from_a.rotation), 30.0 * kPi / 180.0, 1e-12);

  // IMU: 200 Hz over the 3 s trajectory, from t0.
  ASSERT_EQ(seq.imu.size(), 601u);
  EXPECT_EQ(seq.imu.front().t_ns, 1'000'000'000);
  EXPECT_EQ(seq.imu.back().t_ns, 4'000'000'000);
  EXPECT_LT(seq.imu.front().gyro_rad_s.norm(), 1e-12);
  EXPECT_LT((seq.imu.front().accel_m_s2 - Eigen::Vector3d(0, 0, 9.81)).norm(), 1e-9);  // IMU z up
  // Integrating the gyro between the two frames gives the frames' relative rotation.
  Eigen::Quaterniond imu_a_r_imu_b = Eigen::Quaterniond::Identity();
  for (size_t k = 0; k + 1 < seq.imu.size(); ++k) {
    if (seq.imu[k].t_ns < seq.frames[0].t_ns || seq.imu[k + 1].t_ns > seq.frames[1].t_ns) continue;
    const double dt = (seq.imu[k + 1].t_ns - seq.imu[k].t_ns) * 1e-9;
    imu_a_r_imu_b =
        imu_a_r_imu_b * ExpSO3(0.5 * (seq.imu[k].gyro_rad_s + seq.imu[k + 1].gyro_rad_s) * dt);
  }
  const Eigen::Quaterniond expected =
      seq.frames[0].world_from_imu.rotation.conjugate() * seq.frames[1].world_from_imu.rotation;
  EXPECT_LT(RotationDistance(imu_a_r_imu_b, expected), 1e-5);
}

// The frames' exact IMU states and the simulated samples are consistent: preintegrating the ideal
// IMU between the seed frames and propagating the true state of frame A lands on frame B.
TEST(SyntheticSequenceTest, ImuPropagationReachesTheNextFrame) {
  for (const char* motion : {"front1m", "left30", "walk"}) {
    SyntheticSequenceOptions options;
    options.motion = motion;
    options.frame_times_s = {options.motion_options.MotionStartTime(),
                             options.motion_options.MotionEndTime()};
    options.camera = SmallCamera(32);
    options.imu_model = "ideal";
    options.t0_ns = 7'000'000'000;
    const SyntheticSequence seq = MakeSyntheticSequence(options, CoarseScene());
    const SyntheticFrame& a = seq.frames[0];
    const SyntheticFrame& b = seq.frames[1];
    std::vector<ImuSample> samples;
    for (const ImuSample& s : seq.imu) {
      if (s.t_ns >= a.t_ns && s.t_ns <= b.t_ns) samples.push_back(s);
    }
    ASSERT_EQ(samples.front().t_ns, a.t_ns);
    ASSERT_EQ(samples.back().t_ns, b.t_ns);
    const ImuPreintegration pim = Preintegrate(samples, ImuBias(), seq.imu_params);
    NavState state_a;
    state_a.t_ns = a.t_ns;
    state_a.world_from_imu = a.world_from_imu;
    state_a.velocity_in_world = a.imu_velocity_in_world;
    const NavState state_b = Propagate(state_a, pim, seq.imu_params.gravity_in_world);
    EXPECT_LT((state_b.world_from_imu.translation - b.world_from_imu.translation).norm(), 2e-3)
        << motion;
    EXPECT_LT(RotationDistance(state_b.world_from_imu.rotation, b.world_from_imu.rotation), 1e-4)
        << motion;
    EXPECT_LT((state_b.velocity_in_world - b.imu_velocity_in_world).norm(), 2e-3) << motion;
  }
}

TEST(SyntheticSequenceTest, FrameRateAndDeterminism) {
  SyntheticSequenceOptions options;
  options.motion = "shake";
  options.motion_options.duration_s = 1.0;  // trajectory 0..2 s
  options.camera = SmallCamera(32);
  options.render.depth_noise.add_noise = true;
  const SyntheticSequence a = MakeSyntheticSequence(options, CoarseScene());
  ASSERT_EQ(a.frames.size(), 61u);  // 0, 1/30, ..., 2 s
  for (size_t k = 0; k < a.frames.size(); ++k) {
    EXPECT_EQ(a.frames[k].t_ns, SecondsToNs(k / 30.0));
  }
  EXPECT_EQ(a.imu.size(), 401u);
  EXPECT_EQ(a.imu_params.gyro_noise_density, ImuParams::EurocAdis16448().gyro_noise_density);
  const SyntheticSequence b = MakeSyntheticSequence(options, CoarseScene());
  ASSERT_EQ(a.imu.size(), b.imu.size());
  for (size_t k = 0; k < a.imu.size(); ++k) {
    ASSERT_EQ(a.imu[k].gyro_rad_s, b.imu[k].gyro_rad_s);
    ASSERT_EQ(a.imu[k].accel_m_s2, b.imu[k].accel_m_s2);
  }
  for (size_t k = 0; k < a.frames.size(); ++k) {
    ASSERT_EQ(cv::norm(a.frames[k].rgb, b.frames[k].rgb, cv::NORM_INF), 0.0);
    ASSERT_EQ(cv::norm(a.frames[k].depth, b.frames[k].depth, cv::NORM_INF), 0.0);
  }
  options.imu_seed = 43;
  const SyntheticSequence c = MakeSyntheticSequence(options, CoarseScene());
  EXPECT_NE(a.imu[10].gyro_rad_s, c.imu[10].gyro_rad_s);
}

TEST(SyntheticSequenceTest, AnyTrajectory) {
  SyntheticSequenceOptions options;
  options.camera = SmallCamera(32);
  options.frame_times_s = {0.0, 1.0};
  options.imu_model = "mems";
  const auto walk = MakeMotion("walk", MotionOptions());
  options.motion = "my_walk";
  const SyntheticSequence seq = MakeSyntheticSequence(*walk, options, CoarseScene());
  EXPECT_EQ(seq.motion, "my_walk");
  ASSERT_EQ(seq.frames.size(), 2u);
  EXPECT_LT(
      RotationDistance(seq.frames[1].world_from_imu.rotation, walk->WorldFromBody(1.0).rotation),
      1e-15);
  EXPECT_LT((seq.frames[1].imu_velocity_in_world - walk->VelocityInWorld(1.0)).norm(), 1e-15);
}

TEST(SyntheticSequenceTest, RejectsBadOptions) {
  SyntheticSequenceOptions options;
  options.camera = SmallCamera(32);
  options.motion = "teleport";
  EXPECT_THROW(MakeSyntheticSequence(options, CoarseScene()), InvalidArgument);
  options = SyntheticSequenceOptions();
  options.imu_model = "perfect";
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = SyntheticSequenceOptions();
  options.frame_times_s = {1.0, 0.5};
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.frame_times_s = {0.5, 3.5};  // beyond the 3 s trajectory
  options.camera = SmallCamera(32);
  EXPECT_THROW(MakeSyntheticSequence(options, CoarseScene()), InvalidArgument);
  options = SyntheticSequenceOptions();
  options.camera.fy = -1.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = SyntheticSequenceOptions();
  options.frame_rate_hz = 0.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  // Bounded work, refused before simulating or rendering: 1e6 s at 1 fps, or 30000 frames.
  options = SyntheticSequenceOptions();
  options.camera = SmallCamera(32);
  options.motion_options.duration_s = 1e6;
  options.frame_rate_hz = 1.0;
  try {
    MakeSyntheticSequence(options, CoarseScene());
    ADD_FAILURE() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("20000"), std::string::npos) << e.what();
  }
  options.motion_options.duration_s = 4000.0;  // 4001 frames, but longer than an hour
  EXPECT_THROW(MakeSyntheticSequence(options, CoarseScene()), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
