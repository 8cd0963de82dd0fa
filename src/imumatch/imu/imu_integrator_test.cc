#include "imumatch/imu/imu_integrator.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/sim/imu_simulator.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {
namespace {

constexpr int64_t kT0 = 1'000'000'000'000;  // an arbitrary epoch: 1000 s

ImuBuffer NoiseFreeBuffer(const Trajectory& traj, double rate_hz = 200.0) {
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  opt.rate_hz = rate_hz;
  opt.t0_ns = kT0;
  ImuBuffer buffer;
  for (const ImuSample& s : SimulateImu(traj, ImuParams::Ideal(), opt)) buffer.Push(s);
  return buffer;
}

struct Case {
  const char* name;
  std::shared_ptr<Trajectory> traj;
};

std::vector<Case> AnalyticCases() {
  SinusoidTrajectory::Params p;  // default: a handheld shake of 3-6 deg and a few cm, ~0.5-1 Hz
  return {
      {"constant_rate", std::make_shared<ConstantRateTrajectory>(
                            Rigid3d(FromEulerZYX(0.1, 0.2, 0.3), Eigen::Vector3d(1, 0, 1)),
                            Eigen::Vector3d(0.4, -0.7, 1.1), Eigen::Vector3d(0.3, 0.1, 0), 2.0)},
      {"circle", std::make_shared<CircleTrajectory>(1.5, 1.2, 1.0, 2.0)},
      {"sinusoid", std::make_shared<SinusoidTrajectory>(p)},
  };
}

// Noise-free 200 Hz samples over a 50 ms frame interval whose ends fall between samples:
// the rotation error against the analytic trajectory is below 1e-6 rad, position below 5e-6 m
// (measured: rotation <= 6e-7 rad on the shake, ~1e-15 for constant rate and circle).
TEST(Preintegrate, MatchesAnalyticTrajectories) {
  for (const Case& c : AnalyticCases()) {
    const ImuBuffer buffer = NoiseFreeBuffer(*c.traj);
    for (double ta : {0.3013, 0.7771, 1.2502}) {
      const double tb = ta + 0.05;
      const int64_t ta_ns = kT0 + SecondsToNs(ta), tb_ns = kT0 + SecondsToNs(tb);
      const ImuPreintegration pim =
          Preintegrate(buffer.Slice(ta_ns, tb_ns), ImuBias(), ImuParams::Ideal());
      const Rigid3d pa = c.traj->WorldFromBody(NsToSeconds(ta_ns - kT0));
      const Rigid3d pb = c.traj->WorldFromBody(NsToSeconds(tb_ns - kT0));
      const double rot_err =
          RotationDistance(pim.delta_rotation, pa.rotation.conjugate() * pb.rotation);
      EXPECT_LT(rot_err, 1e-6) << c.name << " ta=" << ta;
      std::printf("%s ta=%.4f rotation error %.3g rad\n", c.name, ta, rot_err);

      NavState sa;
      sa.t_ns = ta_ns;
      sa.world_from_imu = pa;
      sa.velocity_in_world = c.traj->VelocityInWorld(NsToSeconds(ta_ns - kT0));
      const NavState sb = Propagate(sa, pim, ImuParams().gravity_in_world);
      EXPECT_LT((sb.world_from_imu.translation - pb.translation).norm(), 5e-6) << c.name;
      EXPECT_LT((sb.velocity_in_world - c.traj->VelocityInWorld(NsToSeconds(tb_ns - kT0))).norm(),
                1e-4)
          << c.name;
    }
  }
}

// A violent shake (0.2-0.4 rad at 0.7-1.3 Hz, rates up to 2.5 rad/s): the midpoint rule's error
// is the trapezoid quadrature error of the rate, O(dt^2): doubling the IMU rate divides it by ~4.
TEST(Preintegrate, ErrorShrinksQuadraticallyWithRate) {
  SinusoidTrajectory::Params p;
  p.angle_amplitude_rad = Eigen::Vector3d(0.2, 0.3, 0.4);
  p.angle_frequency_hz = Eigen::Vector3d(1.3, 0.9, 0.7);
  SinusoidTrajectory traj(p);
  const int64_t ta_ns = kT0 + SecondsToNs(0.7771), tb_ns = ta_ns + 50'000'000;
  const Eigen::Quaterniond truth =
      traj.WorldFromBody(0.7771).rotation.conjugate() * traj.WorldFromBody(0.8271).rotation;
  double errors[2];
  int i = 0;
  for (double rate : {200.0, 400.0}) {
    const ImuPreintegration pim = Preintegrate(NoiseFreeBuffer(traj, rate).Slice(ta_ns, tb_ns),
                                               ImuBias(), ImuParams::Ideal());
    errors[i++] = RotationDistance(pim.delta_rotation, truth);
  }
  EXPECT_LT(errors[0], 2e-5);
  EXPECT_NEAR(errors[0] / errors[1], 4.0, 1.0);
}

TEST(Preintegrate, GyroBiasIsSubtracted) {
  ConstantRateTrajectory traj(Rigid3d(), Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d::Zero(), 1.0);
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  opt.initial_bias.gyro = Eigen::Vector3d(0.01, -0.02, 0.03);
  opt.initial_bias.accel = Eigen::Vector3d(0.1, 0.2, -0.1);
  ImuBuffer buffer;
  for (const ImuSample& s : SimulateImu(traj, ImuParams::Ideal(), opt)) buffer.Push(s);
  const auto samples = buffer.Slice(SecondsToNs(0.1), SecondsToNs(0.6));
  const ImuPreintegration with_bias = Preintegrate(samples, opt.initial_bias, ImuParams::Ideal());
  const ImuPreintegration without = Preintegrate(samples, ImuBias(), ImuParams::Ideal());
  // Truth: 0.25 rad about z, and a still body: dv = -g_world in frame i integrated = +9.81 z * 0.5
  // s.
  EXPECT_LT(RotationDistance(with_bias.delta_rotation,
                             Eigen::Quaterniond(Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitZ()))),
            1e-9);
  EXPECT_GT(RotationDistance(without.delta_rotation, with_bias.delta_rotation), 0.015);
  EXPECT_LT((with_bias.delta_velocity - Eigen::Vector3d(0, 0, 9.81 * 0.5)).norm(), 1e-9);
}

