#include "imumatch/sim/spline_trajectory.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/sim/motions.h"

namespace imumatch {
namespace {

constexpr int64_t kT0Ns = 1305031102175304000;  // a TUM-like absolute timestamp

std::vector<StampedPose> Sample(const Trajectory& traj, double rate_hz, double noise_m = 0.0,
                                double noise_rad = 0.0) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<StampedPose> poses;
  const int64_t step_ns = static_cast<int64_t>(std::llround(1e9 / rate_hz));
  for (int64_t k = 0; k * step_ns <= static_cast<int64_t>(traj.EndTime() * 1e9); ++k) {
    StampedPose p;
    p.t_ns = kT0Ns + k * step_ns;
    p.world_from_body = traj.WorldFromBody(static_cast<double>(k * step_ns) * 1e-9);
    p.world_from_body.translation += noise_m * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    p.world_from_body.rotation =
        p.world_from_body.rotation *
        ExpSO3(noise_rad * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)));
    if (k % 2 == 1) p.world_from_body.rotation.coeffs() *= -1.0;  // same rotation, other sign
    poses.push_back(p);
  }
  return poses;
}

struct FitErrors {
  double position = 0, rotation = 0, velocity = 0, accel = 0, omega = 0;  // max over the interior
  double velocity_rms = 0, omega_rms = 0;                                 // RMS of the true signals
};

FitErrors Compare(const Trajectory& truth, const SplineTrajectory& spline) {
  FitErrors e;
  int n = 0;
  // Skip the first and last 0.1 s (end effects of the fit).
  for (double t = 0.1; t < truth.EndTime() - 0.1; t += 0.0037) {
    const Rigid3d a = truth.WorldFromBody(t), b = spline.WorldFromBody(t);
    e.position = std::max(e.position, (a.translation - b.translation).norm());
    e.rotation = std::max(e.rotation, RotationDistance(a.rotation, b.rotation));
    e.velocity =
        std::max(e.velocity, (truth.VelocityInWorld(t) - spline.VelocityInWorld(t)).norm());
    e.accel =
        std::max(e.accel, (truth.AccelerationInWorld(t) - spline.AccelerationInWorld(t)).norm());
    e.omega = std::max(e.omega,
                       (truth.AngularVelocityInBody(t) - spline.AngularVelocityInBody(t)).norm());
    e.velocity_rms += truth.VelocityInWorld(t).squaredNorm();
    e.omega_rms += truth.AngularVelocityInBody(t).squaredNorm();
    ++n;
  }
  e.velocity_rms = std::sqrt(e.velocity_rms / n);
  e.omega_rms = std::sqrt(e.omega_rms / n);
  return e;
}

TEST(SplineTrajectoryTest, ReproducesAnAnalyticTrajectorySampledAt100Hz) {
  MotionOptions options;
  options.duration_s = 3.0;
  SplineFitOptions fine;
  fine.knot_spacing_s = 0.02;
  for (const char* name : {"shake", "walk", "fast_rotation"}) {
    const auto truth = MakeMotion(name, options);
    const std::vector<StampedPose> poses = Sample(*truth, 100.0);
    // Knots every 20 ms: close to the analytic trajectory including acceleration.
    const SplineTrajectory spline(poses, fine);
    EXPECT_EQ(spline.t0_ns(), kT0Ns);
    EXPECT_NEAR(spline.EndTime(), 4.0, 1e-9);
    FitErrors e = Compare(*truth, spline);
    std::printf(
        "%s (20 ms knots): pos %.1e m rot %.1e rad vel %.1e m/s (rms %.2f) acc %.1e m/s2 "
        "omega %.1e rad/s (rms %.2f)\n",
        name, e.position, e.rotation, e.velocity, e.velocity_rms, e.accel, e.omega, e.omega_rms);
    EXPECT_LT(e.position, 1e-5) << name;
    EXPECT_LT(e.rotation, 2e-5) << name;
    EXPECT_LT(e.velocity, 5e-4) << name;
    EXPECT_LT(e.accel, 0.1) << name;
    EXPECT_LT(e.omega, 2e-3) << name;
    // Default knots (50 ms, meant for noisy ground truth): smoother, still close.
    e = Compare(*truth, SplineTrajectory(poses));
    std::printf(
        "%s (50 ms knots): pos %.1e m rot %.1e rad vel %.1e m/s acc %.1e m/s2 omega %.1e rad/s\n",
        name, e.position, e.rotation, e.velocity, e.accel, e.omega);
    EXPECT_LT(e.position, 1e-4) << name;
    EXPECT_LT(e.rotation, 3e-4) << name;
    EXPECT_LT(e.velocity, 5e-3) << name;
    EXPECT_LT(e.accel, 0.4) << name;
    EXPECT_LT(e.omega, 0.02) << name;
  }
}

