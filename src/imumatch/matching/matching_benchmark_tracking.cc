// matching_benchmark, part 3: tracking vs matching, ORB-1000 on the TUM pair (fr1 lens).
#include <benchmark/benchmark.h>

#include <vector>

#include <opencv2/features2d.hpp>

#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/klt_tracker.h"
#include "imumatch/matching/matching_benchmark_data.h"
#include "imumatch/matching/subpixel_refinement.h"

namespace imumatch::bench {
namespace {

// ---- Tracking vs matching (issue: IMU-seeded KLT and the hybrid front end) --------------------
// ORB-1000 on the TUM pair, TUM fr1 lens. A stream extracts every frame once and builds every
// frame's pyramid once: a pair charges frame B's.

void BM_OrbExtractOneFrame(benchmark::State& state) {
  cv::Ptr<cv::ORB> orb = cv::ORB::create(1000);
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  for (auto _ : state) {
    orb->detectAndCompute(GetFrames().gray_b, cv::noArray(), kps, desc);
    benchmark::DoNotOptimize(desc.data);
  }
  state.counters["kps"] = static_cast<double>(kps.size());
}

struct TrackingInputs {
  PixelUndistorter undistorter;
  std::vector<KeypointInfo> ideal_a, ideal_b;
  std::vector<KeypointPrediction> predictions;
  TrackingPyramid pyr_a;
};
const TrackingInputs& GetTrackingInputs() {
  static const TrackingInputs in = [] {
    TrackingInputs t;
    t.undistorter = PixelUndistorter(PinholeCamera::TumFreiburg1());
    const FeatureSet& s = GetFeatures(0, 1000);
    t.ideal_a = ToIdealKeypointInfos(s.kps_a, t.undistorter);
    t.ideal_b = ToIdealKeypointInfos(s.kps_b, t.undistorter);
    const std::vector<float> depths = SampleDepths(
        GetFrames().depth_a, t.undistorter.camera().depth_scale, s.kps_a, DepthSampling::kNearest);
    t.predictions =
        PredictKeypoints(t.undistorter, GetFrames().motion, t.ideal_a, depths, PredictionOptions());
    t.pyr_a = TrackingPyramid::Build(GetFrames().gray_a, KltOptions().max_level);
    return t;
  }();
  return in;
}

// Guided matching as a stream runs it (frame B's keypoints mapped, depth, prediction, grid,
// matching, sub-pixel refinement), without extraction.
void BM_GuidedStream(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(0, 1000);
  const TrackingInputs& in = GetTrackingInputs();
  const PinholeCamera& camera = in.undistorter.camera();
  size_t matches = 0;
  for (auto _ : state) {
    std::vector<KeypointInfo> ideal_b;
    ToIdealKeypointInfos(s.kps_b, in.undistorter, &ideal_b);
    const std::vector<float> depths =
        SampleDepths(GetFrames().depth_a, camera.depth_scale, s.kps_a, DepthSampling::kNearest);
    const auto predictions = PredictKeypoints(in.undistorter, GetFrames().motion, in.ideal_a,
                                              depths, PredictionOptions());
    GridIndex grid;
    grid.Build(ideal_b, camera.width, camera.height,
               static_cast<float>(GuidedMatcherOptions().grid_cell_size));
    MatchResult r = MatchGuided(predictions, in.ideal_a, DescriptorView::FromMat(s.desc_a), ideal_b,
                                grid, DescriptorView::FromMat(s.desc_b), GuidedMatcherOptions());
    RefineMatches(GetFrames().gray_a, GetFrames().gray_b, s.kps_a, s.kps_b, predictions, camera,
                  SubpixelOptions(), r.matches);
    matches = r.matches.size();
    benchmark::DoNotOptimize(r.matches.data());
  }
  SetCounters(state, s, matches);
}

// The seeded tracker: frame B's pyramid + tracking from the predictions (prediction not
// included: the same as guided's).
void BM_KltSeeded(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(0, 1000);
  const TrackingInputs& in = GetTrackingInputs();
  size_t tracks = 0;
  int64_t iterations = 0;
  for (auto _ : state) {
    const TrackingPyramid pyr_b =
        TrackingPyramid::Build(GetFrames().gray_b, KltOptions().max_level);
    TrackResult r =
        TrackSeeded(in.pyr_a, pyr_b, s.kps_a, in.predictions, in.undistorter, KltOptions());
    tracks = r.tracks.size();
    iterations = r.stats.iterations;
    benchmark::DoNotOptimize(r.tracks.data());
  }
  SetCounters(state, s, tracks);
  state.counters["iters_per_kp"] = static_cast<double>(iterations) / s.kps_a.size();
}

// Hybrid: the seeded tracker, then guided matching (+ refinement) for the keypoints whose track
// failed; frame B's keypoints mapped and gridded.
void BM_Hybrid(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(0, 1000);
  const TrackingInputs& in = GetTrackingInputs();
  const PinholeCamera& camera = in.undistorter.camera();
  size_t matches = 0;
  for (auto _ : state) {
    const TrackingPyramid pyr_b =
        TrackingPyramid::Build(GetFrames().gray_b, KltOptions().max_level);
    TrackResult t =
        TrackSeeded(in.pyr_a, pyr_b, s.kps_a, in.predictions, in.undistorter, KltOptions());
    std::vector<KeypointInfo> ideal_b;
    ToIdealKeypointInfos(s.kps_b, in.undistorter, &ideal_b);
    MatchResult r =
        MatchGuided(PredictionsOfFailedTracks(in.predictions, t), in.ideal_a,
                    DescriptorView::FromMat(s.desc_a), ideal_b, DescriptorView::FromMat(s.desc_b),
                    camera.width, camera.height, GuidedMatcherOptions());
    RefineMatches(GetFrames().gray_a, GetFrames().gray_b, s.kps_a, s.kps_b, in.predictions, camera,
                  SubpixelOptions(), r.matches);
    matches = t.tracks.size() + r.matches.size();
    benchmark::DoNotOptimize(r.matches.data());
  }
  SetCounters(state, s, matches);
}

// The unseeded VINS-Fusion baseline: OpenCV pyramidal LK, 21 x 21, levels 0-3, forward and
// backward.
void BM_KltOpenCv(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(0, 1000);
  KltOptions vins;
  vins.half_size = 10;
  vins.convergence_px = 0.01;
  vins.min_correlation = -1.0;
  size_t tracks = 0;
  for (auto _ : state) {
    TrackResult r = TrackOpenCvLk(GetFrames().gray_a, GetFrames().gray_b, s.kps_a, vins);
    tracks = r.tracks.size();
    benchmark::DoNotOptimize(r.tracks.data());
  }
  SetCounters(state, s, tracks);
}

BENCHMARK(BM_OrbExtractOneFrame)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GuidedStream)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_KltSeeded)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Hybrid)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_KltOpenCv)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace imumatch::bench
