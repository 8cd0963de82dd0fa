#include "imumatch/eval/end_to_end.h"

#include <iomanip>
#include <sstream>
#include <vector>

#include <opencv2/features2d.hpp>

#include "imumatch/core/error.h"
#include "imumatch/eval/pair_motion.h"
#include "imumatch/eval/pipelined.h"
#include "imumatch/matching/baseline_matchers.h"

namespace imumatch {

void EndToEndOptions::Check() const {
  IMUMATCH_CHECK(max_frames >= 2, "max_frames = " << max_frames);
  IMUMATCH_CHECK(max_keypoints >= 1, "max_keypoints = " << max_keypoints);
}

std::string EndToEndTiming::Describe() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  out << "end-to-end ORB pipeline over " << frames << " frames (" << width << "x" << height
      << "): sequential OpenCV (imread + ORB + BFMatcher knn/ratio) " << sequential_ms_per_frame
      << " ms/frame, imumatch pipelined (reader thread + ORB + IMU + guided) "
      << pipelined_ms_per_frame << " ms/frame";
  if (pipelined_ms_per_frame > 0.0) {
    out << " (x" << sequential_ms_per_frame / pipelined_ms_per_frame << ")";
  }
  if (motion_failures > 0) out << "; " << motion_failures << " frames had no motion";
  return out.str();
}

EndToEndTiming MeasureEndToEnd(const EvalSource& source, const EvaluationOptions& options,
                               const EndToEndOptions& e2e) {
  e2e.Check();
  options.Check();
  const Dataset& dataset = source.dataset;
  const ImuBiasEstimate bias = options.motion_source == MotionSource::kImu
                                   ? EstimateImuBias(dataset, options.still_init_s)
                                   : ImuBiasEstimate();
  EndToEndTiming timing;
  if (e2e.first_frame >= dataset.frames.size()) return timing;
  const size_t n = std::min(e2e.max_frames, dataset.frames.size() - e2e.first_frame);
  if (n < 2) return timing;
  timing.frames = static_cast<int>(n);

  // Sequential plain OpenCV.
  {
    cv::Ptr<cv::ORB> orb = cv::ORB::create(e2e.max_keypoints);
    cv::BFMatcher matcher(cv::NORM_HAMMING);
    std::vector<cv::KeyPoint> kp_prev, kp;
    cv::Mat desc_prev, desc;
    const auto t0 = SteadyClock::now();
    for (size_t i = 0; i < n; ++i) {
      const FrameImages img = source.reader(e2e.first_frame + i, false);
      timing.width = img.image.cols;
      timing.height = img.image.rows;
      orb->detectAndCompute(img.image, cv::noArray(), kp, desc);
      if (i > 0 && !desc.empty() && !desc_prev.empty()) {
        std::vector<std::vector<cv::DMatch>> knn;
        matcher.knnMatch(desc_prev, desc, knn, 2);
        for (const auto& m : knn) {
          if (m.size() == 1 || (m.size() >= 2 && m[0].distance < options.ratio * m[1].distance))
            ++timing.sequential_matches;
        }
      }
      std::swap(kp_prev, kp);
      std::swap(desc_prev, desc);
    }
    timing.sequential_ms_per_frame = MsSince(t0) / static_cast<double>(n);
  }

  // imumatch, pipelined.
  {
    FeatureOptions fopts = options.features;
    fopts.kind = DetectorKind::kOrb;
    fopts.max_keypoints = e2e.max_keypoints;
    GuidedMatcherWorkspace workspace;
    Features prev;
    cv::Mat prev_depth;
    const auto t0 = SteadyClock::now();
    size_t i = 0;
    RunPipelined<FrameImages>(
        n, 2, [&](size_t k) { return source.reader(e2e.first_frame + k, true); },
        [&](FrameImages img) {
          const size_t index = e2e.first_frame + i;
          Features cur = ExtractFeatures(img.image, fopts);
          if (i > 0) {
            std::string reason;
            const std::optional<PairMotion> motion =
                (dataset.frames[index - 1].world_from_cam && dataset.frames[index].world_from_cam)
                    ? ComputePairMotion(dataset, {index - 1, index}, i, options, bias, reason)
                    : std::nullopt;
            if (motion) {
              const MatchResult r = workspace.Match(
                  dataset.camera, motion->motion, prev.keypoints, prev.descriptors, prev_depth,
                  cur.keypoints, cur.descriptors, options.prediction, options.guided);
              timing.pipelined_matches += static_cast<int>(r.matches.size());
            } else {
              ++timing.motion_failures;
              timing.pipelined_matches += static_cast<int>(
                  MatchOpenCvKnnRatio(prev.descriptors, cur.descriptors, options.ratio).size());
            }
          }
          prev = std::move(cur);
          prev_depth = img.depth;
          ++i;
        });
    timing.pipelined_ms_per_frame = MsSince(t0) / static_cast<double>(n);
  }
  return timing;
}

}  // namespace imumatch
