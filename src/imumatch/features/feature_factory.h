#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "imumatch/features/orb_split.h"
#include "imumatch/features/surf.h"

namespace imumatch {

enum class DetectorKind { kSift, kSurf, kOrb, kFastBrief, kAkaze, kBrisk };

// Accepts "sift", "surf", "orb", "fast" or "fast_brief", "akaze", "brisk" (case-insensitive).
// Throws InvalidArgument listing the valid names otherwise.
DetectorKind ParseDetectorKind(std::string_view name);
// "sift", "surf", "orb", "fast_brief", "akaze", "brisk".
std::string ToString(DetectorKind kind);
// True for the kinds with binary descriptors compared with NORM_HAMMING (ORB, FAST+BRIEF, AKAZE's
// MLDB, BRISK); false for SIFT and SURF (float, NORM_L2).
bool IsBinaryDescriptor(DetectorKind kind);

struct FeatureOptions {
  DetectorKind kind = DetectorKind::kOrb;
  // Upper bound on the number of keypoints, strongest (largest response) first. >= 1.
  int max_keypoints = 1000;
  // Bound on max_keypoints: 100000 SIFT descriptors are 51 MB, and no frame of a front end needs
  // more (a 4K image at one keypoint per 8 x 8 pixels has 130000 cells).
  static constexpr int kMaxKeypoints = 100000;

  // SIFT (cv::SIFT): contrast threshold (OpenCV default 0.04) and edge threshold (10).
  double sift_contrast_threshold = 0.04;
  double sift_edge_threshold = 10.0;
  // SURF (imumatch::Surf); surf.max_keypoints is replaced by max_keypoints.
  SurfOptions surf;
  // ORB (cv::ORB): pyramid scale factor and number of levels, FAST threshold.
  double orb_scale_factor = 1.2;
  int orb_n_levels = 8;
  int orb_fast_threshold = 20;
  // ORB: with 2 or more, the pyramid levels are split between two tasks on OpenCV's thread pool
  // (DetectAndComputeOrbSplit: the same detector up to the rounding of the deeper levels' sizes).
  // Other kinds ignore it (OpenCV parallelises inside some of them on its own).
  int threads = 1;
  // FAST + BRIEF: FAST-9/16 threshold with non-maximum suppression.
  int fast_threshold = 20;
  // AKAZE (cv::AKAZE, MLDB descriptor): detector response threshold (OpenCV default 0.001).
  double akaze_threshold = 0.001;
  // BRISK (cv::BRISK): AGAST threshold (OpenCV default 30) and octaves (3).
  int brisk_threshold = 30;
  int brisk_octaves = 3;

  void Check() const;
};

// Builds the detector/descriptor of options.kind. FAST+BRIEF is a Feature2D that detects FAST
// corners (non-maximum suppressed), drops those too close to the border for BRIEF, keeps the
// max_keypoints strongest by FAST response and describes them with imumatch::Brief. SIFT, SURF and
// ORB get max_keypoints as their own cap; AKAZE and BRISK have none (ExtractFeatures caps them).
cv::Ptr<cv::Feature2D> CreateFeature2D(const FeatureOptions& options);

struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // one row per keypoint; CV_32F (SIFT, SURF) or CV_8U (binary kinds)
};

// Detects and describes features on an 8-bit gray, BGR or BGRA image. The result holds at most
// options.max_keypoints features sorted by decreasing response, for every kind. Throws
// InvalidArgument for an empty image, another pixel type, options failing Check(), or when an
// OpenCV detector rejects the image (cv::Exception is translated, e.g. for tiny images).
// mask: empty, or 8-bit single-channel of the image's size; keypoints are detected only where it
// is non-zero (e.g. a fisheye's field of view), every kind keeping up to max_keypoints there.
Features ExtractFeatures(const cv::Mat& image, const FeatureOptions& options,
                         const cv::Mat& mask = cv::Mat());

// The ORB settings of options as DetectAndComputeOrbSplit / DetectAndComputeOrbPart take them.
OrbSplitParams ToOrbSplitParams(const FeatureOptions& options);

// The at most max_keypoints strongest features (largest response first, ties in input order):
// how ExtractFeatures orders and caps every detector's output, for callers that detect in parts.
// Throws InvalidArgument when the descriptor rows do not match the keypoints.
Features StrongestFirst(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& descriptors,
                        int max_keypoints);

}  // namespace imumatch
