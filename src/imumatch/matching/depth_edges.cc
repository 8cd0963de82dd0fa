#include "imumatch/matching/depth_edges.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "imumatch/core/error.h"
#include "imumatch/matching/depth_reading.h"

namespace imumatch {
namespace {

template <typename T>
bool NearEdge(const cv::Mat& depth, double inv_scale, int cx, int cy, int radius, double ratio) {
  float lo = std::numeric_limits<float>::infinity(), hi = 0.0f;
  for (int r = std::max(cy - radius, 0); r <= std::min(cy + radius, depth.rows - 1); ++r) {
    const T* row = depth.ptr<T>(r);
    for (int c = std::max(cx - radius, 0); c <= std::min(cx + radius, depth.cols - 1); ++c) {
      const float z = ReadingToMetres<T>(row[c], inv_scale);
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
  CheckDepthImage(depth, depth_scale);
  if (!options.enabled) return 0;
  const bool raw = depth.type() == CV_16UC1;
  const double inv_scale = raw ? 1.0 / depth_scale : 1.0;
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
