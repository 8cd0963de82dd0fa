#pragma once

// The guided matcher's whole per-frame pipeline, composed of the parts below it: depth read in
// frame A, keypoints mapped to ideal pixels, the grid and prepared candidates of frame B, the
// predictions (with the segments' near end from the scene's pilot, scene_depth.h) and the window
// search (guided_matcher.h).

#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/grid_index.h"
#include "imumatch/matching/guided_candidates.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

// The whole pipeline for one frame pair: depth lookup in A (depth_a may be empty: no depth),
// keypoints mapped to ideal pixels, grid over B, prediction (with the segments' near end from the
// scene when prediction_options.scene_near.enabled: PredictKeypointsInScene), matching. Keypoints
// as OpenCV gives them (image pixels).
MatchResult MatchFramesGuided(const PinholeCamera& camera, const CameraMotion& motion,
                              const std::vector<cv::KeyPoint>& keypoints_a,
                              const cv::Mat& descriptors_a, const cv::Mat& depth_a,
                              const std::vector<cv::KeyPoint>& keypoints_b,
                              const cv::Mat& descriptors_b,
                              const PredictionOptions& prediction_options,
                              const GuidedMatcherOptions& matcher_options);

// Reusable per-frame state for a caller that matches many frames: keeps the keypoint copies (in
// ideal pixels), depths, predictions, the grid and the camera's PixelUndistorter between calls so
// their buffers are reused; frame B is prepared for the search once per call (pilot and search).
// Predictions and the grid are in ideal pixels (see KeypointPredictor). In a stream (frame B of
// one call is frame A of the next, with the same keypoint positions) each frame's keypoints are
// mapped to ideal pixels once.
class GuidedMatcherWorkspace {
 public:
  MatchResult Match(const PinholeCamera& camera, const CameraMotion& motion,
                    const std::vector<cv::KeyPoint>& keypoints_a, const cv::Mat& descriptors_a,
                    const cv::Mat& depth_a, const std::vector<cv::KeyPoint>& keypoints_b,
                    const cv::Mat& descriptors_b, const PredictionOptions& prediction_options,
                    const GuidedMatcherOptions& matcher_options);

  const std::vector<KeypointPrediction>& predictions() const { return predictions_; }
  // Where the last call's epipolar segments started (PredictKeypointsInScene).
  const SceneNearDepth& scene_near() const { return scene_near_; }
  // The keypoints of the last call in ideal pixels.
  const std::vector<KeypointInfo>& ideal_keypoints_a() const { return info_a_; }
  const std::vector<KeypointInfo>& ideal_keypoints_b() const { return info_b_; }
  // The grid over the last call's frame B (ideal pixels), for the second look by the image patch
  // (patch_matching.h's MatchByPatch taking a workspace).
  const GridIndex& grid_b() const { return grid_; }

 private:
  const PixelUndistorter& UndistorterFor(const PinholeCamera& camera);
  PixelUndistorter undistorter_;
  bool has_undistorter_ = false;
  std::vector<cv::Point2f> last_b_;  // B's positions of the last call (reused as the next A)
  std::vector<KeypointInfo> info_a_, info_b_;
  std::vector<float> depths_;
  std::vector<KeypointPrediction> predictions_;
  GridIndex grid_;
  GuidedCandidates candidates_b_;  // B prepared once for the pilot and the search
  GuidedSearchScratch scratch_;
  SceneNearDepth scene_near_;
};

}  // namespace imumatch
