#include "imumatch/frontend/second_pass.h"

#include <cmath>

#include "imumatch/core/error.h"

namespace imumatch {

KeypointPredictor SecondPassPredictor(const PixelUndistorter& undistorter, const MotionRefit& refit,
                                      const PredictionOptions& prediction,
                                      const SceneNearDepth& first_pass_scene) {
  IMUMATCH_CHECK(refit.ok, "no fitted motion for a second pass: " << refit.reason);
  return KeypointPredictor(undistorter, refit.motion, prediction)
      .WithSceneNearEnd(first_pass_scene);
}

double SearchArea(const std::vector<KeypointPrediction>& predictions) {
  double area = 0.0;
  for (const KeypointPrediction& p : predictions) {
    if (!p.HasWindow()) continue;
    if (p.status == PredictionStatus::kWithoutDepth) {
      const double r = p.radius;
      area +=
          2.0 * r * static_cast<double>((p.segment_end - p.segment_start).norm()) + M_PI * r * r;
    } else {
      area += static_cast<double>(p.max_x - p.min_x) * static_cast<double>(p.max_y - p.min_y);
    }
  }
  return area;
}

}  // namespace imumatch
