#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace imumatch {

// ORB (cv::ORB, Harris score, patch 31) with its pyramid levels split between two tasks that run
// on OpenCV's thread pool: levels [0, split) on the full image, levels [split, n_levels) on the
// image of level `split`, built by the same chain of INTER_LINEAR_EXACT resizes that cv::ORB
// uses, with cv::ORB's per-level feature counts. The keypoints of the second part are mapped back
// as cv::ORB reports them (position and size times scale_factor^split, octave + split).
//
// The result is cv::ORB's up to the rounding of the deeper levels' sizes (cv::ORB sizes level l
// from the image, here from level `split`: a level may come out one pixel narrower), so the
// levels below `split` are identical and the others nearly so. split is chosen so that both parts
// take about as long (OrbSplitLevel: levels 0-2 of the default 8 x 1.2). With one thread in
// OpenCV's pool the two parts run one after the other.
struct OrbSplitParams {
  int max_keypoints = 1000;
  float scale_factor = 1.2f;
  int n_levels = 8;
  int fast_threshold = 20;
  // The first level of the second part; 0: OrbSplitLevel(scale_factor, n_levels).
  int split_level = 0;
};
// gray: 8-bit single-channel, non-empty. Throws InvalidArgument otherwise, and cv::Exception where
// cv::ORB does. mask: as cv::ORB takes it (empty, or 8-bit of gray's size; the second part
// resizes it to its first level, nearest neighbour).
void DetectAndComputeOrbSplit(const cv::Mat& gray, const OrbSplitParams& params,
                              std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors,
                              const cv::Mat& mask = cv::Mat());

// The two parts on their own, for callers that schedule them (e.g. next to other work): part 0
// (levels below the split) or 1 (the others), as DetectAndComputeOrbSplit runs them; keypoints in
// the full image's coordinates. MergeOrbSplitParts concatenates part 0 and part 1.
void DetectAndComputeOrbPart(const cv::Mat& gray, const OrbSplitParams& params, int part,
                             std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors,
                             const cv::Mat& mask = cv::Mat());
void MergeOrbSplitParts(std::vector<cv::KeyPoint> (&keypoints)[2], const cv::Mat (&descriptors)[2],
                        std::vector<cv::KeyPoint>* merged_keypoints, cv::Mat* merged_descriptors);

// The first level of the second part for n_levels levels of scale_factor: the smallest split whose
// levels below hold 60 % of the pyramid's cost, a level's cost being the mean of its shares of
// the pixels and of the keypoints (in [1, n_levels - 1]; n_levels when there is a single level).
int OrbSplitLevel(float scale_factor, int n_levels);

}  // namespace imumatch
