#include "imumatch/imu/time_offset.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/sim/imu_simulator.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {
namespace {

// A handheld shake (the sinusoid trajectory: angular velocity up to 0.25 rad/s, angular
// acceleration up to 1.1 rad/s^2) sampled by the EuRoC IMU at 200 Hz with its white noise and a
// constant gyro bias. A camera whose clock runs offset_s behind the IMU's (t_imu = t_cam +
// offset) measures, between its frames at camera times t_a and t_b, the rotation the body made
// between IMU times t_a + offset and t_b + offset.
struct Shake {
  SinusoidTrajectory traj;
  ImuParams params = ImuParams::EurocAdis16448();
  ImuBuffer buffer;
  explicit Shake(const Eigen::Vector3d& bias)
      : traj([] {
          SinusoidTrajectory::Params p;
          p.duration_s = 8.0;
          return p;
        }()) {
    ImuSimulatorOptions sim;
    sim.add_bias_walk = false;
    sim.initial_bias.gyro = bias;
    sim.seed = 5;
    for (const ImuSample& s : SimulateImu(traj, params, sim)) buffer.Push(s);
  }

  // n frames at 20 Hz from camera time 0.5 s, rotations measured to sigma_meas rad.
  std::vector<RotationObservation> Observe(double offset_s, int n, double sigma_meas,
                                           std::mt19937_64& rng) const {
    std::normal_distribution<double> normal(0.0, sigma_meas);
    std::vector<RotationObservation> out;
    for (int k = 0; k < n; ++k) {
      const double ta = 0.5 + 0.05 * k, tb = ta + 0.05;
      const Eigen::Quaterniond truth = traj.WorldFromBody(ta + offset_s).rotation.conjugate() *
                                       traj.WorldFromBody(tb + offset_s).rotation;
      RotationObservation o;
      o.t_a_ns = SecondsToNs(ta);
      o.t_b_ns = SecondsToNs(tb);
      o.imu_a_from_imu_b = truth * ExpSO3(Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
      o.covariance = Eigen::Matrix3d::Identity() * sigma_meas * sigma_meas;
      out.push_back(o);
    }
    return out;
  }
};

const Eigen::Vector3d kBias(0.012, -0.021, 0.078);  // MH_05's size

// The offset that produced the measurements is found within 3 of its sigmas and 0.5 ms, for
// either sign and for none; the sigma is what 120 rotations measured to 2e-4 rad allow
// (sub-millisecond) and the search's edges are never reached.
TEST(TimeOffset, RecoversTheOffsetTheMeasurementsWereTakenWith) {
  const Shake s(kBias);
  for (const double offset : {0.012, -0.007, 0.0, 0.031}) {
    std::mt19937_64 rng(3);
    const TimeOffsetEstimate est =
        EstimateTimeOffset(s.buffer, s.params, kBias, s.Observe(offset, 120, 2e-4, rng));
    ASSERT_TRUE(est.measured) << est.reason;
    EXPECT_NEAR(est.offset_s, offset, std::max(3.0 * est.sigma_s, 5e-4)) << offset;
    EXPECT_GT(est.sigma_s, 1e-5);
    EXPECT_LT(est.sigma_s, 1e-3);
    EXPECT_EQ(est.observations, 120);
    EXPECT_GE(est.inliers, 118);
    if (offset != 0.0) {
      EXPECT_GT(est.cost_at_zero, est.cost + 25.0);
    }
  }
}

// A bias that was never estimated (zero given, the IMU's is kBias) turns every rotation by -dt b:
// the offset is still found, and the correction solved with it is the bias.
TEST(TimeOffset, SolvesAConstantBiasErrorWithTheOffset) {
  const Shake s(kBias);
  std::mt19937_64 rng(4);
  const TimeOffsetEstimate est = EstimateTimeOffset(s.buffer, s.params, Eigen::Vector3d::Zero(),
                                                    s.Observe(0.015, 120, 2e-4, rng));
  ASSERT_TRUE(est.measured) << est.reason;
  EXPECT_NEAR(est.offset_s, 0.015, std::max(3.0 * est.sigma_s, 5e-4));
  EXPECT_LT((est.gyro_bias_correction - kBias).norm(), 2e-3)
      << est.gyro_bias_correction.transpose();
}

// A tenth of the fits locked onto something else (rotations 2 deg off): truncated, they do not
// move the offset, and they are not counted as inliers.
TEST(TimeOffset, IgnoresFitsThatLockedOntoSomethingElse) {
  const Shake s(kBias);
  std::mt19937_64 rng(5);
  std::vector<RotationObservation> obs = s.Observe(0.010, 120, 2e-4, rng);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (size_t k = 0; k < obs.size(); k += 10) {
    const Eigen::Vector3d axis =
        Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)).normalized();
    obs[k].imu_a_from_imu_b = obs[k].imu_a_from_imu_b * ExpSO3(axis * 2.0 * M_PI / 180.0);
  }
  const TimeOffsetEstimate est = EstimateTimeOffset(s.buffer, s.params, kBias, obs);
  ASSERT_TRUE(est.measured) << est.reason;
  EXPECT_NEAR(est.offset_s, 0.010, std::max(3.0 * est.sigma_s, 5e-4));
  EXPECT_LE(est.inliers, 108);
  EXPECT_GE(est.inliers, 106);
}

