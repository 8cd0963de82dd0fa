#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/eval/evaluation.h"

namespace imumatch {

struct MatchImageOptions {
  // Correct matches (residual <= threshold): solid green lines; false ones: dashed red lines.
  double threshold_px = 1.5;
  // Search windows of the guided methods drawn on frame B for the matched keypoints (at most this
  // many, spread evenly over the matches): the search box as a rectangle, the 99% uncertainty
  // ellipse of the prediction, and for keypoints without depth the epipolar segment.
  int max_windows = 40;
  bool draw_unmatched_keypoints = true;
  void Check() const;
};

// Frame A left, frame B right, a header with case, detector, method and counts.
cv::Mat DrawMatchImage(const PairVisual& visual, size_t run_index,
                       const MatchImageOptions& options);

// Writes match_<case>_<pair>_<detector>_<method>.png for every visual and run; returns the paths.
std::vector<std::string> WriteMatchImages(const std::string& dir,
                                          const std::vector<PairVisual>& visuals,
                                          const MatchImageOptions& options);

}  // namespace imumatch