TEST(Preintegrate, CovarianceMatchesMonteCarlo) {
  // Noisy samples around a still IMU: the spread of 300 noisy preintegrations over 0.5 s matches
  // the propagated covariance (rotation and position blocks, within 20%).
  ConstantRateTrajectory traj(Rigid3d(), Eigen::Vector3d(0, 0, 0.3), Eigen::Vector3d::Zero(), 0.6);
  const ImuParams params = ImuParams::ConsumerMems();
  ImuSimulatorOptions opt;
  opt.add_bias_walk = false;
  ImuSimulatorOptions clean = opt;
  clean.add_noise = false;
  const auto truth_samples = SimulateImu(traj, params, clean);
  const ImuPreintegration truth = Preintegrate(truth_samples, ImuBias(), params);
  double theta_var = 0, pos_var = 0;
  const int runs = 300;
  for (int r = 0; r < runs; ++r) {
    opt.seed = 1000 + r;
    const ImuPreintegration pim = Preintegrate(SimulateImu(traj, params, opt), ImuBias(), params);
    theta_var += LogSO3(truth.delta_rotation.conjugate() * pim.delta_rotation).squaredNorm();
    pos_var += (pim.delta_position - truth.delta_position).squaredNorm();
  }
  theta_var /= runs;
  pos_var /= runs;
  EXPECT_NEAR(theta_var / (truth.covariance.block<3, 3>(0, 0).trace()), 1.0, 0.2);
  EXPECT_NEAR(pos_var / (truth.covariance.block<3, 3>(6, 6).trace()), 1.0, 0.2);
}

