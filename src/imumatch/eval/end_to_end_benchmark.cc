// The end-to-end stream on two cores against the sequential OpenCV pipeline, on a synthetic
// 640x480 sequence rendered here (the seed case "left30": 31 frames over 2 s, exact depth,
// simulated EuRoC-grade IMU, frames PNG-encoded in memory so that reading decodes a PNG).
//
//   end_to_end_benchmark [--benchmark_... flags]
//
// The Google Benchmark runs time the stages one by one (decode, ORB one thread / OpenCV's
// threads / levels split, brute force, guided); then MeasureEndToEnd runs both pipelines over
// the stream, alternating, 5 times, and the summary prints the best throughput and latency of
// each and their ratios against the targets (throughput >= 2.5x, latency <= 0.6x).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>

#include "imumatch/core/time.h"
#include "imumatch/eval/end_to_end.h"
#include "imumatch/eval/pair_motion.h"
#include "imumatch/eval/seed_cases.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/features/orb_split.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/guided_pipeline.h"

namespace imumatch {
namespace bench {

const SeedCase& Stream() {
  static const SeedCase c = [] {
    SeedCaseOptions o;
    o.motions = {"left30"};
    o.intermediate_frames = 29;
    std::vector<SeedCase> cases = MakeSeedCases(o);
    return cases.front();
  }();
  return c;
}

const cv::Mat& Image(size_t i) {
  static std::vector<cv::Mat> images;
  if (images.empty()) {
    for (size_t k = 0; k < Stream().source.dataset.frames.size(); ++k) {
      images.push_back(Stream().source.image_reader(k));
    }
  }
  return images[i];
}

void BM_DecodeImage(benchmark::State& state) {
  size_t i = 0;
  for (auto _ : state) {
    cv::Mat m = Stream().source.image_reader(i++ % Stream().source.dataset.frames.size());
    benchmark::DoNotOptimize(m.data);
  }
}
// What the sequential baseline reads with: cv::imdecode(IMREAD_GRAYSCALE) (libpng).
void BM_DecodeImageOpenCv(benchmark::State& state) {
  size_t i = 0;
  for (auto _ : state) {
    cv::Mat m = Stream().source.opencv_image_reader(i++ % Stream().source.dataset.frames.size());
    benchmark::DoNotOptimize(m.data);
  }
}
void BM_DecodeDepth(benchmark::State& state) {
  size_t i = 0;
  for (auto _ : state) {
    cv::Mat m = Stream().source.depth_reader(i++ % Stream().source.dataset.frames.size());
    benchmark::DoNotOptimize(m.data);
  }
}
// arg 0: cv::ORB with OpenCV's threads; 1: cv::ORB with one thread; 2: levels split (two tasks).
void BM_Orb1000(benchmark::State& state) {
  const int mode = static_cast<int>(state.range(0));
  const int threads = cv::getNumThreads();
  if (mode == 1) cv::setNumThreads(1);
  FeatureOptions o;
  o.threads = mode == 2 ? 2 : 1;
  size_t i = 0, keypoints = 0;
  for (auto _ : state) {
    const Features f = ExtractFeatures(Image(i++ % 31), o);
    keypoints = f.keypoints.size();
  }
  cv::setNumThreads(threads);
  state.counters["keypoints"] = static_cast<double>(keypoints);
}
void BM_OrbPart(benchmark::State& state) {
  const int part = static_cast<int>(state.range(0));
  OrbSplitParams p;
  p.split_level = static_cast<int>(state.range(1));
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  size_t i = 0;
  for (auto _ : state) {
    DetectAndComputeOrbPart(Image(i++ % 31), p, part, &k, &d);
    benchmark::DoNotOptimize(d.data);
  }
  state.counters["keypoints"] = static_cast<double>(k.size());
}
BENCHMARK(BM_OrbPart)
    ->ArgsProduct({{0, 1}, {1, 2, 3}})
    ->ArgNames({"part", "split"})
    ->Unit(benchmark::kMicrosecond);

void BM_KnnRatio1000(benchmark::State& state) {
  const Features a = ExtractFeatures(Image(10), FeatureOptions());
  const Features b = ExtractFeatures(Image(11), FeatureOptions());
  for (auto _ : state) {
    auto m = MatchOpenCvKnnRatio(a.descriptors, b.descriptors, 0.8);
    benchmark::DoNotOptimize(m.data());
  }
}
void BM_ImuAndGuided1000(benchmark::State& state) {
  const Features a = ExtractFeatures(Image(10), FeatureOptions());
  const Features b = ExtractFeatures(Image(11), FeatureOptions());
  const cv::Mat depth = Stream().source.depth_reader(10);
  const EvaluationOptions options;
  const Dataset& d = Stream().source.dataset;
  const ImuBiasEstimate bias;
  GuidedMatcherWorkspace workspace;
  for (auto _ : state) {
    std::string reason;
    const auto motion = ComputePairMotion(d, {10, 11}, 1, options, bias, reason);
    const MatchResult r =
        workspace.Match(d.camera, motion->motion, a.keypoints, a.descriptors, depth, b.keypoints,
                        b.descriptors, options.prediction, options.guided);
    benchmark::DoNotOptimize(r.matches.data());
  }
}

BENCHMARK(BM_DecodeImage)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DecodeImageOpenCv)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DecodeDepth)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Orb1000)->Arg(0)->Arg(1)->Arg(2)->ArgName("mode")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_KnnRatio1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ImuAndGuided1000)->Unit(benchmark::kMicrosecond);

