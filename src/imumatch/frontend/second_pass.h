#pragma once

#include <vector>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/frontend/motion_refit.h"
#include "imumatch/matching/predictor.h"

// A second guided pass in the windows of a fitted motion: its predictor, and the measure that
// decides whether it is worth running (it must search less than the first pass).
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

}  // namespace imumatch
