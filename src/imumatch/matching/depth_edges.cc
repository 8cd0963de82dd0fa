#include "imumatch/matching/depth_edges.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

// Depth in metres of one raw value; NaN for no reading.
inline float Metres(uint16_t v, float inv_scale) {
  return v == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v) * inv_scale;
}
inline float Metres(float v, float) {
  return (std::isfinite(v) && v > 0.0f) ? v : std::numeric_limits<float>::quiet_NaN();
}

template <typename T>
bool NearEdge(const cv::Mat& depth, float inv_scale, int cx, int cy, int radius, double ratio) {
  float lo = std::numeric_limits<float>::infinity(), hi = 0.0f;
  for (int r = std::max(cy - radius, 0); r <= std::min(cy + radius, depth.rows - 1); ++r) {
    const T* row = depth.ptr<T>(r);
    for (int c = std::max(cx - radius, 0); c <= std::min(cx + radius, depth.cols - 1); ++c) {
      const float z = Metres(row[c], inv_scale);
      if (std::isnan(z)) return true;  // a hole
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
  }
  return static_cast<double>(hi) > ratio * static_cast<double>(lo);
}

}  // namespace

void DepthEdgeOptions::Check() const {
  IMUMATCH_CHECK(radius_px >= 0 && radius_px <= 64, "radius_px=" << radius_px << " (0 .. 64)");
  IMUMATCH_CHECK(std::isfinite(max_depth_ratio) && max_depth_ratio >= 1.0,
                 "max_depth_ratio=" << max_depth_ratio << " (must be >= 1)");
}

int ClearDepthsNearEdges(const cv::Mat& depth, double depth_scale,
                         const std::vector<cv::KeyPoint>& keypoints,
                         const DepthEdgeOptions& options, std::vector<float>* depths) {
  options.Check();
  IMUMATCH_CHECK(depths != nullptr, "no depths");
  IMUMATCH_CHECK(depths->size() == keypoints.size(),
                 depths->size() << " depths for " << keypoints.size() << " keypoints");
  IMUMATCH_CHECK(!depth.empty(), "empty depth image");
  IMUMATCH_CHECK(depth.type() == CV_16UC1 || depth.type() == CV_32FC1,
                 "depth image must be CV_16UC1 or CV_32FC1");
  IMUMATCH_CHECK(std::isfinite(depth_scale) && depth_scale > 0.0, "depth_scale=" << depth_scale);
  if (!options.enabled) return 0;
  const bool raw = depth.type() == CV_16UC1;
  const float inv_scale = raw ? static_cast<float>(1.0 / depth_scale) : 1.0f;
  int cleared = 0;
  for (size_t i = 0; i < keypoints.size(); ++i) {
    float& z = (*depths)[i];
    if (std::isnan(z)) continue;
    const cv::Point2f& pt = keypoints[i].pt;
    if (!std::isfinite(pt.x) || !std::isfinite(pt.y)) continue;
    const int cx = static_cast<int>(std::lround(pt.x)), cy = static_cast<int>(std::lround(pt.y));
    if (cx < 0 || cy < 0 || cx >= depth.cols || cy >= depth.rows) continue;
    const bool edge =
        raw ? NearEdge<uint16_t>(depth, inv_scale, cx, cy, options.radius_px,
                                 options.max_depth_ratio)
            : NearEdge<float>(depth, inv_scale, cx, cy, options.radius_px, options.max_depth_ratio);
    if (edge) {
      z = std::numeric_limits<float>::quiet_NaN();
      ++cleared;
    }
  }
  return cleared;
}

}  // namespace imumatch
