// Guided matching vs unguided baselines on the same real keypoints (TUM fr1_xyz pair, the
// ground-truth relative pose standing in for the IMU). Single thread. Every guided iteration does
// the whole per-frame work: keypoint conversion, depth lookup in A, prediction with covariance,
// grid build over B, and matching. At the end a summary table prints times, speedups and time per
// keypoint.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <tuple>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/trajectory_io.h"  // ReadTumPose
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/grid_index.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/klt_tracker.h"
#include "imumatch/matching/subpixel_refinement.h"

#ifndef IMUMATCH_BENCH_DATA_DIR
#define IMUMATCH_BENCH_DATA_DIR "../shared/data"
#endif

namespace imumatch {
namespace {

std::string DataPath(const std::string& file) {
  const char* env = std::getenv("IMUMATCH_DATA_DIR");
  const std::string dir = (env != nullptr && *env != '\0') ? env : IMUMATCH_BENCH_DATA_DIR;
  return dir + "/tum_fr1_xyz_pair/" + file;
}

struct Frames {
  cv::Mat gray_a, gray_b, depth_a;
  CameraMotion motion;
};

const Frames& GetFrames() {
  static const Frames f = [] {
    Frames fr;
    fr.gray_a = cv::imread(DataPath("img_prev.png"), cv::IMREAD_GRAYSCALE);
    fr.gray_b = cv::imread(DataPath("img_curr.png"), cv::IMREAD_GRAYSCALE);
    fr.depth_a = cv::imread(DataPath("dep_prev.png"), cv::IMREAD_UNCHANGED);
    if (fr.gray_a.empty() || fr.gray_b.empty() || fr.depth_a.empty()) {
      std::fprintf(stderr, "missing TUM pair under %s (set IMUMATCH_DATA_DIR)\n",
                   DataPath("").c_str());
      std::exit(1);
    }
    try {
      fr.motion = CameraMotionFromPoses(0, ReadTumPose(DataPath("pose_prev.txt")), 1,
                                        ReadTumPose(DataPath("pose_curr.txt")));
    } catch (const Error& e) {
      std::fprintf(stderr, "cannot read pose: %s\n", e.what());
      std::exit(1);
    }
    return fr;
  }();
  return f;
}

struct FeatureSet {
  std::vector<cv::KeyPoint> kps_a, kps_b;
  cv::Mat desc_a, desc_b;
};

// A benchmark that runs the same frame pair in every iteration lets the CPU learn it: the branch
// predictor memorises the whole pass when it is short (1000 keypoints, not 8000), which flatters
// small sizes by up to 1.5x (measured on the synthetic search below). A stream never shows the
// same frame twice, so the per-keypoint figures rotate through kStreamVariants different pairs:
// the TUM pair forward and backward, each also mirrored left-right, up-down and both (a mirrored
// pair is a valid pair of the same camera: cx, cy sit at the image centre; the motion is
// conjugated by the mirror), each with its own keypoints.
constexpr int kStreamVariants = 8;

struct PairVariant {
  cv::Mat gray_a, gray_b, depth_a;
  CameraMotion motion;
};

const PairVariant& GetPairVariant(int v) {
  static std::map<int, PairVariant> cache;
  auto it = cache.find(v);
  if (it != cache.end()) return it->second;
  const Frames& f = GetFrames();
  const bool backward = (v & 4) != 0;
  const bool flip_x = (v & 1) != 0, flip_y = (v & 2) != 0;
  PairVariant pv;
  cv::Mat gray_a = backward ? f.gray_b : f.gray_a, gray_b = backward ? f.gray_a : f.gray_b;
  cv::Mat depth_a =
      backward ? cv::imread(DataPath("dep_curr.png"), cv::IMREAD_UNCHANGED) : f.depth_a;
  Rigid3d b_from_a = backward ? f.motion.cam_b_from_cam_a.Inverse() : f.motion.cam_b_from_cam_a;
  const int code = flip_x && flip_y ? -1 : (flip_x ? 1 : 0);
  if (flip_x || flip_y) {
    cv::flip(gray_a, pv.gray_a, code);
    cv::flip(gray_b, pv.gray_b, code);
    cv::flip(depth_a, pv.depth_a, code);
  } else {
    pv.gray_a = gray_a;
    pv.gray_b = gray_b;
    pv.depth_a = depth_a;
  }
  const Eigen::Matrix3d mirror =
      Eigen::Vector3d(flip_x ? -1.0 : 1.0, flip_y ? -1.0 : 1.0, 1.0).asDiagonal();
  pv.motion = f.motion;
  pv.motion.cam_b_from_cam_a = Rigid3d(mirror * b_from_a.rotation.toRotationMatrix() * mirror,
                                       mirror * b_from_a.translation);
  return cache.emplace(v, std::move(pv)).first->second;
}

// kind 0: ORB with n features (FAST threshold lowered so 8000 are reachable), 1: SIFT.
// variant -1: the TUM pair itself; 0..kStreamVariants-1: GetPairVariant.
const FeatureSet& GetFeatures(int kind, int n, int variant = -1) {
  static std::map<std::tuple<int, int, int>, FeatureSet> cache;
  auto it = cache.find({kind, n, variant});
  if (it != cache.end()) return it->second;
  cv::Ptr<cv::Feature2D> f;
  if (kind == 0) {
    f = cv::ORB::create(n, 1.2f, 8, 15, 0, 2, cv::ORB::HARRIS_SCORE, 31, n > 2000 ? 5 : 20);
  } else {
    f = cv::SIFT::create(n);
  }
  FeatureSet s;
  const cv::Mat& a = variant < 0 ? GetFrames().gray_a : GetPairVariant(variant).gray_a;
  const cv::Mat& b = variant < 0 ? GetFrames().gray_b : GetPairVariant(variant).gray_b;
  f->detectAndCompute(a, cv::noArray(), s.kps_a, s.desc_a);
  f->detectAndCompute(b, cv::noArray(), s.kps_b, s.desc_b);
  return cache.emplace(std::make_tuple(kind, n, variant), std::move(s)).first->second;
}

PinholeCamera BenchCamera() {
  // The generic Kinect intrinsics (no distortion): on this pair they fit the ground truth as well
  // as the fr1 calibration (see matching_tum_test), and avoid the iterative undistortion.
  return PinholeCamera::KinectDefault();
}

void SetCounters(benchmark::State& state, const FeatureSet& s, size_t matches) {
  state.counters["kps_a"] = static_cast<double>(s.kps_a.size());
  state.counters["kps_b"] = static_cast<double>(s.kps_b.size());
  state.counters["matches"] = static_cast<double>(matches);
}

// One guided iteration per loop: the whole per-frame work of GuidedMatcherWorkspace::Match.
void RunGuided(benchmark::State& state, const PinholeCamera& camera) {
  const FeatureSet& s = GetFeatures(static_cast<int>(state.range(0)), state.range(1));
  GuidedMatcherWorkspace workspace;
  size_t matches = 0;
  double per_query = 0.0, scanned = 0.0, no_depth = 0.0;
  for (auto _ : state) {
    MatchResult r =
        workspace.Match(camera, GetFrames().motion, s.kps_a, s.desc_a, GetFrames().depth_a, s.kps_b,
                        s.desc_b, PredictionOptions(), GuidedMatcherOptions());
    matches = r.matches.size();
    per_query = static_cast<double>(r.stats.distances_computed) / std::max(1, r.stats.queries);
    scanned = static_cast<double>(r.stats.points_scanned) / std::max(1, r.stats.queries);
    no_depth = static_cast<double>(r.stats.predicted_without_depth) / std::max(1, r.stats.queries);
    benchmark::DoNotOptimize(r.matches.data());
  }
  SetCounters(state, s, matches);
  state.counters["dist/query"] = per_query;
  state.counters["scan/query"] = scanned;
  state.counters["no_depth"] = no_depth;
}

void BM_Guided(benchmark::State& state) { RunGuided(state, BenchCamera()); }

// BM_Guided's whole per-frame work in a stream: every iteration another of kStreamVariants pairs.
void BM_GuidedStreamOfPairs(benchmark::State& state) {
  const int kind = static_cast<int>(state.range(0)), n = static_cast<int>(state.range(1));
  double keypoints = 0.0;
  for (int v = 0; v < kStreamVariants; ++v) {
    keypoints += static_cast<double>(GetFeatures(kind, n, v).kps_a.size()) / kStreamVariants;
  }
  GuidedMatcherWorkspace workspace;
  const PinholeCamera camera = BenchCamera();
  int frame = 0;
  size_t matches = 0;
  for (auto _ : state) {
    const int v = frame++ % kStreamVariants;
    const FeatureSet& s = GetFeatures(kind, n, v);
    const PairVariant& pv = GetPairVariant(v);
    MatchResult r = workspace.Match(camera, pv.motion, s.kps_a, s.desc_a, pv.depth_a, s.kps_b,
                                    s.desc_b, PredictionOptions(), GuidedMatcherOptions());
    matches += r.matches.size();
    benchmark::DoNotOptimize(r.matches.data());
  }
  state.counters["kps_a"] = keypoints;
  state.counters["matches"] =
      static_cast<double>(matches) / static_cast<double>(std::max<int64_t>(1, state.iterations()));
}

// The parts of BM_Guided: prediction (depth lookup + KeypointPredictor, per keypoint of A), grid
// build over B, and the window search alone (MatchGuided on ready predictions and grid).
struct GuidedParts {
  std::vector<KeypointInfo> info_a, info_b;
  std::vector<float> depths;
  std::vector<KeypointPrediction> predictions;
  GridIndex grid;
};
const GuidedParts& GetGuidedParts(int kind, int n) {
  static std::map<std::pair<int, int>, GuidedParts> cache;
  auto it = cache.find({kind, n});
  if (it != cache.end()) return it->second;
  const FeatureSet& s = GetFeatures(kind, n);
  const PinholeCamera camera = BenchCamera();
  GuidedParts g;
  g.info_a = ToKeypointInfos(s.kps_a);
  g.info_b = ToKeypointInfos(s.kps_b);
  g.depths = SampleDepths(GetFrames().depth_a, camera.depth_scale, s.kps_a,
                          PredictionOptions().depth_sampling);
  g.predictions =
      PredictKeypoints(camera, GetFrames().motion, g.info_a, g.depths, PredictionOptions());
  g.grid.Build(g.info_b, camera.width, camera.height,
               static_cast<float>(GuidedMatcherOptions().grid_cell_size));
  return cache.emplace(std::make_pair(kind, n), std::move(g)).first->second;
}

void BM_GuidedPredictOnly(benchmark::State& state) {
  const int kind = static_cast<int>(state.range(0)), n = static_cast<int>(state.range(1));
  const FeatureSet& s = GetFeatures(kind, n);
  const GuidedParts& g = GetGuidedParts(kind, n);
  const PixelUndistorter undistorter(BenchCamera());
  std::vector<KeypointPrediction> predictions;
  for (auto _ : state) {
    const std::vector<float> depths = SampleDepths(GetFrames().depth_a, BenchCamera().depth_scale,
                                                   s.kps_a, PredictionOptions().depth_sampling);
    const KeypointPredictor predictor(undistorter, GetFrames().motion, PredictionOptions());
    PredictKeypoints(predictor, g.info_a, depths, &predictions);
    benchmark::DoNotOptimize(predictions.data());
  }
  SetCounters(state, s, 0);
}

// The window search at a constant keypoint density: n keypoints spread over an image whose area
// grows with n (1000 per 640 x 480), windows of the same sizes, so every query has the same number
// of candidates whatever n. The time per keypoint then shows whether the search itself is linear
// (its cost per query must not grow with the arrays); on a real image of fixed size it also grows
// with the candidates per window, i.e. with the density.
struct SyntheticSearch {
  std::vector<KeypointInfo> info_a, info_b;
  std::vector<KeypointPrediction> predictions;
  cv::Mat desc_a, desc_b;
  GridIndex grid;
};
const SyntheticSearch& GetSyntheticSearch(int n, int seed) {
  static std::map<std::pair<int, int>, SyntheticSearch> cache;
  auto it = cache.find({n, seed});
  if (it != cache.end()) return it->second;
  SyntheticSearch s;
  const double scale = std::sqrt(n / 1000.0);
  const int width = static_cast<int>(640 * scale), height = static_cast<int>(480 * scale);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(0.0f, static_cast<float>(width - 1)),
      uy(0.0f, static_cast<float>(height - 1)), angle(0.0f, 360.0f), size(31.0f, 100.0f),
      u01(0.0f, 1.0f);
  std::uniform_int_distribution<int> byte(0, 255), bit(0, 255);
  s.desc_a.create(n, 32, CV_8U);
  s.desc_b.create(n, 32, CV_8U);
  s.info_a.resize(n);
  s.info_b.resize(n);
  s.predictions.resize(n);
  for (int j = 0; j < n; ++j) {
    s.info_b[j] = {ux(rng), uy(rng), angle(rng), size(rng), 0};
    for (int k = 0; k < 32; ++k) s.desc_b.at<uint8_t>(j, k) = static_cast<uint8_t>(byte(rng));
  }
  for (int i = 0; i < n; ++i) {
    const int partner = static_cast<int>((static_cast<int64_t>(i) * 7919) % n);
    const KeypointInfo& kb = s.info_b[partner];
    s.info_a[i] = {kb.x, kb.y, kb.angle_deg, kb.size, 0};
    s.desc_b.row(partner).copyTo(s.desc_a.row(i));
    for (int f = 0; f < 8; ++f) {
      const int b = bit(rng);
      s.desc_a.at<uint8_t>(i, b / 8) ^= static_cast<uint8_t>(1u << (b % 8));
    }
    KeypointPrediction& p = s.predictions[i];
    const float cx = kb.x + 2.0f * (u01(rng) - 0.5f), cy = kb.y + 2.0f * (u01(rng) - 0.5f);
    p.scale_min = 0.9f;
    p.scale_max = 1.1f;
    if (i % 10 == 0) {  // no depth: a capsule 60 px long
      p.status = PredictionStatus::kWithoutDepth;
      const float dir = 6.2832f * u01(rng);
      p.segment_start = Eigen::Vector2f(cx, cy);
      p.segment_end = Eigen::Vector2f(cx + 60.0f * std::cos(dir), cy + 60.0f * std::sin(dir));
      p.radius = 4.0f;
      p.min_x = std::min(p.segment_start.x(), p.segment_end.x()) - p.radius;
      p.max_x = std::max(p.segment_start.x(), p.segment_end.x()) + p.radius;
      p.min_y = std::min(p.segment_start.y(), p.segment_end.y()) - p.radius;
      p.max_y = std::max(p.segment_start.y(), p.segment_end.y()) + p.radius;
    } else {
      p.status = PredictionStatus::kWithDepth;
      p.uv = p.segment_start = p.segment_end = Eigen::Vector2f(cx, cy);
      p.min_x = cx - 10.0f;
      p.max_x = cx + 10.0f;
      p.min_y = cy - 10.0f;
      p.max_y = cy + 10.0f;
    }
  }
  s.grid.Build(s.info_b, width, height, static_cast<float>(GuidedMatcherOptions().grid_cell_size));
  return cache.emplace(std::make_pair(n, seed), std::move(s)).first->second;
}

void BM_GuidedSearchConstantDensity(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (int v = 0; v < kStreamVariants; ++v) GetSyntheticSearch(n, 7 + v);
  double per_query = 0.0;
  size_t matches = 0;
  int frame = 0;
  GuidedSearchScratch scratch;  // reused across frames, as GuidedMatcherWorkspace does
  for (auto _ : state) {
    const SyntheticSearch& s = GetSyntheticSearch(n, 7 + frame++ % kStreamVariants);
    MatchResult r =
        MatchGuided(s.predictions, s.info_a, DescriptorView::FromMat(s.desc_a), s.info_b, s.grid,
                    DescriptorView::FromMat(s.desc_b), GuidedMatcherOptions(), &scratch);
    matches = r.matches.size();
    per_query = static_cast<double>(r.stats.distances_computed) / std::max(1, r.stats.queries);
    benchmark::DoNotOptimize(r.matches.data());
  }
  state.counters["kps_a"] = n;
  state.counters["matches"] = static_cast<double>(matches);
  state.counters["dist/query"] = per_query;
}

void BM_GuidedSearchOnly(benchmark::State& state) {
  const int kind = static_cast<int>(state.range(0)), n = static_cast<int>(state.range(1));
  const FeatureSet& s = GetFeatures(kind, n);
  const GuidedParts& g = GetGuidedParts(kind, n);
  size_t matches = 0;
  GuidedSearchScratch scratch;  // reused across frames, as GuidedMatcherWorkspace does
  for (auto _ : state) {
    MatchResult r =
        MatchGuided(g.predictions, g.info_a, DescriptorView::FromMat(s.desc_a), g.info_b, g.grid,
                    DescriptorView::FromMat(s.desc_b), GuidedMatcherOptions(), &scratch);
    matches = r.matches.size();
    benchmark::DoNotOptimize(r.matches.data());
  }
  SetCounters(state, s, matches);
}

void BM_GuidedWithDistortion(benchmark::State& state) {
  RunGuided(state, PinholeCamera::TumFreiburg1());
}
// The same intrinsics without the lens: the baseline that isolates what distortion costs.
void BM_GuidedFr1Pinhole(benchmark::State& state) {
  PinholeCamera camera = PinholeCamera::TumFreiburg1();
  camera.distortion = {0, 0, 0, 0, 0};
  RunGuided(state, camera);
}

// Mapping one frame's keypoints to ideal pixels (the TUM fr1 lens): the part of the distorted
// camera's cost that a stream pays once per frame, not twice per pair.
void BM_MapToIdeal(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(static_cast<int>(state.range(0)), state.range(1));
  const PixelUndistorter undistorter(PinholeCamera::TumFreiburg1());
  std::vector<KeypointInfo> out;
  for (auto _ : state) {
    ToIdealKeypointInfos(s.kps_a, undistorter, &out);
    benchmark::DoNotOptimize(out.data());
  }
  SetCounters(state, s, 0);
}

// Sub-pixel refinement of the guided matches (TUM fr1 camera, the prediction's affine warp): the
// extra cost per frame pair that buys the precision at 1 px.
void BM_RefineGuided(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(static_cast<int>(state.range(0)), state.range(1));
  const PinholeCamera camera = PinholeCamera::TumFreiburg1();
  GuidedMatcherWorkspace workspace;
  const MatchResult r =
      workspace.Match(camera, GetFrames().motion, s.kps_a, s.desc_a, GetFrames().depth_a, s.kps_b,
                      s.desc_b, PredictionOptions(), GuidedMatcherOptions());
  SubpixelOptions options;
  options.drop_unaligned = false;
  SubpixelStats stats;
  for (auto _ : state) {
    std::vector<Match> matches = r.matches;
    stats = RefineMatches(GetFrames().gray_a, GetFrames().gray_b, s.kps_a, s.kps_b,
                          workspace.predictions(), camera, options, matches);
    benchmark::DoNotOptimize(matches.data());
  }
  SetCounters(state, s, r.matches.size());
  state.counters["refined"] = stats.refined;
  state.counters["iters"] =
      static_cast<double>(stats.iterations) / std::max<size_t>(1, r.matches.size());
}

void BM_CvKnnRatio(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(static_cast<int>(state.range(0)), state.range(1));
  size_t matches = 0;
  for (auto _ : state) {
    std::vector<Match> m = MatchOpenCvKnnRatio(s.desc_a, s.desc_b, 0.8);
    matches = m.size();
    benchmark::DoNotOptimize(m.data());
  }
  SetCounters(state, s, matches);
}

// Own brute force + ratio on one instruction-set path (kAuto: the fastest this CPU runs).
void RunOwnBruteForce(benchmark::State& state, BruteForceKernel kernel) {
  const FeatureSet& s = GetFeatures(static_cast<int>(state.range(0)), state.range(1));
  BruteForceOptions options;
  options.ratio = 0.8;
  options.kernel = kernel;
  const auto available = AvailableBruteForceKernels();
  if (kernel != BruteForceKernel::kAuto &&
      std::find(available.begin(), available.end(), kernel) == available.end()) {
    state.SkipWithError("path not available on this CPU");
    return;
  }
  size_t matches = 0;
  for (auto _ : state) {
    std::vector<Match> m = MatchBruteForce(s.desc_a, s.desc_b, options);
    matches = m.size();
    benchmark::DoNotOptimize(m.data());
  }
  SetCounters(state, s, matches);
}

void BM_OwnBruteForceRatio(benchmark::State& state) {
  RunOwnBruteForce(state, BruteForceKernel::kAuto);
}

// range 2: the BruteForceKernel forced.
void BM_OwnBruteForceKernel(benchmark::State& state) {
  RunOwnBruteForce(state, static_cast<BruteForceKernel>(state.range(2)));
}

void KernelSizes(benchmark::internal::Benchmark* b) {
  for (int k = 1; k <= 4; ++k) {
    b->Args({0, 1000, k});
    b->Args({0, 4000, k});
    b->Args({1, 1000, k});
  }
  b->ArgNames({"sift", "n", "kernel"});
}

void BM_FlannLsh(benchmark::State& state) {
  const FeatureSet& s = GetFeatures(static_cast<int>(state.range(0)), state.range(1));
  size_t matches = 0;
  for (auto _ : state) {
    std::vector<Match> m = MatchFlannLsh(s.desc_a, s.desc_b, FlannLshOptions());
    matches = m.size();
    benchmark::DoNotOptimize(m.data());
  }
  SetCounters(state, s, matches);
}

void OrbSizes(benchmark::internal::Benchmark* b) {
  for (int n : {500, 1000, 2000, 4000, 8000}) b->Args({0, n});
  b->Args({1, 1000});  // SIFT
  b->ArgNames({"sift", "n"});
}

BENCHMARK(BM_Guided)->Apply(OrbSizes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GuidedStreamOfPairs)->Apply(OrbSizes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GuidedPredictOnly)->Apply(OrbSizes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GuidedSearchOnly)->Apply(OrbSizes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GuidedSearchConstantDensity)
    ->ArgsProduct({{1000, 2000, 4000, 8000, 16000}})
    ->ArgNames({"n"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CvKnnRatio)->Apply(OrbSizes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_OwnBruteForceRatio)->Apply(OrbSizes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_OwnBruteForceKernel)->Apply(KernelSizes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GuidedWithDistortion)
    ->Args({0, 1000})
    ->ArgNames({"sift", "n"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GuidedFr1Pinhole)
    ->Args({0, 1000})
    ->ArgNames({"sift", "n"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MapToIdeal)->Args({0, 1000})->ArgNames({"sift", "n"})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RefineGuided)
    ->Args({0, 1000})
    ->Args({1, 1000})
    ->ArgNames({"sift", "n"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FlannLsh)
    ->Args({0, 1000})
    ->Args({0, 4000})
    ->ArgNames({"sift", "n"})
    ->Unit(benchmark::kMicrosecond);

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

void PrintTrackingSummary(const std::map<std::string, double>& t) {
  const auto get = [&t](const std::string& name) {
    auto it = t.find(name);
    return it == t.end() ? -1.0 : it->second;
  };
  const double orb = get("BM_OrbExtractOneFrame"), guided = get("BM_GuidedStream"),
               klt = get("BM_KltSeeded"), hybrid = get("BM_Hybrid"), cv = get("BM_KltOpenCv");
  if (orb <= 0 || guided <= 0 || klt <= 0 || hybrid <= 0 || cv <= 0) return;
  std::printf(
      "\nTracking vs matching, ORB-1000 on the TUM pair (fr1 lens), wall time per frame, one "
      "thread:\n"
      "  ORB extraction (one frame)                %8.1f us\n"
      "  guided matching + refinement (stream)     %8.1f us\n"
      "  KLT IMU-seeded (pyramid of B + tracks)    %8.1f us\n"
      "  hybrid (KLT + guided for the rest)        %8.1f us\n"
      "  KLT unseeded, OpenCV, VINS settings       %8.1f us (%.1fx the seeded one)\n"
      "  hybrid / (ORB extraction + guided) = %.2f (target <= 1)\n",
      orb, guided, klt, hybrid, cv, cv / klt, hybrid / (orb + guided));
}

// Console output as usual, plus the per-iteration real time of every run for the summary.
class CapturingReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
      // With --benchmark_repetitions, the fastest repetition: the machine is shared, and noise only
      // ever adds time.
      const std::string name = r.run_name.str();
      const double real = r.GetAdjustedRealTime(), cpu = r.GetAdjustedCPUTime();  // us
      if (!times_us.count(name) || real < times_us[name]) times_us[name] = real;
      if (!cpu_us.count(name) || cpu < cpu_us[name]) cpu_us[name] = cpu;
      if (r.counters.count("kps_a")) kps[name] = r.counters.at("kps_a").value;
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> times_us;
  std::map<std::string, double> cpu_us;
  std::map<std::string, double> kps;
};

void PrintTable(const CapturingReporter& rep, const std::map<std::string, double>& times,
                const char* what) {
  std::printf(
      "\n%s per frame pair, single thread (guided = depth lookup + prediction + grid build +\n"
      "matching; descriptor kernels: Hamming %s, L2 %s)\n",
      what, DescriptorKernelName(DescriptorNorm::kHamming),
      DescriptorKernelName(DescriptorNorm::kL2));
  std::printf("%-10s %7s %11s %13s %13s %11s %11s %12s %12s\n", "features", "kps_a", "guided[us]",
              "cv knn+r[us]", "own BF+r[us]", "x vs knn", "x vs ownBF", "guided ns/kp",
              "knn ns/kp");
  const auto get = [&times](const std::string& name) {
    auto it = times.find(name);
    return it == times.end() ? -1.0 : it->second;
  };
  for (int kind : {0, 1}) {
    for (int n : {500, 1000, 2000, 4000, 8000}) {
      if (kind == 1 && n != 1000) continue;
      const std::string args = "/sift:" + std::to_string(kind) + "/n:" + std::to_string(n);
      const double g = get("BM_Guided" + args), k = get("BM_CvKnnRatio" + args),
                   b = get("BM_OwnBruteForceRatio" + args);
      if (g <= 0 || k <= 0 || b <= 0) continue;
      const double kp = rep.kps.count("BM_Guided" + args) ? rep.kps.at("BM_Guided" + args) : n;
      std::printf("%-10s %7.0f %11.1f %13.1f %13.1f %10.1fx %10.1fx %12.1f %12.1f\n",
                  kind ? "SIFT" : "ORB", kp, g, k, b, k / g, b / g, 1000.0 * g / kp,
                  1000.0 * k / kp);
    }
  }
}

// Guided cost per keypoint as the keypoint count grows: the repeated pair, the stream of pairs,
// and the synthetic constant-density search (windows with the same number of candidates).
void PrintLinearity(const CapturingReporter& rep) {
  const auto ns_per_kp = [&rep](const std::string& name) {
    auto t = rep.times_us.find(name);
    auto k = rep.kps.find(name);
    if (t == rep.times_us.end() || k == rep.kps.end() || k->second <= 0) return -1.0;
    return 1000.0 * t->second / k->second;
  };
  std::printf(
      "\nGuided matching, wall time per keypoint of A (ns), one thread: the TUM pair repeated in "
      "every\niteration, a stream of %d different pairs (the pair forward/backward x mirrored), "
      "and the\nsynthetic search at constant density (image area grows with n, same candidates "
      "per window)\n",
      kStreamVariants);
  std::printf("%-8s %14s %14s %18s\n", "n", "repeated pair", "stream", "constant density");
  for (int n : {500, 1000, 2000, 4000, 8000, 16000}) {
    const std::string args = "/sift:0/n:" + std::to_string(n);
    const double r = ns_per_kp("BM_Guided" + args), st = ns_per_kp("BM_GuidedStreamOfPairs" + args);
    const double cd = ns_per_kp("BM_GuidedSearchConstantDensity/n:" + std::to_string(n));
    if (r <= 0 && st <= 0 && cd <= 0) continue;
    std::printf("%-8d %14.1f %14.1f %18.1f\n", n, r, st, cd);
  }
  const auto ratio = [&](const std::string& a, const std::string& b) {
    const double x = ns_per_kp(a), y = ns_per_kp(b);
    return x > 0 && y > 0 ? x / y : -1.0;
  };
  std::printf(
      "ns/keypoint 8000 / 1000: repeated pair %.2f, stream %.2f (target <= 1.3); constant density "
      "%.2f (16000: %.2f)\n",
      ratio("BM_Guided/sift:0/n:8000", "BM_Guided/sift:0/n:1000"),
      ratio("BM_GuidedStreamOfPairs/sift:0/n:8000", "BM_GuidedStreamOfPairs/sift:0/n:1000"),
      ratio("BM_GuidedSearchConstantDensity/n:8000", "BM_GuidedSearchConstantDensity/n:1000"),
      ratio("BM_GuidedSearchConstantDensity/n:16000", "BM_GuidedSearchConstantDensity/n:1000"));
  std::printf(
      "SIFT-1000 guided / ORB-1000 guided: repeated pair %.2f, stream %.2f (target <= 1.5)\n",
      ratio("BM_Guided/sift:1/n:1000", "BM_Guided/sift:0/n:1000"),
      ratio("BM_GuidedStreamOfPairs/sift:1/n:1000", "BM_GuidedStreamOfPairs/sift:0/n:1000"));
}

// Issue #13's table: the speed targets, measured in this process (the end-to-end row is
// end_to_end_benchmark's, in eval).
void PrintTargets(const CapturingReporter& rep) {
  const auto get = [&rep](const std::string& name) {
    auto it = rep.times_us.find(name);
    return it == rep.times_us.end() ? -1.0 : it->second;
  };
  const auto per_kp = [&](const std::string& name) {
    auto k = rep.kps.find(name);
    const double t = get(name);
    return t > 0 && k != rep.kps.end() && k->second > 0 ? 1000.0 * t / k->second : -1.0;
  };
  const auto ratio = [](double a, double b) { return a > 0 && b > 0 ? a / b : -1.0; };
  std::printf("\nSpeed targets (wall time, one thread, fastest repetition):\n");
  std::printf("%-62s %12s %10s\n", "", "measured", "target");
  for (int n : {1000, 4000}) {
    const std::string args = "/sift:0/n:" + std::to_string(n);
    const double knn = get("BM_CvKnnRatio" + args), own = get("BM_OwnBruteForceRatio" + args);
    std::printf(
        "%-62s %11.1fx %10s\n",
        ("own brute force + ratio vs cv::BFMatcher knnMatch, ORB " + std::to_string(n)).c_str(),
        ratio(knn, own), ">= 20x");
  }
  std::printf("%-62s %11.2fx %10s\n", "guided ns/keypoint 8000 / 1000, stream of pairs (TUM)",
              ratio(per_kp("BM_GuidedStreamOfPairs/sift:0/n:8000"),
                    per_kp("BM_GuidedStreamOfPairs/sift:0/n:1000")),
              "<= 1.3x");
  std::printf("%-62s %11.2fx %10s\n", "  same, constant density (same candidates per window)",
              ratio(per_kp("BM_GuidedSearchConstantDensity/n:8000"),
                    per_kp("BM_GuidedSearchConstantDensity/n:1000")),
              "<= 1.3x");
  std::printf("%-62s %11.2fx %10s\n", "  same, one pair repeated every iteration",
              ratio(per_kp("BM_Guided/sift:0/n:8000"), per_kp("BM_Guided/sift:0/n:1000")),
              "<= 1.3x");
  std::printf("%-62s %11.2fx %10s\n", "guided SIFT-1000 / guided ORB-1000, stream of pairs",
              ratio(get("BM_GuidedStreamOfPairs/sift:1/n:1000"),
                    get("BM_GuidedStreamOfPairs/sift:0/n:1000")),
              "<= 1.5x");
}

void PrintSummary(const CapturingReporter& rep) {
  PrintTrackingSummary(rep.times_us);
  PrintTable(rep, rep.times_us, "Real (wall) time");
  PrintTable(rep, rep.cpu_us, "CPU time");
  PrintLinearity(rep);
  const auto get = [&rep](const std::string& name) {
    auto it = rep.times_us.find(name);
    return it == rep.times_us.end() ? -1.0 : it->second;
  };
  std::printf(
      "\nOwn brute force + ratio per instruction-set path vs cv::BFMatcher::knnMatch + ratio, "
      "same descriptors, wall time (CPU: %s; auto = %s)\n",
      CpuFeaturesString().c_str(), ToString(AvailableBruteForceKernels().back()));
  std::printf("%-10s %8s %12s", "features", "n", "knn[us]");
  for (int k = 1; k <= 4; ++k) {
    std::printf(" %10s[us] %6s", ToString(static_cast<BruteForceKernel>(k)), "x");
  }
  std::printf("\n");
  for (const auto& [kind, n] : std::vector<std::pair<int, int>>{{0, 1000}, {0, 4000}, {1, 1000}}) {
    const std::string args = "/sift:" + std::to_string(kind) + "/n:" + std::to_string(n);
    const double knn = get("BM_CvKnnRatio" + args);
    if (knn <= 0) continue;
    std::printf("%-10s %8d %12.1f", kind ? "SIFT" : "ORB", n, knn);
    for (int k = 1; k <= 4; ++k) {
      const double t = get("BM_OwnBruteForceKernel" + args + "/kernel:" + std::to_string(k));
      if (t > 0) {
        std::printf(" %14.1f %5.1fx", t, knn / t);
      } else {
        std::printf(" %14s %6s", "-", "-");
      }
    }
    std::printf("\n");
  }
  const double gd = get("BM_GuidedWithDistortion/sift:0/n:1000");
  const double g1 = get("BM_GuidedFr1Pinhole/sift:0/n:1000");
  if (gd > 0 && g1 > 0) {
    std::printf(
        "ORB 1000 guided with TUM fr1 distortion, one pair alone (keypoints of both frames "
        "mapped to ideal pixels): %.1f us (%.2fx the same intrinsics without distortion)\n",
        gd, gd / g1);
  }
  const double map = get("BM_MapToIdeal/sift:0/n:1000");
  if (gd > 0 && g1 > 0 && map > 0) {
    std::printf(
        "ORB 1000 guided with distortion in a stream (each frame mapped once: %.1f - %.1f us): "
        "%.2fx the same intrinsics without distortion (target <= 1.3x)\n",
        gd, map, (gd - map) / g1);
  }
  for (int kind : {0, 1}) {
    const std::string args = "/sift:" + std::to_string(kind) + "/n:1000";
    const double rf = get("BM_RefineGuided" + args), g = get("BM_Guided" + args);
    if (rf > 0 && g > 0) {
      std::printf("%s 1000 sub-pixel refinement of the guided matches: %.1f us (%.2fx guided)\n",
                  kind ? "SIFT" : "ORB", rf, rf / g);
    }
  }
  for (int n : {1000, 4000}) {
    const double l = get("BM_FlannLsh/sift:0/n:" + std::to_string(n));
    const double g = get("BM_Guided/sift:0/n:" + std::to_string(n));
    if (l > 0 && g > 0) {
      std::printf("ORB %d FLANN LSH (index build + knn + ratio): %.1f us, guided %.1fx faster\n", n,
                  l, l / g);
    }
  }
  PrintTargets(rep);
}

}  // namespace
}  // namespace imumatch

int main(int argc, char** argv) {
  cv::setNumThreads(1);  // single-thread comparison (OpenCV would otherwise use both cores)
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  imumatch::CapturingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  imumatch::PrintSummary(reporter);
  benchmark::Shutdown();
  return 0;
}