TEST(SplineTrajectoryTest, DerivativesAreConsistentWithThePose) {
  const auto truth = MakeMotion("shake", MotionOptions());
  const SplineTrajectory spline(Sample(*truth, 100.0));
  const double h = 1e-6;
  for (double t = 0.2; t < 2.8; t += 0.13) {
    const Rigid3d a = spline.WorldFromBody(t - h), b = spline.WorldFromBody(t + h);
    EXPECT_LT((spline.VelocityInWorld(t) - (b.translation - a.translation) / (2 * h)).norm(), 1e-7);
    EXPECT_LT(
        (spline.AngularVelocityInBody(t) - LogSO3(a.rotation.conjugate() * b.rotation) / (2 * h))
            .norm(),
        1e-6);
    EXPECT_LT((spline.AccelerationInWorld(t) -
               (spline.VelocityInWorld(t + h) - spline.VelocityInWorld(t - h)) / (2 * h))
                  .norm(),
              1e-4);  // the jerk jumps at knots: central differences are off by ~jump * h / 4
  }
}

TEST(SplineTrajectoryTest, SmoothsNoisyGroundTruth) {
  // Motion-capture-like noise (0.5 mm, 0.05 deg) on 100 Hz samples: the fitted velocity and
  // angular velocity stay close to the truth.
  const auto truth = MakeMotion("walk", MotionOptions());
  const SplineTrajectory spline(Sample(*truth, 100.0, 5e-4, 1e-3));
  const FitErrors e = Compare(*truth, spline);
  std::printf("noisy walk: pos %.2e vel %.2e (rms %.2f) omega %.2e (rms %.2f)\n", e.position,
              e.velocity, e.velocity_rms, e.omega, e.omega_rms);
  EXPECT_LT(e.position, 1e-3);
  EXPECT_LT(e.velocity, 0.05);
  EXPECT_LT(e.omega, 0.1);
}

TEST(SplineTrajectoryTest, SparsePosesDoNotSagBetweenThem) {
  // A body at rest at x = 10 m, its pose known every 10 s (200 knots apart; found by fuzzing the
  // TUM reader: the fit sank toward zero mid-gap and the simulated IMU saw motion, or NaN).
  std::vector<StampedPose> poses;
  for (int i = 0; i < 5; ++i) {
    StampedPose p;
    p.t_ns = int64_t{10'000'000'000} * i;
    p.world_from_body.translation = Eigen::Vector3d(10.0, 0.0, 0.0);
    poses.push_back(p);
  }
  const SplineTrajectory spline(poses);
  for (double t : {5.0, 15.0, 25.0, 35.0}) {
    EXPECT_NEAR(spline.WorldFromBody(t).translation.x(), 10.0, 1e-6) << t;
    EXPECT_NEAR(spline.VelocityInWorld(t).norm(), 0.0, 1e-6) << t;
    EXPECT_NEAR(spline.AngularVelocityInBody(t).norm(), 0.0, 1e-6) << t;
  }
}

TEST(SplineTrajectoryTest, RejectsBadInput) {
  const auto truth = MakeMotion("front1m", MotionOptions());
  std::vector<StampedPose> poses = Sample(*truth, 100.0);
  EXPECT_THROW(SplineTrajectory(std::vector<StampedPose>(poses.begin(), poses.begin() + 3)),
               InvalidArgument);
  std::vector<StampedPose> duplicate = poses;
  duplicate[10].t_ns = duplicate[9].t_ns;
  try {
    SplineTrajectory spline(duplicate);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("pose 10"), std::string::npos) << e.what();
  }
  std::vector<StampedPose> unsorted = poses;
  std::swap(unsorted[20], unsorted[21]);
  EXPECT_THROW(SplineTrajectory{unsorted}, InvalidArgument);
  std::vector<StampedPose> nan = poses;
  nan[5].world_from_body.translation.x() = std::nan("");
  EXPECT_THROW(SplineTrajectory{nan}, InvalidArgument);
  // Bounded work: a last pose 1e6 s later would need 2e7 knots; refused before allocating.
  std::vector<StampedPose> far = poses;
  far.back().t_ns += 1'000'000'000'000'000;
  try {
    SplineTrajectory spline(far);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("knots"), std::string::npos) << e.what();
  }
  SplineFitOptions bad;
  bad.knot_spacing_s = 0.0;
  EXPECT_THROW(SplineTrajectory(poses, bad), InvalidArgument);
  // Knots much denser than the samples are held together by the smoothing penalty.
  SplineFitOptions dense;
  dense.knot_spacing_s = 0.002;
  const SplineTrajectory fine(poses, dense);
  EXPECT_LT((fine.WorldFromBody(1.5).translation - truth->WorldFromBody(1.5).translation).norm(),
            1e-3);
}

}  // namespace
}  // namespace imumatch
