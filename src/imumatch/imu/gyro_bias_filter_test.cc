#include "imumatch/imu/gyro_bias_filter.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/sim/imu_simulator.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {
namespace {

// A handheld shake sampled by the EuRoC IMU (white noise on, a constant bias, no walk), and the
// true rotations imu_a_from_imu_b between 20 Hz frames, measured with rotation noise sigma_meas
// (a vision fit's precision).
struct ShakeWithBias {
  SinusoidTrajectory traj;
  ImuParams params = ImuParams::EurocAdis16448();
  ImuSimulatorOptions sim;
  ImuBuffer buffer;
  explicit ShakeWithBias(const Eigen::Vector3d& bias)
      : traj([] {
          SinusoidTrajectory::Params p;
          p.duration_s = 6.0;
          return p;
        }()) {
    sim.add_bias_walk = false;
    sim.initial_bias.gyro = bias;
    sim.seed = 7;
    for (const ImuSample& s : SimulateImu(traj, params, sim)) buffer.Push(s);
  }
  Eigen::Quaterniond TrueDelta(double ta, double tb) const {
    return traj.WorldFromBody(ta).rotation.conjugate() * traj.WorldFromBody(tb).rotation;
  }
};

constexpr double kFrameS = 0.05;

// Runs frames 0.1 s .. 0.1 + n * 50 ms through the filter, measurement noise sigma_meas (rad).
void Feed(const ShakeWithBias& s, GyroBiasFilter& f, int n, double sigma_meas,
          std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, sigma_meas);
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * sigma_meas * sigma_meas;
  for (int k = 0; k < n; ++k) {
    const double ta = 0.1 + k * kFrameS, tb = ta + kFrameS;
    const Eigen::Vector3d e(normal(rng), normal(rng), normal(rng));
    const Eigen::Quaterniond measured = s.TrueDelta(ta, tb) * ExpSO3(e);
    // The gate (probability 0.999) rejects about one correct measurement in 1000.
    f.Update(s.buffer.Slice(SecondsToNs(ta), SecondsToNs(tb)), s.params, measured, cov);
  }
}

// From no knowledge (zero, 0.1 rad/s), 100 frames (5 s) of rotations measured to 2e-4 rad find
// the simulator's bias (MH_05's size) within 4 of the filter's own sigmas, and that sigma is what
// the measurements allow: 2e-4 rad / 50 ms / sqrt(100) = 4e-4 rad/s per axis, within 2x.
TEST(GyroBiasFilter, LearnsTheBiasFromMeasuredRotations) {
  const Eigen::Vector3d truth(0.012, -0.031, 0.078);
  const ShakeWithBias s(truth);
  GyroBiasFilter f(Eigen::Vector3d::Zero(), 0.1, s.params.gyro_random_walk, SecondsToNs(0.1));
  std::mt19937_64 rng(11);
  Feed(s, f, 100, 2e-4, rng);
  EXPECT_GE(f.updates(), 98);
  const int64_t t_end = SecondsToNs(5.1);
  const Eigen::Matrix3d p = f.CovarianceAt(t_end);
  for (int i = 0; i < 3; ++i) {
    const double sigma = std::sqrt(p(i, i));
    EXPECT_NEAR(f.bias()[i], truth[i], 4.0 * sigma) << "axis " << i;
    EXPECT_GT(sigma, 2e-4);
    EXPECT_LT(sigma, 8e-4);
  }
  EXPECT_LT((f.bias() - truth).norm(), 2e-3);
  EXPECT_NEAR(f.SigmaAt(t_end), std::sqrt(p.eigenvalues().real().maxCoeff()), 1e-12);
}

