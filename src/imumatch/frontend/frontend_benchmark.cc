// The second pass's motion fit (RefitMotion) on a scene of a drone in flight as EuRoC MH_05 shows
// it: cam0's lens (k1 = -0.28), 4.6 cm sideways and 0.6 deg between two frames at 20 Hz, points
// 3-15 m away, a first pass of 750 matches with 5 % of them wrong by 1-5 px, the IMU's motion off
// by its stated sigmas. Arg depth: the share of the matches whose keypoint of A has a depth (0: a
// frame without a depth image, most of the flight; 15: about a take-off frame). Arg rotation:
// also measure the rotation the matches alone show (MotionRefitOptions::measure_rotation, on in
// `eval` and `track` for the gyro bias filter). The motion fit is about half of the guided
// method's time per pair on MH_05 (ORB: 2.5 of 5.3 ms).
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/so3.h"
#include "imumatch/frontend/motion_refit.h"

namespace imumatch {
namespace {

struct FlightScene {
  PixelUndistorter undistorter;
  std::vector<cv::KeyPoint> keypoints_a, keypoints_b;
  std::vector<Match> matches;
  std::vector<float> depths;
  CameraMotion prior;
};

FlightScene MakeFlightScene(int matches, double depth_share, uint64_t seed) {
  FlightScene s;
  const PinholeCamera camera = PinholeCamera::EurocCam0();
  s.undistorter = PixelUndistorter(camera);
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.004, -0.009, 0.003)),
                      Eigen::Vector3d(0.046, 0.004, 0.008));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 0.5);
  s.depths.reserve(matches);
  while (static_cast<int>(s.matches.size()) < matches) {
    const Eigen::Vector2d uv_a(20.0 + 712.0 * u(rng), 20.0 + 440.0 * u(rng));
    const double z = 3.0 + 12.0 * u(rng);
    const Eigen::Vector2d ideal_a = s.undistorter.ToIdeal(uv_a);
    const Eigen::Vector3d p_in_a = z * camera.IdealToNormalized(ideal_a).homogeneous();
    const Eigen::Vector3d p_in_b = truth * p_in_a;
    const std::optional<Eigen::Vector2d> projected = camera.Project(p_in_b);
    if (!projected || !camera.IsInside(*projected)) continue;
    Eigen::Vector2d uv_b = *projected;
    if (u(rng) < 0.05) {
      const double a = 2.0 * M_PI * u(rng), r = 1.0 + 4.0 * u(rng);
      uv_b += r * Eigen::Vector2d(std::cos(a), std::sin(a));
    } else {
      uv_b += Eigen::Vector2d(gauss(rng), gauss(rng));
    }
    Match m;
    m.query_idx = static_cast<int>(s.keypoints_a.size());
    m.train_idx = static_cast<int>(s.keypoints_b.size());
    s.keypoints_a.emplace_back(static_cast<float>(uv_a.x()), static_cast<float>(uv_a.y()), 7.0f);
    s.keypoints_b.emplace_back(static_cast<float>(uv_b.x()), static_cast<float>(uv_b.y()), 7.0f);
    s.matches.push_back(m);
    s.depths.push_back(u(rng) < depth_share ? static_cast<float>(z)
                                            : std::numeric_limits<float>::quiet_NaN());
  }
  // The IMU's motion as MH_05's integration states it: 0.005 deg and 2.5 mm per axis, the truth
  // one sigma off on each.
  Eigen::Matrix<double, 6, 1> sigma;
  sigma << 8.7e-5, 8.7e-5, 8.7e-5, 2.5e-3, 2.5e-3, 2.5e-3;
  s.prior.cam_b_from_cam_a =
      Rigid3d(ExpSO3(Eigen::Vector3d(sigma[0], -sigma[1], sigma[2])) * truth.rotation,
              truth.translation + Eigen::Vector3d(-sigma[3], sigma[4], sigma[5]));
  s.prior.covariance = sigma.cwiseAbs2().asDiagonal();
  return s;
}

void BM_RefitMotion(benchmark::State& state) {
  const double depth_share = static_cast<double>(state.range(0)) / 100.0;
  MotionRefitOptions options;
  options.measure_rotation = state.range(1) != 0;
  constexpr int kScenes = 8;  // different scenes in turn, as a stream of pairs
  std::vector<FlightScene> scenes;
  for (int k = 0; k < kScenes; ++k) scenes.push_back(MakeFlightScene(750, depth_share, 11 + k));
  const PredictionOptions prediction;
  int held = 0, runs = 0, iterations = 0;
  for (auto _ : state) {
    const FlightScene& s = scenes[runs % kScenes];
    const MotionRefit fit = RefitMotion(s.prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                        prediction, s.undistorter, options);
    held += fit.ok ? 1 : 0;
    iterations += fit.iterations;
    ++runs;
    benchmark::DoNotOptimize(fit.motion.covariance.data());
  }
  state.counters["held"] = runs > 0 ? static_cast<double>(held) / runs : 0.0;
  state.counters["steps"] = runs > 0 ? static_cast<double>(iterations) / runs : 0.0;
}

BENCHMARK(BM_RefitMotion)
    ->ArgNames({"depth%", "rotation"})
    ->ArgsProduct({{0, 15}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace imumatch

BENCHMARK_MAIN();
