#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/frontend/motion_refit.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

// A second guided pass in the windows of a fitted motion: its predictor, the measure that decides
// whether it is worth running (it must search less than the first pass), and the filter of its
// matches by the fitted geometry.
namespace imumatch {

// The predictor of a second pass with a fitted motion (refit.ok, else InvalidArgument): the
// fitted motion and covariance, the segments' near end of the first pass (first_pass_scene).
KeypointPredictor SecondPassPredictor(const PixelUndistorter& undistorter, const MotionRefit& refit,
                                      const PredictionOptions& prediction,
                                      const SceneNearDepth& first_pass_scene);

// The summed area (px^2) of the predictions' search regions: a box's 4 hw hh, a capsule's
// 2 r L + pi r^2. A second pass is worth its cost only when it searches less than the first: the
// candidates a window holds, rivals of the true partner in the ratio test, grow with its area.
// A fit that does not shrink the windows (its residuals larger than the keypoints' noise, or a
// prior already as tight) is no reason to match again.
double SearchArea(const std::vector<KeypointPrediction>& predictions);

// The matches a fitted motion (cam_b_from_cam_a) explains within max_px (ideal pixels, at the
// mean focal length): where with_depth and depths_a (metres per keypoint of A; may be empty) holds
// a depth prediction.IsUsableDepth accepts, the distance of B's keypoint (PositionInB) from A's
// keypoint moved by the motion at that depth; else its distance from the epipolar line. A motion
// without translation draws no line: its matches without depth are all kept.
std::vector<Match> MatchesExplainedByFit(const std::vector<Match>& matches, const Rigid3d& fitted,
                                         bool with_depth,
                                         const std::vector<cv::KeyPoint>& keypoints_a,
                                         const std::vector<float>& depths_a,
                                         const std::vector<cv::KeyPoint>& keypoints_b,
                                         const PixelUndistorter& undistorter,
                                         const PredictionOptions& prediction, double max_px);

}  // namespace imumatch
