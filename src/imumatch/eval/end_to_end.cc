#include "imumatch/eval/end_to_end.h"

#include <algorithm>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/eval/pair_motion.h"
#include "imumatch/features/orb_split.h"
#include "imumatch/features/parallel_tasks.h"
#include "imumatch/matching/baseline_matchers.h"

namespace imumatch {

void EndToEndOptions::Check() const {
  IMUMATCH_CHECK(max_frames >= 2, "max_frames = " << max_frames);
  IMUMATCH_CHECK(max_keypoints >= 1, "max_keypoints = " << max_keypoints);
  IMUMATCH_CHECK(repetitions >= 1 && repetitions <= 100, "repetitions = " << repetitions);
}

std::string EndToEndTiming::Describe() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  out << "end-to-end ORB-1000 stream over " << frames << " frames (" << width << "x" << height
      << "): sequential OpenCV (decode + ORB + BFMatcher knn/ratio) " << sequential_ms_per_frame
      << " ms/frame, latency " << sequential_latency_ms << " ms; imumatch on " << threads
      << " threads frame by frame (decode image | depth, ORB levels split, IMU + guided) "
      << imumatch_ms_per_frame << " ms/frame, latency " << imumatch_latency_ms
      << " ms; overlapped (next image decoded during ORB) " << overlapped_ms_per_frame
      << " ms/frame, latency " << overlapped_latency_ms << " ms";
  if (imumatch_ms_per_frame > 0.0 && sequential_latency_ms > 0.0) {
    out << " (throughput x" << Throughput() << ", latency x" << LatencyRatio() << ")";
  }
  if (motion_failures > 0) out << "; " << motion_failures << " frames had no motion";
  return out.str();
}

namespace {

struct PassTiming {
  double ms_per_frame = 0.0;
  double latency_ms = 0.0;
  int matches = 0;
  int motion_failures = 0;
};

PassTiming SequentialOpenCvPass(const EvalSource& source, const EvaluationOptions& options,
                                const EndToEndOptions& e2e, size_t n, cv::Size* size) {
  PassTiming pass;
  cv::Ptr<cv::ORB> orb = cv::ORB::create(e2e.max_keypoints);
  std::vector<cv::KeyPoint> kp_prev, kp;
  cv::Mat desc_prev, desc;
  double latency_sum = 0.0;
  const auto t0 = SteadyClock::now();
  for (size_t i = 0; i < n; ++i) {
    const auto frame_start = SteadyClock::now();
    const cv::Mat image = source.opencv_image_reader(e2e.first_frame + i);
    *size = image.size();
    orb->detectAndCompute(image, cv::noArray(), kp, desc);
    if (i > 0) {
      pass.matches += static_cast<int>(MatchOpenCvKnnRatio(desc_prev, desc, options.ratio).size());
    }
    latency_sum += MsSince(frame_start);
    std::swap(kp_prev, kp);
    std::swap(desc_prev, desc);
  }
  pass.ms_per_frame = MsSince(t0) / static_cast<double>(n);
  pass.latency_ms = latency_sum / static_cast<double>(n);
  return pass;
}

// Matches frame `index` (cur) with frame index - 1 (prev, with its depth): guided with the pair's
// IMU motion, or brute force when there is none. Adds to the pass's counts.
void MatchWithPrevious(const Dataset& dataset, size_t index, size_t pair_index,
                       const EvaluationOptions& options, const ImuBiasEstimate& bias,
                       const Features& prev, const cv::Mat& prev_depth, const Features& cur,
                       GuidedMatcherWorkspace* workspace, PassTiming* pass) {
  std::string reason;
  const std::optional<PairMotion> motion =
      (dataset.frames[index - 1].world_from_cam && dataset.frames[index].world_from_cam)
          ? ComputePairMotion(dataset, {index - 1, index}, pair_index, options, bias, reason)
          : std::nullopt;
  if (motion) {
    const MatchResult r = workspace->Match(dataset.camera, motion->motion, prev.keypoints,
                                           prev.descriptors, prev_depth, cur.keypoints,
                                           cur.descriptors, options.prediction, options.guided);
    pass->matches += static_cast<int>(r.matches.size());
  } else {
    ++pass->motion_failures;
    pass->matches += static_cast<int>(
        MatchOpenCvKnnRatio(prev.descriptors, cur.descriptors, options.ratio).size());
  }
}

PassTiming ImumatchPass(const EvalSource& source, const EvaluationOptions& options,
                        const EndToEndOptions& e2e, size_t n, const ImuBiasEstimate& bias) {
  const Dataset& dataset = source.dataset;
  PassTiming pass;
  FeatureOptions fopts = options.features;
  fopts.kind = DetectorKind::kOrb;
  fopts.max_keypoints = e2e.max_keypoints;
  fopts.threads = 2;
  GuidedMatcherWorkspace workspace;
  Features prev, cur;
  cv::Mat prev_depth, image, depth;
  double latency_sum = 0.0;
  const auto t0 = SteadyClock::now();
  for (size_t i = 0; i < n; ++i) {
    const size_t index = e2e.first_frame + i;
    const auto frame_start = SteadyClock::now();
    // The depth is needed only when this frame is A of the next pair, but decoding it next to the
    // image uses the second core while the image decodes.
    RunTasks(2, [&](int task) {
      if (task == 0) {
        image = source.image_reader(index);
      } else {
        depth = source.depth_reader(index);
      }
    });
    cur = ExtractFeatures(image, fopts);
    if (i > 0) {
      MatchWithPrevious(dataset, index, i, options, bias, prev, prev_depth, cur, &workspace, &pass);
    }
    latency_sum += MsSince(frame_start);
    std::swap(prev, cur);
    std::swap(prev_depth, depth);
  }
  pass.ms_per_frame = MsSince(t0) / static_cast<double>(n);
  pass.latency_ms = latency_sum / static_cast<double>(n);
  return pass;
}

// The overlapped schedule: step t decodes image t and describes frame t-1 (ORB in two parts,
// depth decode), four tasks that OpenCV's threads take in this order as they free up (the longest
// first); then frame t-1 is matched with frame t-2.
PassTiming OverlappedPass(const EvalSource& source, const EvaluationOptions& options,
                          const EndToEndOptions& e2e, size_t n, const ImuBiasEstimate& bias) {
  const Dataset& dataset = source.dataset;
  PassTiming pass;
  OrbSplitParams orb = ToOrbSplitParams(options.features);
  orb.max_keypoints = e2e.max_keypoints;
  GuidedMatcherWorkspace workspace;
  cv::Mat image[2], depth[2];  // by frame parity
  Features prev, cur;
  std::vector<cv::KeyPoint> part_kp[2];
  cv::Mat part_desc[2];
  std::vector<SteadyClock::time_point> started(n);
  double latency_sum = 0.0;
  const auto t0 = SteadyClock::now();
  for (size_t t = 0; t <= n; ++t) {
    if (t < n) started[t] = SteadyClock::now();
    const size_t k = t - 1;  // the frame described in this step (when t >= 1)
    RunTasks(4, [&](int task) {
      if (task == 0 && t < n) image[t % 2] = source.image_reader(e2e.first_frame + t);
      if (t == 0) return;
      if (task == 1) {
        DetectAndComputeOrbPart(image[k % 2], orb, 0, &part_kp[0], &part_desc[0]);
      } else if (task == 2) {
        depth[k % 2] = source.depth_reader(e2e.first_frame + k);
      } else if (task == 3) {
        DetectAndComputeOrbPart(image[k % 2], orb, 1, &part_kp[1], &part_desc[1]);
      }
    });
    if (t == 0) continue;
    std::vector<cv::KeyPoint> merged;
    cv::Mat merged_desc;
    MergeOrbSplitParts(part_kp, part_desc, &merged, &merged_desc);
    cur = StrongestFirst(merged, merged_desc, e2e.max_keypoints);  // as ExtractFeatures does
    if (k > 0) {
      MatchWithPrevious(dataset, e2e.first_frame + k, k, options, bias, prev, depth[(k - 1) % 2],
                        cur, &workspace, &pass);
    }
    latency_sum += MsSince(started[k]);
    std::swap(prev, cur);
  }
  pass.ms_per_frame = MsSince(t0) / static_cast<double>(n);
  pass.latency_ms = latency_sum / static_cast<double>(n);
  return pass;
}

}  // namespace