// Fits of consecutive pairs share errors their covariances do not state (the pairs share a frame,
// a scene's errors last over many frames): here each run of 12 consecutive rotations shares an
// error three times each one's own. Taken as independent (the parabola's sigma, though scaled by
// the scatter), the estimate misses by more than 3 of its sigmas in 7 of 30 draws (errors up to 6
// of its sigmas); the block jackknife's sigma, 2-3x larger, covers every draw. On independent
// errors the jackknife's is the smaller (0.74x on average) and the parabola's stands.
TEST(TimeOffset, TheJackknifeSigmaCoversErrorsSharedByConsecutiveFits) {
  const Shake s(kBias);
  TimeOffsetOptions parabola;
  parabola.jackknife_blocks = 0;
  const double truth = 0.012;
  const int draws = 30;
  int missed_parabola = 0, missed_jackknife = 0;
  double ratio_independent = 0.0;
  for (int draw = 0; draw < draws; ++draw) {
    std::mt19937_64 rng(100 + static_cast<uint64_t>(draw));
    std::vector<RotationObservation> obs = s.Observe(truth, 120, 2e-4, rng);
    const TimeOffsetEstimate independent = EstimateTimeOffset(s.buffer, s.params, kBias, obs);
    const TimeOffsetEstimate independent_parabola =
        EstimateTimeOffset(s.buffer, s.params, kBias, obs, parabola);
    ASSERT_TRUE(independent.measured && independent_parabola.measured) << independent.reason;
    EXPECT_EQ(independent_parabola.jackknife_sigma_s, 0.0);
    EXPECT_EQ(independent.offset_s, independent_parabola.offset_s);
    ratio_independent += independent.jackknife_sigma_s / independent_parabola.sigma_s / draws;
    std::normal_distribution<double> shared(0.0, 6e-4);
    for (size_t run = 0; run < obs.size(); run += 12) {
      const Eigen::Vector3d e(shared(rng), shared(rng), shared(rng));
      for (size_t i = run; i < run + 12; ++i) {
        obs[i].imu_a_from_imu_b = obs[i].imu_a_from_imu_b * ExpSO3(e);
      }
    }
    const TimeOffsetEstimate with = EstimateTimeOffset(s.buffer, s.params, kBias, obs);
    const TimeOffsetEstimate without = EstimateTimeOffset(s.buffer, s.params, kBias, obs, parabola);
    ASSERT_TRUE(with.measured && without.measured) << with.reason << " / " << without.reason;
    EXPECT_GE(with.sigma_s, without.sigma_s);
    missed_jackknife += std::fabs(with.offset_s - truth) > 3.0 * with.sigma_s;
    missed_parabola += std::fabs(without.offset_s - truth) > 3.0 * without.sigma_s;
  }
  std::printf(
      "misses beyond 3 sigma: parabola %d, jackknife %d of %d; independent errors: "
      "jackknife / parabola sigma %.2f\n",
      missed_parabola, missed_jackknife, draws, ratio_independent);
  EXPECT_GE(missed_parabola, 5);
  EXPECT_LE(missed_jackknife, 2);
  EXPECT_GT(ratio_independent, 0.6);
  EXPECT_LT(ratio_independent, 1.5);
}