TEST(IntegratePaper, SumsEulerAnglesAndIgnoresGravity) {
  // A still, level IMU: the paper's method reads gravity as acceleration, so over 0.1 s it
  // "moves" 0.5 * 9.81 * 0.1^2 = 0.04905 m up; the SO(3) integrator with gravity removed says 0.
  ConstantRateTrajectory still(Rigid3d(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1.0);
  const ImuBuffer buffer = NoiseFreeBuffer(still);
  const auto samples = buffer.Slice(kT0, kT0 + 100'000'000);
  const PaperIntegration paper = IntegratePaper(samples, Eigen::Vector3d::Zero());
  EXPECT_NEAR(paper.imu_i_from_imu_j.translation.z(), 0.04905, 1e-9);
  EXPECT_NEAR(paper.velocity_end.z(), 0.981, 1e-9);
  // Constant yaw rate: Euler sum is exact for a single axis.
  ConstantRateTrajectory yaw(Rigid3d(), Eigen::Vector3d(0, 0, 0.8), Eigen::Vector3d::Zero(), 1.0);
  const PaperIntegration p2 =
      IntegratePaper(NoiseFreeBuffer(yaw).Slice(kT0, kT0 + 500'000'000), Eigen::Vector3d::Zero());
  EXPECT_NEAR(RotationAngle(p2.imu_i_from_imu_j.rotation), 0.4, 1e-9);
}

TEST(InitializeFromStill, FindsGyroBiasAndGravity) {
  // Tilted still IMU with a gyro bias and noise.
  ConstantRateTrajectory still(Rigid3d(FromEulerZYX(0.2, -0.1, 1.0), Eigen::Vector3d::Zero()),
                               Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 2.0);
  ImuSimulatorOptions opt;
  opt.add_bias_walk = false;
  opt.initial_bias.gyro = Eigen::Vector3d(0.002, -0.021, 0.077);
  ImuBuffer buffer;
  const ImuParams params;
  for (const ImuSample& s : SimulateImu(still, params, opt)) buffer.Push(s);
  const StillInitialization init = InitializeFromStill(buffer, 0, SecondsToNs(2.0), params);
  EXPECT_LT((init.bias.gyro - opt.initial_bias.gyro).norm(), 5 * init.gyro_bias_sigma);
  EXPECT_LT(init.gyro_bias_sigma, 1e-3);
  // Gravity direction: roll and pitch recovered (yaw is not observable).
  const Eigen::Vector3d down_true =
      still.WorldFromBody(0).rotation.conjugate() * Eigen::Vector3d(0, 0, -9.81);
  EXPECT_LT((init.gravity_in_imu - down_true).norm(), 0.01);
  EXPECT_LT(
      (init.world_from_imu.rotation * init.gravity_in_imu - Eigen::Vector3d(0, 0, -9.81)).norm(),
      1e-9);
}

TEST(InitializeFromStill, AGapInTheLogEndsThePeriodThere) {
  // Still for 2 s, then moving; 0.1 s of the log missing from 0.8 s on. The period stops at the
  // gap instead of failing, and the bias comes from the samples before it.
  ConstantRateTrajectory still(Rigid3d(FromEulerZYX(0.2, -0.1, 1.0), Eigen::Vector3d::Zero()),
                               Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 2.0);
  ImuSimulatorOptions opt;
  opt.add_bias_walk = false;
  opt.initial_bias.gyro = Eigen::Vector3d(0.002, -0.021, 0.077);
  const ImuParams params;
  ImuBuffer buffer;
  int64_t last_before_gap = 0;
  for (const ImuSample& s : SimulateImu(still, params, opt)) {
    if (s.t_ns > SecondsToNs(0.8) && s.t_ns < SecondsToNs(0.9)) continue;
    if (s.t_ns <= SecondsToNs(0.8)) last_before_gap = s.t_ns;
    buffer.Push(s);
  }
  EXPECT_THROW(buffer.Slice(0, SecondsToNs(1.5)), OutOfRange);
  const StillInitialization init = InitializeFromStill(buffer, 0, SecondsToNs(1.5), params);
  EXPECT_EQ(init.end_ns, last_before_gap);
  EXPECT_EQ(init.num_samples, static_cast<int>(last_before_gap / 5'000'000) + 1);  // 200 Hz
  EXPECT_LT((init.bias.gyro - opt.initial_bias.gyro).norm(), 5 * init.gyro_bias_sigma);
  // Without a gap the period runs to t1.
  EXPECT_EQ(InitializeFromStill(buffer, SecondsToNs(0.9), SecondsToNs(1.5), params).end_ns,
            SecondsToNs(1.5));
  // A gap right at the start leaves too few samples: refused, naming the gap.
  try {
    InitializeFromStill(buffer, SecondsToNs(0.75), SecondsToNs(1.5), params);
    ADD_FAILURE() << "no throw";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("before an IMU gap at 0.800"), std::string::npos)
        << e.what();
  }
}

TEST(InitializeFromStill, RejectsMotion) {
  ConstantRateTrajectory spin(Rigid3d(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 2.0);
  SinusoidTrajectory::Params p;
  p.angle_amplitude_rad = Eigen::Vector3d(0.5, 0.5, 0.5);
  SinusoidTrajectory shake(p);
  ImuBuffer buffer;
  ImuSimulatorOptions opt;
  for (const ImuSample& s : SimulateImu(shake, ImuParams(), opt)) buffer.Push(s);
  EXPECT_THROW(InitializeFromStill(buffer, 0, SecondsToNs(2.0), ImuParams()), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