EndToEndTiming MeasureEndToEnd(const EvalSource& source, const EvaluationOptions& options,
                               const EndToEndOptions& e2e) {
  e2e.Check();
  options.Check();
  IMUMATCH_CHECK(source.image_reader && source.depth_reader && source.opencv_image_reader,
                 "the end-to-end timing needs a source with separate image and depth readers "
                 "and an OpenCV image reader");
  const Dataset& dataset = source.dataset;
  const ImuBiasEstimate bias = options.motion_source == MotionSource::kImu
                                   ? EstimateImuBias(dataset, options.still_init_s)
                                   : ImuBiasEstimate();
  EndToEndTiming timing;
  if (e2e.first_frame >= dataset.frames.size()) return timing;
  const size_t n = std::min(e2e.max_frames, dataset.frames.size() - e2e.first_frame);
  if (n < 2) return timing;
  timing.frames = static_cast<int>(n);
  timing.threads = cv::getNumThreads();
  const double inf = std::numeric_limits<double>::infinity();
  timing.sequential_ms_per_frame = timing.sequential_latency_ms = inf;
  timing.imumatch_ms_per_frame = timing.imumatch_latency_ms = inf;
  timing.overlapped_ms_per_frame = timing.overlapped_latency_ms = inf;
  // The two pipelines alternate, so that a slow spell of the machine hits both.
  for (int rep = 0; rep < e2e.repetitions; ++rep) {
    cv::Size size;
    const PassTiming s = SequentialOpenCvPass(source, options, e2e, n, &size);
    const PassTiming m = ImumatchPass(source, options, e2e, n, bias);
    const PassTiming o = OverlappedPass(source, options, e2e, n, bias);
    timing.width = size.width;
    timing.height = size.height;
    timing.sequential_ms_per_frame = std::min(timing.sequential_ms_per_frame, s.ms_per_frame);
    timing.sequential_latency_ms = std::min(timing.sequential_latency_ms, s.latency_ms);
    timing.imumatch_ms_per_frame = std::min(timing.imumatch_ms_per_frame, m.ms_per_frame);
    timing.imumatch_latency_ms = std::min(timing.imumatch_latency_ms, m.latency_ms);
    timing.overlapped_ms_per_frame = std::min(timing.overlapped_ms_per_frame, o.ms_per_frame);
    timing.overlapped_latency_ms = std::min(timing.overlapped_latency_ms, o.latency_ms);
    timing.sequential_matches = s.matches;
    timing.imumatch_matches = m.matches;
    timing.overlapped_matches = o.matches;
    timing.motion_failures = m.motion_failures;
  }
  return timing;
}

}  // namespace imumatch