// A rotation 3 deg away from the truth after convergence (a fit locked onto a moving object) fails
// the gate and leaves the bias; the bias's uncertainty grows with the random walk between updates.
TEST(GyroBiasFilter, GatesAWrongRotationAndGrowsWithTheRandomWalk) {
  const Eigen::Vector3d truth(0.0, 0.0, 0.05);
  const ShakeWithBias s(truth);
  GyroBiasFilter f(Eigen::Vector3d::Zero(), 0.1, s.params.gyro_random_walk, SecondsToNs(0.1));
  std::mt19937_64 rng(3);
  Feed(s, f, 40, 2e-4, rng);
  const Eigen::Vector3d before = f.bias();
  const int rejected_before = f.rejected();
  const double ta = 0.1 + 40 * kFrameS, tb = ta + kFrameS;
  const Eigen::Quaterniond wrong =
      s.TrueDelta(ta, tb) * ExpSO3(Eigen::Vector3d(0.0, 3.0 * M_PI / 180.0, 0.0));
  EXPECT_FALSE(f.Update(s.buffer.Slice(SecondsToNs(ta), SecondsToNs(tb)), s.params, wrong,
                        Eigen::Matrix3d::Identity() * 4e-8));
  EXPECT_GT(f.last_chi2(), 1000.0);
  EXPECT_EQ(f.rejected(), rejected_before + 1);
  EXPECT_EQ(f.bias(), before);
  const double walk = s.params.gyro_random_walk;
  const Eigen::Matrix3d p0 = f.CovarianceAt(SecondsToNs(ta));
  const Eigen::Matrix3d p1 = f.CovarianceAt(SecondsToNs(ta + 100.0));
  EXPECT_NEAR(p1(2, 2) - p0(2, 2), walk * walk * 100.0, 1e-15);
}

// With exact rotations the residual at the true bias is the gyro's white noise only: starting at
// the truth with a tiny sigma, the filter stays there (no drift from the update's linearisation).
TEST(GyroBiasFilter, StaysAtTheTruth) {
  const Eigen::Vector3d truth(-0.02, 0.01, 0.03);
  const ShakeWithBias s(truth);
  GyroBiasFilter f(truth, 1e-4, s.params.gyro_random_walk, SecondsToNs(0.1));
  std::mt19937_64 rng(5);
  Feed(s, f, 60, 1e-6, rng);
  EXPECT_LT((f.bias() - truth).norm(), 3e-4);
}

TEST(GyroBiasFilter, RejectsBadInput) {
  const ShakeWithBias s(Eigen::Vector3d::Zero());
  EXPECT_THROW(GyroBiasFilter(Eigen::Vector3d(NAN, 0, 0), 0.1, 1e-5, 0), InvalidArgument);
  EXPECT_THROW(GyroBiasFilter(Eigen::Vector3d::Zero(), -1.0, 1e-5, 0), InvalidArgument);
  GyroBiasFilterOptions bad;
  bad.gate_chi2 = 0.0;
  EXPECT_THROW(GyroBiasFilter(Eigen::Vector3d::Zero(), 0.1, 1e-5, 0, bad), InvalidArgument);
  GyroBiasFilter f(Eigen::Vector3d::Zero(), 0.1, 1e-5, SecondsToNs(0.1));
  const auto samples = s.buffer.Slice(SecondsToNs(0.2), SecondsToNs(0.25));
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  EXPECT_THROW(f.Update({samples.front()}, s.params, q, Eigen::Matrix3d::Identity()),
               InvalidArgument);
  EXPECT_THROW(f.Update(samples, s.params, q, -Eigen::Matrix3d::Identity()), InvalidArgument);
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(0, 1) = NAN;
  EXPECT_THROW(f.Update(samples, s.params, q, nan), InvalidArgument);
  EXPECT_THROW(
      f.Update(samples, s.params, Eigen::Quaterniond(2, 0, 0, 0), Eigen::Matrix3d::Identity()),
      InvalidArgument);
  // Samples before the filter's time.
  EXPECT_THROW(f.Update(s.buffer.Slice(SecondsToNs(0.0), SecondsToNs(0.05)), s.params, q,
                        Eigen::Matrix3d::Identity()),
               InvalidArgument);
}

}  // namespace
}  // namespace imumatch