// imumatch's work per frame on one thread: decode image and depth, ORB-1000, IMU + guided.
double OneThreadFrameMs() {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const Dataset& d = Stream().source.dataset;
  const EvaluationOptions options;
  GuidedMatcherWorkspace workspace;
  double best = 1e30;
  for (int trial = 0; trial < 3; ++trial) {
    Features prev;
    cv::Mat prev_depth;
    const auto t0 = SteadyClock::now();
    for (size_t i = 0; i < d.frames.size(); ++i) {
      const cv::Mat image = Stream().source.image_reader(i);
      cv::Mat depth = Stream().source.depth_reader(i);
      Features cur = ExtractFeatures(image, FeatureOptions());
      if (i > 0) {
        std::string reason;
        const auto motion = ComputePairMotion(d, {i - 1, i}, i, options, ImuBiasEstimate(), reason);
        if (motion) {
          benchmark::DoNotOptimize(workspace.Match(
              d.camera, motion->motion, prev.keypoints, prev.descriptors, prev_depth, cur.keypoints,
              cur.descriptors, options.prediction, options.guided));
        }
      }
      prev = std::move(cur);
      prev_depth = depth;
    }
    best = std::min(best, MsSince(t0) / static_cast<double>(d.frames.size()));
  }
  cv::setNumThreads(threads);
  return best;
}

// How much two threads give on this machine for independent work: ORB-1000 on the stream's
// frames, one thread doing 2 x 31 frames vs two threads doing 31 each (no sharing between them).
// Virtual CPUs that share a physical core (or a busy host) give well under 2.
double TwoThreadScaling() {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const auto work = [] {
    FeatureOptions o;
    for (size_t i = 0; i < 31; ++i) benchmark::DoNotOptimize(ExtractFeatures(Image(i), o));
  };
  double best = 0.0;
  for (int trial = 0; trial < 3; ++trial) {
    const auto t0 = SteadyClock::now();
    work();
    work();
    const double one = MsSince(t0);
    const auto t1 = SteadyClock::now();
    std::thread other(work);
    work();
    other.join();
    best = std::max(best, one / MsSince(t1));
  }
  cv::setNumThreads(threads);
  return best;
}

}  // namespace bench
}  // namespace imumatch

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  imumatch::bench::Image(0);  // renders the stream before the timings
  benchmark::RunSpecifiedBenchmarks();
  using namespace imumatch;
  EndToEndOptions e2e;
  e2e.max_frames = 31;
  e2e.repetitions = 5;
  const EndToEndTiming t = MeasureEndToEnd(bench::Stream().source, EvaluationOptions(), e2e);
  std::printf(
      "\nEnd to end, ORB-1000 %dx%d, %d frames, best of %d alternating passes (%d OpenCV "
      "threads):\n"
      "%-58s %13s %11s\n"
      "%-58s %13.2f %11.2f\n"
      "%-58s %13.2f %11.2f\n"
      "%-58s %13.2f %11.2f\n"
      "throughput x%.2f (target >= 2.5), latency x%.2f (target <= 0.6); matches per pass: "
      "sequential %d, imumatch %d, overlapped %d\n",
      t.width, t.height, t.frames, e2e.repetitions, t.threads, "", "ms per frame", "latency ms",
      "sequential OpenCV (decode, ORB, BF knn + ratio)", t.sequential_ms_per_frame,
      t.sequential_latency_ms, "imumatch frame by frame (decode|depth, ORB split, guided)",
      t.imumatch_ms_per_frame, t.imumatch_latency_ms,
      "imumatch overlapped (ORB | decode, depth, guided)", t.overlapped_ms_per_frame,
      t.overlapped_latency_ms, t.Throughput(), t.LatencyRatio(), t.sequential_matches,
      t.imumatch_matches, t.overlapped_matches);
  // The work per frame of imumatch's stream on one thread: decode image + depth, ORB, guided.
  const double scaling = bench::TwoThreadScaling();
  std::printf(
      "two threads on this machine run %.2fx the work of one (independent ORB-1000 runs); "
      "imumatch's frame work on one thread (stage timings above: decode image + depth + ORB + "
      "IMU/guided) over %.2f threads' worth bounds the throughput ratio at about x%.2f\n",
      scaling, scaling, t.sequential_ms_per_frame * scaling / bench::OneThreadFrameMs());
  benchmark::Shutdown();
  return 0;
}
