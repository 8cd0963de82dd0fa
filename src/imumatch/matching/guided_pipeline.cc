#include "imumatch/matching/guided_pipeline.h"

#include "imumatch/core/error.h"
#include "imumatch/matching/depth_reading.h"
#include "imumatch/matching/scene_depth.h"

namespace imumatch {

const PixelUndistorter& GuidedMatcherWorkspace::UndistorterFor(const PinholeCamera& camera) {
  if (!has_undistorter_ || !undistorter_.camera().SameImageGeometry(camera)) {
    undistorter_ = PixelUndistorter(camera);
    has_undistorter_ = true;
  }
  return undistorter_;
}

MatchResult GuidedMatcherWorkspace::Match(const PinholeCamera& camera, const CameraMotion& motion,
                                          const std::vector<cv::KeyPoint>& keypoints_a,
                                          const cv::Mat& descriptors_a, const cv::Mat& depth_a,
                                          const std::vector<cv::KeyPoint>& keypoints_b,
                                          const cv::Mat& descriptors_b,
                                          const PredictionOptions& prediction_options,
                                          const GuidedMatcherOptions& matcher_options) {
  matcher_options.Check();
  const PixelUndistorter& undistorter = UndistorterFor(camera);
  const KeypointPredictor predictor(undistorter, motion, prediction_options);
  const size_t n = keypoints_a.size();
  // Depth is registered to the (distorted) image: sampled at the image positions. No depth image:
  // no depths (every keypoint is predicted along its epipolar segment).
  depths_.clear();
  IMUMATCH_CHECK(depth_a.empty() || (depth_a.cols == camera.width && depth_a.rows == camera.height),
                 "depth_a is " << depth_a.cols << "x" << depth_a.rows << ", the camera "
                               << camera.width << "x" << camera.height
                               << ": a depth image must be registered to the camera's pixels");
  if (!depth_a.empty()) {
    depths_ =
        SampleDepths(depth_a, camera.depth_scale, keypoints_a, prediction_options.depth_sampling);
  }
  // A stream passes each frame twice, as B and then as A: its keypoints were mapped to ideal
  // pixels in the previous call. Reused when the positions are the very same (a cheap compare).
  bool reuse = !undistorter.identity() && keypoints_a.size() == last_b_.size();
  for (size_t i = 0; reuse && i < n; ++i) {
    reuse = keypoints_a[i].pt == last_b_[i];
  }
  if (reuse) {
    info_a_.swap(info_b_);
    for (size_t i = 0; i < n; ++i) {
      info_a_[i].angle_deg = keypoints_a[i].angle;
      info_a_[i].size = keypoints_a[i].size;
      info_a_[i].octave = keypoints_a[i].octave;
    }
  } else {
    ToIdealKeypointInfos(keypoints_a, undistorter, &info_a_);
  }
  ToIdealKeypointInfos(keypoints_b, undistorter, &info_b_);
  last_b_.resize(keypoints_b.size());
  for (size_t j = 0; j < keypoints_b.size(); ++j) last_b_[j] = keypoints_b[j].pt;
  grid_.Build(info_b_, camera.width, camera.height,
              static_cast<float>(matcher_options.grid_cell_size));
  PrepareGuidedCandidates(info_b_, grid_, DescriptorView::FromMat(descriptors_b), &candidates_b_);
  scene_near_ =
      PredictKeypointsInScene(predictor, info_a_, depths_, DescriptorView::FromMat(descriptors_a),
                              info_b_, candidates_b_, matcher_options, &predictions_, &scratch_);
  return MatchGuided(predictions_, info_a_, DescriptorView::FromMat(descriptors_a), candidates_b_,
                     matcher_options, &scratch_);
}

MatchResult MatchFramesGuided(const PinholeCamera& camera, const CameraMotion& motion,
                              const std::vector<cv::KeyPoint>& keypoints_a,
                              const cv::Mat& descriptors_a, const cv::Mat& depth_a,
                              const std::vector<cv::KeyPoint>& keypoints_b,
                              const cv::Mat& descriptors_b,
                              const PredictionOptions& prediction_options,
                              const GuidedMatcherOptions& matcher_options) {
  GuidedMatcherWorkspace workspace;
  return workspace.Match(camera, motion, keypoints_a, descriptors_a, depth_a, keypoints_b,
                         descriptors_b, prediction_options, matcher_options);
}

}  // namespace imumatch
