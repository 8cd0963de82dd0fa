#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace imumatch {

// Depth read at a keypoint that sits on an occlusion edge belongs to either surface. A corner
// where a near object's outline crosses a far background is detected at the outline, but it moves
// with neither surface, and a depth image reports the near surface there: stereo fattens the
// foreground by up to half its matching block, and a Kinect leaves a shadow of holes or flying
// pixels beside the edge. On EuRoC MH_05's take-off (depth from two-view stereo) such corners
// along a beam 0.6 m away showed 0.13 of the parallax their depth predicts, and, being the
// nearest keypoints, they set the translation's length of a motion fit by their leverage.
//
// A reading counts as "near an edge" when the (2 radius_px + 1)^2 neighbourhood of its keypoint in
// the depth image holds a pixel without a reading (a hole: at an occlusion the sensor sees only
// one side) or readings whose farthest / nearest ratio exceeds max_depth_ratio (a jump).
struct DepthEdgeOptions {
  bool enabled = true;
  // Pixels of the depth image. 5: a stereo matcher's half block (SGBM blocks of 5-11 px fatten
  // the foreground by 2-5 px), a Kinect's edge shadow of several pixels.
  int radius_px = 5;
  // A smooth surface changes depth gradually: even a floor seen at 10 deg changes by about 1.2 %
  // per pixel at 458 px focal length, 13 % across 11 px. 1.25 is a jump.
  double max_depth_ratio = 1.25;
  void Check() const;  // throws InvalidArgument
};

// Sets depths[i] to NaN where keypoint i's reading lies near an edge of the depth image (see
// above); returns how many it cleared. depth: CV_16U raw (depth_scale units per metre) or CV_32F
// metres, of the keypoints' image; depths: one per keypoint (SampleDepths), NaN for none, left
// as is. A keypoint outside the image keeps its value. Throws InvalidArgument for an empty or
// other depth image, a non-positive depth_scale or depths of another size.
int ClearDepthsNearEdges(const cv::Mat& depth, double depth_scale,
                         const std::vector<cv::KeyPoint>& keypoints,
                         const DepthEdgeOptions& options, std::vector<float>* depths);

}  // namespace imumatch
