#include "imumatch/features/orb_split.h"

#include <cmath>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/features/parallel_tasks.h"

namespace imumatch {

int OrbSplitLevel(float scale_factor, int n_levels) {
  if (n_levels <= 1) return n_levels;
  // A level's cost: its pixels (FAST, blur) and its keypoints (Harris, orientation, descriptor),
  // as shares of the pyramid's totals, weighted equally. The second part also rebuilds the levels
  // down to the split and carries more levels' fixed costs, so the first part takes 60 %
  // (measured, ORB-1000 on 640x480: parts of 2.8 / 2.2 ms with levels 0-2 first, 2.2 / 2.9 ms
  // with levels 0-1).
  double pixels = 0.0, keypoints = 0.0;
  for (int l = 0; l < n_levels; ++l) {
    pixels += std::pow(scale_factor, -2.0 * l);
    keypoints += std::pow(scale_factor, -1.0 * l);
  }
  double below = 0.0;
  for (int l = 0; l < n_levels - 1; ++l) {
    below += 0.5 * (std::pow(scale_factor, -2.0 * l) / pixels +
                    std::pow(scale_factor, -1.0 * l) / keypoints);
    if (below >= 0.6) return l + 1;
  }
  return n_levels - 1;
}

void DetectAndComputeOrbPart(const cv::Mat& gray, const OrbSplitParams& params, int part,
                             std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors,
                             const cv::Mat& mask) {
  IMUMATCH_CHECK(!gray.empty() && gray.type() == CV_8UC1,
                 "DetectAndComputeOrbSplit needs a non-empty 8-bit gray image");
  IMUMATCH_CHECK(params.max_keypoints >= 1 && params.n_levels >= 1 && params.scale_factor > 1.0f,
                 "bad ORB parameters");
  IMUMATCH_CHECK(part == 0 || part == 1, "ORB part " << part);
  IMUMATCH_CHECK(mask.empty() || (mask.type() == CV_8UC1 && mask.size() == gray.size()),
                 "the ORB mask must be empty or 8-bit of the image's size");
  IMUMATCH_CHECK(params.split_level >= 0 && params.split_level <= params.n_levels,
                 "ORB split level " << params.split_level << " of " << params.n_levels);
  const int split = params.split_level > 0 ? params.split_level
                                           : OrbSplitLevel(params.scale_factor, params.n_levels);
  // cv::ORB's features per level: n * (1 - f) / (1 - f^L) * f^l for a factor f = 1 / scale. The
  // first part's total gives its levels the same shares.
  const double f = 1.0 / params.scale_factor;
  const double share_low = (1.0 - std::pow(f, split)) / (1.0 - std::pow(f, params.n_levels));
  const int n_low = std::max(1, static_cast<int>(std::lround(params.max_keypoints * share_low)));
  const int n_high = std::max(1, params.max_keypoints - n_low);
  keypoints->clear();
  *descriptors = cv::Mat();
  if (part == 0) {
    cv::Ptr<cv::ORB> orb = cv::ORB::create(n_low, params.scale_factor, split, 31, 0, 2,
                                           cv::ORB::HARRIS_SCORE, 31, params.fast_threshold);
    orb->detectAndCompute(gray, mask, *keypoints, *descriptors);
    return;
  }
  if (split >= params.n_levels) return;
  // Level `split` as cv::ORB builds it: each level resized from the previous one.
  cv::Mat level = gray, level_mask;
  for (int l = 1; l <= split; ++l) {
    const double scale = std::pow(params.scale_factor, l);
    const cv::Size size(cvRound(gray.cols / scale), cvRound(gray.rows / scale));
    cv::Mat next;
    cv::resize(level, next, size, 0, 0, cv::INTER_LINEAR_EXACT);
    level = next;
  }
  cv::Ptr<cv::ORB> orb = cv::ORB::create(n_high, params.scale_factor, params.n_levels - split, 31,
                                         0, 2, cv::ORB::HARRIS_SCORE, 31, params.fast_threshold);
  if (!mask.empty()) cv::resize(mask, level_mask, level.size(), 0, 0, cv::INTER_NEAREST);
  orb->detectAndCompute(level, level_mask, *keypoints, *descriptors);
  const float scale = static_cast<float>(std::pow(params.scale_factor, split));
  for (cv::KeyPoint& k : *keypoints) {
    k.pt *= scale;
    k.size *= scale;
    k.octave += split;
  }
}

void MergeOrbSplitParts(std::vector<cv::KeyPoint> (&keypoints)[2], const cv::Mat (&descriptors)[2],
                        std::vector<cv::KeyPoint>* merged_keypoints, cv::Mat* merged_descriptors) {
  merged_keypoints->clear();
  merged_keypoints->reserve(keypoints[0].size() + keypoints[1].size());
  merged_keypoints->insert(merged_keypoints->end(), keypoints[0].begin(), keypoints[0].end());
  merged_keypoints->insert(merged_keypoints->end(), keypoints[1].begin(), keypoints[1].end());
  if (descriptors[1].empty()) {
    *merged_descriptors = descriptors[0];
  } else if (descriptors[0].empty()) {
    *merged_descriptors = descriptors[1];
  } else {
    cv::vconcat(descriptors[0], descriptors[1], *merged_descriptors);
  }
}

void DetectAndComputeOrbSplit(const cv::Mat& gray, const OrbSplitParams& params,
                              std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors,
                              const cv::Mat& mask) {
  std::vector<cv::KeyPoint> kp[2];
  cv::Mat desc[2];
  RunTasks(2, [&](int part) {
    DetectAndComputeOrbPart(gray, params, part, &kp[part], &desc[part], mask);
  });
  MergeOrbSplitParts(kp, desc, keypoints, descriptors);
}

}  // namespace imumatch
