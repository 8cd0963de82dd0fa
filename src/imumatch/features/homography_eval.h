#pragma once

#include <opencv2/core.hpp>

#include "imumatch/features/feature_factory.h"

namespace imumatch {

struct HomographyEvalOptions {
  // A keypoint is repeated / a match is correct when the homography maps the first point within
  // this many pixels of the second. > 0.
  double pixel_tolerance = 3.0;
  // Lowe's ratio test on the two nearest descriptors (best < ratio * second best). In (0, 1].
  double ratio = 0.8;

  void Check() const;
};

// Detector repeatability and descriptor matching precision between two images related by a known
// homography (the protocol of Mikolajczyk et al. restricted to positions).
struct HomographyEval {
  int keypoints1 = 0;
  int keypoints2 = 0;
  // Keypoints of image 1 (2) that the homography (its inverse) maps inside image 2 (1).
  int common1 = 0;
  int common2 = 0;
  // Common keypoints of image 1 whose mapped position is within pixel_tolerance of a keypoint of
  // image 2; repeatability = repeated / min(common1, common2), capped at 1.
  int repeated = 0;
  double repeatability = 0.0;
  // Nearest-neighbour matches 1 -> 2 passing the ratio test, and those that are geometrically
  // correct; precision = correct_matches / matches (0 when there is no match).
  int matches = 0;
  int correct_matches = 0;
  double precision = 0.0;
};

// `h_2_from_1` (3x3, CV_64F or CV_32F) maps pixels of image 1 to image 2. `norm` is the descriptor
// norm (cv::NORM_L2 or cv::NORM_HAMMING). Throws InvalidArgument on a bad homography or sizes.
HomographyEval EvaluateOnHomography(const Features& features1, const Features& features2,
                                    const cv::Mat& h_2_from_1, cv::Size size1, cv::Size size2,
                                    int norm,
                                    const HomographyEvalOptions& options = HomographyEvalOptions());

}  // namespace imumatch