// A gyro log drawn from an angular velocity w(t): count samples, sample_ns apart, from 0.
using AngularVelocity = std::function<Eigen::Vector3d(double)>;
ImuBuffer GyroLog(const AngularVelocity& w, int64_t sample_ns, int64_t count) {
  ImuBuffer buffer;
  for (int64_t k = 0; k < count; ++k) {
    ImuSample sample;
    sample.t_ns = k * sample_ns;
    sample.gyro_rad_s = w(NsToSeconds(sample.t_ns));
    sample.accel_m_s2 = Eigen::Vector3d(0.0, 0.0, 9.81);
    buffer.Push(sample);
  }
  return buffer;
}

// The rotations a camera whose clock runs offset_s behind the IMU's measures between n frames
// 50 ms apart from camera time t0_s, with the given variance per axis: w integrated over the
// shifted intervals by the midpoint rule on steps of step_s (from w itself, not the samples).
std::vector<RotationObservation> RotationsSeen(const AngularVelocity& w, double offset_s,
                                               double t0_s, int n, double variance, double step_s) {
  std::vector<RotationObservation> obs;
  const int steps = static_cast<int>(std::lround(0.05 / step_s));
  for (int k = 0; k < n; ++k) {
    RotationObservation o;
    o.t_a_ns = SecondsToNs(t0_s + 0.05 * k);
    o.t_b_ns = o.t_a_ns + SecondsToNs(0.05);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    for (int j = 0; j < steps; ++j) {
      const double t = NsToSeconds(o.t_a_ns) + offset_s + step_s * (j + 0.5);
      q = (q * ExpSO3(w(t) * step_s)).normalized();
    }
    o.imu_a_from_imu_b = q;
    o.covariance = Eigen::Matrix3d::Identity() * variance;
    obs.push_back(o);
  }
  return obs;
}

// Where the angular velocity varies during one run of the fits only, that run alone shows the
// offset: the curvature gives a sigma, but without that run nothing is measured, so the jackknife
// does not call the offset measured (the curvature alone does).
TEST(TimeOffset, AnOffsetShownByOneRunOfFitsAloneIsNotMeasured) {
  ImuParams params = ImuParams::EurocAdis16448();
  const Eigen::Vector3d w0(0.1, -0.3, 0.5);
  auto w = [&](double t) {
    // One period of a 0.3 s wiggle, 0.3 rad/s about x, from 2.1 s; constant elsewhere. Only the
    // fits 30-39 (the fourth run of ten) read it at some offset of the +-50 ms searched.
    if (t < 2.1 || t > 2.4) return w0;
    return Eigen::Vector3d(w0 +
                           Eigen::Vector3d(0.3, 0, 0) * std::sin(2.0 * M_PI * (t - 2.1) / 0.3));
  };
  const ImuBuffer buffer = GyroLog(w, 5'000'000, 1601);
  const double offset = 0.01;
  const std::vector<RotationObservation> obs = RotationsSeen(w, offset, 0.5, 100, 4e-8, 0.001);
  TimeOffsetOptions curvature_only;
  curvature_only.jackknife_blocks = 0;
  const TimeOffsetEstimate one =
      EstimateTimeOffset(buffer, params, Eigen::Vector3d::Zero(), obs, curvature_only);
  ASSERT_TRUE(one.measured) << one.reason;
  EXPECT_NEAR(one.offset_s, offset, 1e-3);
  const TimeOffsetEstimate est = EstimateTimeOffset(buffer, params, Eigen::Vector3d::Zero(), obs);
  EXPECT_FALSE(est.measured);
  EXPECT_NE(est.reason.find("not shown without one of the 10 runs of consecutive fitted rotations"),
            std::string::npos)
      << est.reason;
}

