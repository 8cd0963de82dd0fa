#pragma once

#include <cstddef>
#include <string>

#include "imumatch/eval/evaluation_options.h"
#include "imumatch/eval/frame_source.h"

namespace imumatch {

// End-to-end timing: a stream of consecutive frames, each read, described with ORB and matched
// with the previous frame.
//   - sequential OpenCV: imread (gray), cv::ORB (max_keypoints), BFMatcher knnMatch + ratio 0.8;
//   - imumatch pipelined: a reader thread decodes the next frame (image + depth) while the current
//     one is processed: ORB, IMU camera motion, prediction, guided matching.
struct EndToEndOptions {
  size_t first_frame = 0;
  size_t max_frames = 30;
  int max_keypoints = 1000;
  void Check() const;
};
struct EndToEndTiming {
  int frames = 0;
  int width = 0, height = 0;
  double sequential_ms_per_frame = 0.0;
  double pipelined_ms_per_frame = 0.0;
  int sequential_matches = 0;  // totals over the stream, for a sanity check
  int pipelined_matches = 0;
  int motion_failures = 0;  // frames without a motion (IMU gap / no GT): matched by brute force
  std::string Describe() const;
};
EndToEndTiming MeasureEndToEnd(const EvalSource& source, const EvaluationOptions& options,
                               const EndToEndOptions& e2e);

}  // namespace imumatch
