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

std::vector<Match> MatchesExplainedByFit(const std::vector<Match>& matches, const Rigid3d& fitted,
                                         bool with_depth,
                                         const std::vector<cv::KeyPoint>& keypoints_a,
                                         const std::vector<float>& depths_a,
                                         const std::vector<cv::KeyPoint>& keypoints_b,
                                         const PixelUndistorter& undistorter,
                                         const PredictionOptions& prediction, double max_px) {
  const PinholeCamera& camera = undistorter.camera();
  const Eigen::Matrix3d rf = fitted.rotation.toRotationMatrix();
  const Eigen::Vector3d tf = fitted.translation;
  const double f = 0.5 * (camera.fx + camera.fy);
  std::vector<Match> out;
  for (const Match& m : matches) {
    const cv::Point2f& ka = keypoints_a[static_cast<size_t>(m.query_idx)].pt;
    const Eigen::Vector2d pb = PositionInB(m, keypoints_b);
    const Eigen::Vector2d ia = undistorter.ToIdeal(Eigen::Vector2d(ka.x, ka.y));
    const Eigen::Vector2d ib = undistorter.ToIdeal(pb);
    const Eigen::Vector3d xa = camera.IdealToNormalized(ia).homogeneous();
    const Eigen::Vector3d xb = camera.IdealToNormalized(ib).homogeneous();
    double residual = 0.0;
    const double z = depths_a.empty() ? std::nan("") : depths_a[static_cast<size_t>(m.query_idx)];
    if (with_depth && prediction.IsUsableDepth(z)) {
      const Eigen::Vector3d q = rf * (xa * z) + tf;
      residual = f * (q.head<2>() / q.z() - xb.head<2>()).norm();
    } else {
      const Eigen::Vector3d line = tf.cross(rf * xa);
      const double norm = std::hypot(line.x(), line.y());
      residual = norm > 0.0 ? f * std::fabs(xb.dot(line)) / norm : 0.0;
    }
    if (residual <= max_px) out.push_back(m);
  }
  return out;
}

}  // namespace imumatch
