#pragma once

#include <algorithm>
#include <cstddef>
#include <string>

#include "imumatch/eval/evaluation_options.h"
#include "imumatch/eval/frame_source.h"

namespace imumatch {

// End-to-end timing over a stream of consecutive frames, each read, described with ORB and
// matched with the previous frame, in the same process:
//   - sequential OpenCV: decode the image (cv::imdecode / cv::imread, gray), cv::ORB
//     (max_keypoints), BFMatcher knnMatch + ratio 0.8, one step after the other (OpenCV with its
//     own threads, as a user would run it);
//   - imumatch on two cores, frame by frame (for latency): the frame's image and depth decoded at
//     once on two cores (io's reader: PNGs through DecodePngFast), ORB with its pyramid levels
//     split over the two cores (FeatureOptions::threads), then the IMU camera motion, prediction
//     and guided matching;
//   - imumatch on two cores, overlapped (for throughput): while frame k is described (cv::ORB on
//     one core), the other core decodes frame k+1's image and frame k's depth and matches frame
//     k-1 with frame k-2: two tasks of about equal length per step.
// Throughput: frames per unit of time when the stream is processed flat out (reported as ms per
// frame). Latency: from the start of a frame's read to its matches, averaged over the frames.
// Each figure is the best of `repetitions` passes over the stream (the machine may be shared;
// noise only adds time).
struct EndToEndOptions {
  size_t first_frame = 0;
  size_t max_frames = 30;
  int max_keypoints = 1000;
  int repetitions = 1;
  void Check() const;
};
struct EndToEndTiming {
  int frames = 0;
  int repetitions = 1;  // passes of each pipeline; the figures are the fastest pass's
  int width = 0, height = 0;
  double sequential_ms_per_frame = 0.0;
  double sequential_latency_ms = 0.0;
  double imumatch_ms_per_frame = 0.0;  // frame by frame
  double imumatch_latency_ms = 0.0;
  double overlapped_ms_per_frame = 0.0;  // overlapped
  double overlapped_latency_ms = 0.0;
  int sequential_matches = 0;  // totals over one pass, for a sanity check
  int imumatch_matches = 0;
  int overlapped_matches = 0;  // ~imumatch_matches (unsplit cv::ORB: deeper levels differ)
  int motion_failures = 0;     // frames without a motion (IMU gap / no GT): matched by brute force
  int threads = 0;             // OpenCV's worker threads during the imumatch pass
  double Throughput() const {  // sequential / imumatch ms per frame, the faster imumatch mode
    const double best = std::min(imumatch_ms_per_frame, overlapped_ms_per_frame);
    return best > 0.0 ? sequential_ms_per_frame / best : 0.0;
  }
  double LatencyRatio() const {  // imumatch / sequential latency
    return sequential_latency_ms > 0.0 ? imumatch_latency_ms / sequential_latency_ms : 0.0;
  }
  std::string Describe() const;
};
EndToEndTiming MeasureEndToEnd(const EvalSource& source, const EvaluationOptions& options,
                               const EndToEndOptions& e2e);

}  // namespace imumatch
