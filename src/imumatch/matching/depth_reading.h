#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/core/error.h"
#include "imumatch/matching/match_types.h"

namespace imumatch {

// One depth image's reading in metres, NaN for none: a raw CV_16U value (0 = no reading) times
// inv_scale = 1 / depth_scale, or a CV_32F value in metres (non-finite or <= 0 = no reading).
// Shared by the depth sampling below and the edge test (depth_edges.cc).
template <typename T>
float ReadingToMetres(T v, double inv_scale);
template <>
inline float ReadingToMetres<uint16_t>(uint16_t v, double inv_scale) {
  return v == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v * inv_scale);
}
template <>
inline float ReadingToMetres<float>(float v, double) {
  return (std::isfinite(v) && v > 0.0f) ? v : std::numeric_limits<float>::quiet_NaN();
}

// Throws InvalidArgument unless depth is a non-empty CV_16UC1 (raw) or CV_32FC1 (metres) image
// and depth_scale is positive and finite.
inline void CheckDepthImage(const cv::Mat& depth, double depth_scale) {
  IMUMATCH_CHECK(!depth.empty(), "empty depth image");
  IMUMATCH_CHECK(
      depth.type() == CV_16UC1 || depth.type() == CV_32FC1,
      "depth image must be CV_16UC1 (raw) or CV_32FC1 (metres), got type " << depth.type());
  IMUMATCH_CHECK(std::isfinite(depth_scale) && depth_scale > 0.0, "depth_scale=" << depth_scale);
}

// How a keypoint's depth is read from the depth image of frame A.
//   kNearest: the pixel under the keypoint (rounded); when it has no reading, the valid pixel
//             of the 3x3 neighbourhood nearest to the keypoint's sub-pixel position.
//   kMin3x3 / kMedian3x3: the minimum / median of the valid readings of the 3x3 neighbourhood.
enum class DepthSampling { kNearest, kMin3x3, kMedian3x3 };

// Depth (metres) at sub-pixel position (x, y) of a depth image (image pixels, not ideal ones):
// CV_16U raw (divided by depth_scale, 0 = no reading) or CV_32F metres (0 / NaN / negative = no
// reading). NaN when there is no valid reading. Throws InvalidArgument for other types.
float SampleDepth(const cv::Mat& depth, double depth_scale, float x, float y, DepthSampling mode);
std::vector<float> SampleDepths(const cv::Mat& depth, double depth_scale,
                                const std::vector<KeypointInfo>& keypoints, DepthSampling mode);
std::vector<float> SampleDepths(const cv::Mat& depth, double depth_scale,
                                const std::vector<cv::KeyPoint>& keypoints, DepthSampling mode);

}  // namespace imumatch
