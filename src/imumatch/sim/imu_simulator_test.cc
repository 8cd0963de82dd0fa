#include "imumatch/sim/imu_simulator.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

TEST(ImuSimulator, StillLevelImuReadsGravityUp) {
  ConstantRateTrajectory still(Rigid3d(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1.0);
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  opt.t0_ns = 1000;
  const auto samples = SimulateImu(still, ImuParams(), opt);
  ASSERT_EQ(samples.size(), 201u);  // 0, 5 ms, ..., 1 s
  EXPECT_EQ(samples.front().t_ns, 1000);
  EXPECT_EQ(samples.back().t_ns, 1000 + 1000000000);
  for (const ImuSample& s : samples) {
    EXPECT_LT((s.accel_m_s2 - Eigen::Vector3d(0, 0, 9.81)).norm(), 1e-12);
    EXPECT_LT(s.gyro_rad_s.norm(), 1e-15);
  }
}

TEST(ImuSimulator, RotatedImuAndLeverArm) {
  // IMU mounted rotated 90 deg about body z, 10 cm ahead on body x; body spins at 2 rad/s about z.
  ConstantRateTrajectory spin(Rigid3d(), Eigen::Vector3d(0, 0, 2.0), Eigen::Vector3d::Zero(), 1.0);
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  opt.body_from_imu =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())),
              Eigen::Vector3d(0.1, 0, 0));
  const auto samples = SimulateImu(spin, ImuParams(), opt);
  for (const ImuSample& s : samples) {
    EXPECT_LT((s.gyro_rad_s - Eigen::Vector3d(0, 0, 2.0)).norm(), 1e-12);
    // Centripetal acceleration w^2 r = 0.4 m/s^2 towards the axis: body -x, which is IMU +y
    // (IMU x = body y, IMU y = -body x); plus gravity reaction +9.81 on z.
    EXPECT_LT((s.accel_m_s2 - Eigen::Vector3d(0, 0.4, 9.81)).norm(), 1e-6);
  }
}

TEST(ImuSimulator, NoiseHasTheStatedStandardDeviation) {
  ConstantRateTrajectory still(Rigid3d(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 50.0);
  ImuSimulatorOptions opt;
  opt.add_bias_walk = false;
  opt.seed = 7;
  const ImuParams params = ImuParams::EurocAdis16448();
  const auto samples = SimulateImu(still, params, opt);
  double sg = 0, sa = 0;
  for (const ImuSample& s : samples) {
    sg += s.gyro_rad_s.squaredNorm();
    sa += (s.accel_m_s2 - Eigen::Vector3d(0, 0, 9.81)).squaredNorm();
  }
  const double n = 3.0 * samples.size();
  // density * sqrt(rate): 1.6968e-4 * sqrt(200) = 2.40e-3 rad/s; 2e-3 * sqrt(200) = 2.83e-2 m/s^2.
  EXPECT_NEAR(std::sqrt(sg / n), 2.3997e-3, 0.03 * 2.3997e-3);
  EXPECT_NEAR(std::sqrt(sa / n), 2.8284e-2, 0.03 * 2.8284e-2);
  // Same seed, same samples.
  const auto again = SimulateImu(still, params, opt);
  EXPECT_EQ(again[123].gyro_rad_s, samples[123].gyro_rad_s);
}

}  // namespace
}  // namespace imumatch