// A vibration of period 35 ms repeats the rotations at every shift of 35 ms: the fits taken 10
// ms off fit -25 and +45 ms as well, and the estimate says it cannot tell them apart instead of
// picking one. The same fits without the vibration's repeats (a second, slower component) are
// measured.
TEST(TimeOffset, APeriodicMotionIsAmbiguous) {
  ImuParams params = ImuParams::EurocAdis16448();
  const Eigen::Vector3d w0(0.1, -0.3, 0.5);
  auto vibration = [&](double t) {
    return Eigen::Vector3d(w0 + Eigen::Vector3d(0.0, 0.2, 0.0) * std::sin(2.0 * M_PI * t / 0.035));
  };
  // 1 kHz: the vibration sampled 35 times a period.
  const ImuBuffer periodic = GyroLog(vibration, 1'000'000, 1601);
  const std::vector<RotationObservation> obs = RotationsSeen(vibration, 0.010, 0.1, 20, 1e-8, 1e-4);
  const TimeOffsetEstimate est = EstimateTimeOffset(periodic, params, Eigen::Vector3d::Zero(), obs);
  EXPECT_FALSE(est.measured);
  EXPECT_NE(est.reason.find("ambiguous: a second minimum of the cost at"), std::string::npos)
      << est.reason;
  TimeOffsetOptions no_check;
  no_check.ambiguity_chi2 = 0.0;
  no_check.jackknife_blocks = 0;
  const TimeOffsetEstimate picked =
      EstimateTimeOffset(periodic, params, Eigen::Vector3d::Zero(), obs, no_check);
  ASSERT_TRUE(picked.measured) << picked.reason;
  // One of the repeats, to the grid's resolution.
  const double folded = std::remainder(picked.offset_s - 0.010, 0.035);
  EXPECT_NEAR(folded, 0.0, 1e-3) << picked.offset_s;
  // A slow turn added to the vibration does not repeat: one minimum, at the offset.
  auto vibration_and_turn = [&](double t) {
    return Eigen::Vector3d(vibration(t) +
                           Eigen::Vector3d(0.3 * std::sin(2.0 * M_PI * t / 0.7), 0.0, 0.0));
  };
  const ImuBuffer aperiodic = GyroLog(vibration_and_turn, 1'000'000, 1601);
  const std::vector<RotationObservation> obs2 =
      RotationsSeen(vibration_and_turn, 0.010, 0.1, 20, 1e-8, 1e-4);
  const TimeOffsetEstimate one =
      EstimateTimeOffset(aperiodic, params, Eigen::Vector3d::Zero(), obs2);
  ASSERT_TRUE(one.measured) << one.reason;
  EXPECT_NEAR(one.offset_s, 0.010, std::max(3.0 * one.sigma_s, 5e-4));
}

// Turning at a constant rate, every offset gives the same rotations: nothing is measured, and the
// report says why instead of giving a number.
TEST(TimeOffset, ConstantAngularVelocityShowsNoOffset) {
  ImuParams params = ImuParams::EurocAdis16448();
  const Eigen::Vector3d w(0.1, -0.3, 0.5);
  auto constant = [&](double) { return w; };
  const ImuBuffer buffer = GyroLog(constant, 5'000'000, 1601);
  // One integration step per interval: ExpSO3(w * 0.05) each (any offset reads the same).
  const std::vector<RotationObservation> obs = RotationsSeen(constant, 0.0, 0.5, 100, 4e-8, 0.05);
  const TimeOffsetEstimate est = EstimateTimeOffset(buffer, params, Eigen::Vector3d::Zero(), obs);
  EXPECT_FALSE(est.measured);
  EXPECT_NE(est.reason.find("do not vary enough"), std::string::npos) << est.reason;
  EXPECT_NE(est.Summary().find("not measured"), std::string::npos);
  // A measured offset that rounds to zero reads +0.0, not -0.0.
  TimeOffsetEstimate tiny;
  tiny.measured = true;
  tiny.offset_s = -3e-6;
  tiny.sigma_s = 2e-4;
  tiny.inliers = 51;
  tiny.observations = 52;
  EXPECT_EQ(tiny.Summary(), "+0.0 ms (+- 0.2 ms, 51 of 52 fitted rotations)");
}

