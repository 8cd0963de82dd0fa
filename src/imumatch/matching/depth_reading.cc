#include "imumatch/matching/depth_reading.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace imumatch {

namespace {
template <typename T>
float SampleTyped(const cv::Mat& depth, double inv_scale, float x, float y, DepthSampling mode) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (!std::isfinite(x) || !std::isfinite(y)) return nan;
  const int cx = static_cast<int>(std::lround(x)), cy = static_cast<int>(std::lround(y));
  if (cx < 0 || cy < 0 || cx >= depth.cols || cy >= depth.rows) return nan;
  if (mode == DepthSampling::kNearest) {
    const float centre = ReadingToMetres<T>(depth.at<T>(cy, cx), inv_scale);
    if (!std::isnan(centre)) return centre;
  }
  std::array<float, 9> vals;
  int n = 0;
  float best = nan, best_d2 = std::numeric_limits<float>::infinity();
  for (int r = std::max(cy - 1, 0); r <= std::min(cy + 1, depth.rows - 1); ++r) {
    const T* row = depth.ptr<T>(r);
    for (int c = std::max(cx - 1, 0); c <= std::min(cx + 1, depth.cols - 1); ++c) {
      const float z = ReadingToMetres<T>(row[c], inv_scale);
      if (std::isnan(z)) continue;
      vals[n++] = z;
      const float d2 = (c - x) * (c - x) + (r - y) * (r - y);
      if (d2 < best_d2) {
        best_d2 = d2;
        best = z;
      }
    }
  }
  if (n == 0) return nan;
  switch (mode) {
    case DepthSampling::kNearest:
      return best;
    case DepthSampling::kMin3x3:
      return *std::min_element(vals.begin(), vals.begin() + n);
    case DepthSampling::kMedian3x3:
      // Lower median for an even count (a real reading, never an average across an edge).
      std::nth_element(vals.begin(), vals.begin() + (n - 1) / 2, vals.begin() + n);
      return vals[(n - 1) / 2];
  }
  return nan;
}

}  // namespace

float SampleDepth(const cv::Mat& depth, double depth_scale, float x, float y, DepthSampling mode) {
  CheckDepthImage(depth, depth_scale);
  if (depth.type() == CV_16UC1) return SampleTyped<uint16_t>(depth, 1.0 / depth_scale, x, y, mode);
  return SampleTyped<float>(depth, 1.0, x, y, mode);
}

namespace {

// Depth at each position position_of(i), i < n, on the image's type chosen once.
template <typename PositionOf>
std::vector<float> SampleEach(const cv::Mat& depth, double depth_scale, size_t n,
                              DepthSampling mode, PositionOf position_of) {
  CheckDepthImage(depth, depth_scale);
  std::vector<float> out(n);
  const bool raw = depth.type() == CV_16UC1;
  const double inv = 1.0 / depth_scale;
  for (size_t i = 0; i < n; ++i) {
    const cv::Point2f p = position_of(i);
    out[i] = raw ? SampleTyped<uint16_t>(depth, inv, p.x, p.y, mode)
                 : SampleTyped<float>(depth, 1.0, p.x, p.y, mode);
  }
  return out;
}

}  // namespace

std::vector<float> SampleDepths(const cv::Mat& depth, double depth_scale,
                                const std::vector<KeypointInfo>& keypoints, DepthSampling mode) {
  return SampleEach(depth, depth_scale, keypoints.size(), mode,
                    [&](size_t i) { return cv::Point2f(keypoints[i].x, keypoints[i].y); });
}

std::vector<float> SampleDepths(const cv::Mat& depth, double depth_scale,
                                const std::vector<cv::KeyPoint>& keypoints, DepthSampling mode) {
  return SampleEach(depth, depth_scale, keypoints.size(), mode,
                    [&](size_t i) { return keypoints[i].pt; });
}

}  // namespace imumatch
