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
#include "imumatch/features/parallel_tasks.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/guided_pipeline.h"

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
      << (repetitions > 1 ? ", best of " + std::to_string(repetitions) + " passes each" : "")
      << "): sequential OpenCV (decode + ORB + BFMatcher knn/ratio) " << sequential_ms_per_frame
      << " ms/frame, latency " << sequential_latency_ms << " ms; imumatch on " << threads
      << " threads frame by frame (decode image | depth, ORB levels split, IMU + guided) "
      << imumatch_ms_per_frame << " ms/frame, latency " << imumatch_latency_ms
      << " ms; overlapped (ORB on one core, decoding and matching on the other) "
      << overlapped_ms_per_frame << " ms/frame, latency " << overlapped_latency_ms << " ms";
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

// The overlapped schedule, two tasks per step t of about equal length (one per core):
//   - task 0 decodes image t and depth t-1 (the depth is needed only when frame t-1 is A of the
//     next pair), then matches frame t-2 with frame t-3 (IMU motion + guided);
//   - task 1 describes frame t-1 with ORB on one thread (cv::ORB: the split of the frame-by-frame
//     pipeline helps latency, not throughput, and costs ~10 % more work).
// With TBB under OpenCV, tasks handed out as more, shorter stripes are not taken in index order
// (the range is split in halves), so the schedule is fixed here: a core's work per step is
// ~decode image + decode depth + match against ~ORB. A frame's latency spans three steps.
PassTiming OverlappedPass(const EvalSource& source, const EvaluationOptions& options,
                          const EndToEndOptions& e2e, size_t n, const ImuBiasEstimate& bias) {
  const Dataset& dataset = source.dataset;
  PassTiming pass;
  FeatureOptions fopts = options.features;
  fopts.kind = DetectorKind::kOrb;
  fopts.max_keypoints = e2e.max_keypoints;
  fopts.threads = 1;
  GuidedMatcherWorkspace workspace;
  cv::Mat image[2];      // by frame % 2: image t is written while image t-1 is described
  cv::Mat depth[3];      // by frame % 3: depth t-1 is written while depth t-3 is read
  Features features[3];  // by frame % 3: frame t-1 is described while t-2 and t-3 are matched
  std::vector<SteadyClock::time_point> started(n);
  double latency_sum = 0.0;
  const auto t0 = SteadyClock::now();
  for (size_t t = 0; t <= n + 1; ++t) {
    if (t < n) started[t] = SteadyClock::now();
    RunTasks(2, [&](int task) {
      if (task == 0) {
        if (t < n) image[t % 2] = source.image_reader(e2e.first_frame + t);
        if (t >= 1 && t <= n) depth[(t - 1) % 3] = source.depth_reader(e2e.first_frame + t - 1);
        if (t >= 3) {  // frame k = t - 2 against k - 1 (features and depth of k - 1 ready)
          const size_t k = t - 2;
          MatchWithPrevious(dataset, e2e.first_frame + k, k, options, bias, features[(k - 1) % 3],
                            depth[(k - 1) % 3], features[k % 3], &workspace, &pass);
        }
      } else if (t >= 1 && t <= n) {
        features[(t - 1) % 3] = ExtractFeatures(image[(t - 1) % 2], fopts);
      }
    });
    if (t >= 2) latency_sum += MsSince(started[t - 2]);  // frame t - 2 is matched
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
  timing.repetitions = e2e.repetitions;
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