// Rotations outside the log at some offset of the search are not used; too few left is said.
TEST(TimeOffset, NeedsObservationsInsideTheLogAtEveryOffset) {
  const Shake s(kBias);
  std::mt19937_64 rng(6);
  std::vector<RotationObservation> obs = s.Observe(0.0, 5, 2e-4, rng);
  RotationObservation early = obs[0];
  early.t_a_ns = SecondsToNs(0.01);  // 0.01 - 0.05 s is before the log
  early.t_b_ns = SecondsToNs(0.06);
  obs.push_back(early);
  const TimeOffsetEstimate est = EstimateTimeOffset(s.buffer, s.params, kBias, obs);
  EXPECT_FALSE(est.measured);
  EXPECT_EQ(est.observations, 5);
  EXPECT_NE(est.reason.find("5 fitted rotations inside the IMU log, 10 needed"), std::string::npos)
      << est.reason;
}

TEST(TimeOffset, RefusesInvalidObservationsAndOptions) {
  const Shake s(kBias);
  std::mt19937_64 rng(7);
  const std::vector<RotationObservation> good = s.Observe(0.0, 20, 2e-4, rng);
  std::vector<RotationObservation> obs = good;
  obs[3].t_b_ns = obs[3].t_a_ns;
  EXPECT_THROW(EstimateTimeOffset(s.buffer, s.params, kBias, obs), InvalidArgument);
  obs = good;
  obs[4].imu_a_from_imu_b.coeffs() *= 2.0;
  EXPECT_THROW(EstimateTimeOffset(s.buffer, s.params, kBias, obs), InvalidArgument);
  // For reports: the error as the reason of an estimate not measured.
  const TimeOffsetEstimate tried = TryEstimateTimeOffset(s.buffer, s.params, kBias, obs);
  EXPECT_FALSE(tried.measured);
  EXPECT_NE(tried.reason.find("rotation observation 4: not a unit quaternion"), std::string::npos)
      << tried.reason;
  obs = good;
  obs[5].covariance(0, 0) = std::nan("");
  EXPECT_THROW(EstimateTimeOffset(s.buffer, s.params, kBias, obs), InvalidArgument);
  obs = good;
  obs[6].covariance = -obs[6].covariance;
  EXPECT_THROW(EstimateTimeOffset(s.buffer, s.params, kBias, obs), InvalidArgument);
  TimeOffsetOptions bad;
  bad.step_s = 0.03;  // more than a quarter of the range
  EXPECT_THROW(EstimateTimeOffset(s.buffer, s.params, kBias, good, bad), InvalidArgument);
  bad = TimeOffsetOptions();
  bad.max_offset_s = std::nan("");
  EXPECT_THROW(EstimateTimeOffset(s.buffer, s.params, kBias, good, bad), InvalidArgument);
  // A grid of 10^9 steps (1 ns over +-1 s) is refused before any work, not left to exhaust memory.
  bad = TimeOffsetOptions();
  bad.max_offset_s = 1.0;
  bad.step_s = 1e-9;
  try {
    EstimateTimeOffset(s.buffer, s.params, kBias, good, bad);
    ADD_FAILURE() << "a 10^9-step grid was taken";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("at most 10000 grid steps"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(TryEstimateTimeOffset(s.buffer, s.params, kBias, good, bad).measured);
  bad = TimeOffsetOptions();
  bad.min_observations = 3;  // fewer than the four unknowns
  EXPECT_THROW(EstimateTimeOffset(s.buffer, s.params, kBias, good, bad), InvalidArgument);
}

// An offset beyond the range searched: the cost falls towards the grid's edge, and the estimate
// says so instead of giving the edge as the offset.
TEST(TimeOffset, AnOffsetBeyondTheSearchSaysSo) {
  const Shake s(kBias);
  std::mt19937_64 rng(8);
  TimeOffsetOptions options;
  options.max_offset_s = 0.02;
  const TimeOffsetEstimate est =
      EstimateTimeOffset(s.buffer, s.params, kBias, s.Observe(0.035, 120, 2e-4, rng), options);
  EXPECT_FALSE(est.measured);
  EXPECT_NE(est.reason.find("towards the edge of the +-20 ms searched"), std::string::npos)
      << est.reason;
  // The searched range widened to hold it: found.
  options.max_offset_s = 0.05;
  std::mt19937_64 rng2(8);
  const TimeOffsetEstimate wide =
      EstimateTimeOffset(s.buffer, s.params, kBias, s.Observe(0.035, 120, 2e-4, rng2), options);
  ASSERT_TRUE(wide.measured) << wide.reason;
  EXPECT_NEAR(wide.offset_s, 0.035, std::max(3.0 * wide.sigma_s, 5e-4));
}

// The advice, hand-checked: given only for a measured offset of at least 2 ms beyond 3 sigmas,
// with the total to set (the shift applied plus the offset, seconds to 0.1 ms), both places to set
// it and the units.
TEST(TimeOffset, AdvisesTheTotalShiftOnlyWhenItIsWorthSetting) {
  TimeOffsetEstimate est;
  est.measured = true;
  est.offset_s = 0.0098;
  est.sigma_s = 0.0002;
  est.inliers = 183;
  est.observations = 190;
  const std::string advice = TimeOffsetAdvice(est, 0.0004);
  EXPECT_NE(advice.find("look +9.8 ms apart (+- 0.2 ms) beyond the timeshift_cam_imu applied "
                        "(0.0004 s)"),
            std::string::npos)
      << advice;
  EXPECT_NE(advice.find("set timeshift_cam_imu to 0.0102 s"), std::string::npos) << advice;
  EXPECT_NE(advice.find("cam0/sensor.yaml or Kalibr's camchain.yaml, or --timeshift-cam-imu "
                        "0.0102)"),
            std::string::npos)
      << advice;
  // What cancels the shift applied reads 0, not -0 or 1e-18.
  EXPECT_NE(TimeOffsetAdvice(est, -0.0098).find("set timeshift_cam_imu to 0.0 s"),
            std::string::npos);
  // Not worth it: under 2 ms, within 3 sigmas, or not measured.
  est.offset_s = 0.0019;
  est.sigma_s = 1e-5;
  EXPECT_EQ(TimeOffsetAdvice(est, 0.0), "");
  est.offset_s = -0.006;
  est.sigma_s = 0.0021;  // 2.86 sigmas
  EXPECT_EQ(TimeOffsetAdvice(est, 0.0), "");
  est.sigma_s = 0.0019;  // 3.16 sigmas
  EXPECT_NE(TimeOffsetAdvice(est, 0.0).find("look -6.0 ms apart (+- 1.9 ms)"), std::string::npos);
  TimeOffsetAdviceOptions strict;
  strict.min_sigmas = 5.0;
  EXPECT_EQ(TimeOffsetAdvice(est, 0.0, strict), "");
  est.measured = false;
  EXPECT_EQ(TimeOffsetAdvice(est, 0.0), "");
  // A sigma below what one decimal shows reads "< 0.1", not "0.0".
  est.measured = true;
  est.offset_s = 0.0123;
  est.sigma_s = 2e-5;
  EXPECT_EQ(est.Summary(), "+12.3 ms (+- < 0.1 ms, 183 of 190 fitted rotations)");
  EXPECT_EQ(FormatOffsetMs(-0.00004), "+0.0 ms");
  EXPECT_EQ(FormatOffsetMs(-0.0123), "-12.3 ms");
}

}  // namespace
}  // namespace imumatch
