#include "imumatch/imu/camera_motion.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/sim/imu_simulator.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {
namespace {

// Camera looking along the IMU's x axis (IMU x forward, y left, z up; camera x right, y down,
// z forward), 3 cm lever arm.
Rigid3d CamFromImu() {
  Eigen::Matrix3d r;
  r << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  return Rigid3d(r, Eigen::Vector3d(0.01, -0.02, 0.03));
}

TEST(CameraMotion, MatchesGroundTruthThroughExtrinsics) {
  CircleTrajectory traj(1.0, 1.0, 1.2, 3.0);  // the body is the IMU
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  ImuBuffer buffer;
  for (const ImuSample& s : SimulateImu(traj, ImuParams::Ideal(), opt)) buffer.Push(s);
  const Rigid3d imu_from_cam = CamFromImu().Inverse();
  const double ta = 0.5123, tb = 0.5123 + 1.0 / 30.0;
  ImuStateAtFrame state;
  state.world_from_imu = traj.WorldFromBody(ta);
  state.velocity_in_world = traj.VelocityInWorld(ta);
  const CameraMotion m =
      ComputeCameraMotion(buffer, SecondsToNs(ta), SecondsToNs(tb), state, ImuParams::Ideal(),
                          CamFromImu(), CameraMotionOptions());
  const CameraMotion truth =
      CameraMotionFromPoses(SecondsToNs(ta), traj.WorldFromBody(ta) * imu_from_cam, SecondsToNs(tb),
                            traj.WorldFromBody(tb) * imu_from_cam);
  EXPECT_LT(RotationDistance(m.cam_b_from_cam_a.rotation, truth.cam_b_from_cam_a.rotation), 1e-6);
  EXPECT_LT((m.cam_b_from_cam_a.translation - truth.cam_b_from_cam_a.translation).norm(), 1e-6);
  // The motion is real: about 1/30 rad and 3.3 cm.
  EXPECT_GT(RotationAngle(truth.cam_b_from_cam_a.rotation), 0.03);
}

TEST(CameraMotion, CovarianceIsCalibrated) {
  // Noisy IMU, uncertain velocity: the Mahalanobis distance of the true motion under the predicted
  // covariance averages about 6 (chi-square, 6 dof) over many seeds.
  SinusoidTrajectory::Params p;
  SinusoidTrajectory traj(p);
  const ImuParams params = ImuParams::ConsumerMems();
  CameraMotionOptions options;
  options.velocity_sigma = 0.02;
  options.attitude_sigma = 0.005;
  options.gyro_bias_sigma = 0.0;
  options.accel_bias_sigma = 0.0;
  const double ta = 1.0, tb = 1.1;
  const Rigid3d imu_from_cam = CamFromImu().Inverse();
  const CameraMotion truth =
      CameraMotionFromPoses(SecondsToNs(ta), traj.WorldFromBody(ta) * imu_from_cam, SecondsToNs(tb),
                            traj.WorldFromBody(tb) * imu_from_cam);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  double chi2_sum = 0;
  const int runs = 200;
  for (int r = 0; r < runs; ++r) {
    ImuSimulatorOptions opt;
    opt.add_bias_walk = false;
    opt.seed = 500 + r;
    ImuBuffer buffer;
    for (const ImuSample& s : SimulateImu(traj, params, opt)) buffer.Push(s);
    ImuStateAtFrame state;
    state.world_from_imu = traj.WorldFromBody(ta);
    state.world_from_imu.rotation =
        state.world_from_imu.rotation *
        ExpSO3(options.attitude_sigma * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
    state.velocity_in_world =
        traj.VelocityInWorld(ta) +
        options.velocity_sigma * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    const CameraMotion m = ComputeCameraMotion(buffer, SecondsToNs(ta), SecondsToNs(tb), state,
                                               params, CamFromImu(), options);
    chi2_sum += SquaredMahalanobis(m, truth.cam_b_from_cam_a);
  }
  EXPECT_NEAR(chi2_sum / runs, 6.0, 1.2);
}

// By hand, with rotations about one axis (their angles add): from R = Exp(0.1 x), t = (1, 2, 3)
// to R' = Exp(0.25 x), t' = (2, 4, 6) the perturbation is (0.15, 0, 0, 1, 2, 3); under the
// covariance diag(0.01, 1, 1, 4, 4, 4) its squared Mahalanobis norm is
// 0.15^2 / 0.01 + (1 + 4 + 9) / 4 = 5.75.
TEST(CameraMotion, PerturbationAndSquaredMahalanobisByHand) {
  CameraMotion m;
  m.cam_b_from_cam_a = Rigid3d(ExpSO3(Eigen::Vector3d(0.1, 0, 0)), Eigen::Vector3d(1, 2, 3));
  const Rigid3d other(ExpSO3(Eigen::Vector3d(0.25, 0, 0)), Eigen::Vector3d(2, 4, 6));
  const Eigen::Matrix<double, 6, 1> d = MotionPerturbation(m.cam_b_from_cam_a, other);
  Eigen::Matrix<double, 6, 1> expected;
  expected << 0.15, 0, 0, 1, 2, 3;
  EXPECT_LT((d - expected).norm(), 1e-12);
  Eigen::Matrix<double, 6, 1> variances;
  variances << 0.01, 1, 1, 4, 4, 4;
  m.covariance = variances.asDiagonal();
  EXPECT_NEAR(SquaredMahalanobis(m, other), 5.75, 1e-9);
  EXPECT_NEAR(SquaredMahalanobis(m, m.cam_b_from_cam_a), 0.0, 1e-24);
}

TEST(CameraMotion, PaperModeDiffersFromSo3ByGravity) {
  ConstantRateTrajectory still(Rigid3d(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1.0);
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  ImuBuffer buffer;
  for (const ImuSample& s : SimulateImu(still, ImuParams::Ideal(), opt)) buffer.Push(s);
  CameraMotionOptions options;
  const CameraMotion so3 = ComputeCameraMotion(buffer, 0, 100'000'000, ImuStateAtFrame(),
                                               ImuParams::Ideal(), CamFromImu(), options);
  options.mode = IntegrationMode::kPaper;
  const CameraMotion paper = ComputeCameraMotion(buffer, 0, 100'000'000, ImuStateAtFrame(),
                                                 ImuParams::Ideal(), CamFromImu(), options);
  EXPECT_LT(so3.cam_b_from_cam_a.translation.norm(), 1e-9);
  // The camera thinks it rose 4.9 cm: in camera coordinates (y down) the scene moves down (+y).
  EXPECT_NEAR(paper.cam_b_from_cam_a.translation.y(), 0.04905, 1e-6);
}

}  // namespace
}  // namespace imumatch
