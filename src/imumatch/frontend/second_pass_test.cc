#include "imumatch/frontend/second_pass.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/frontend/motion_refit_test_util.h"

namespace imumatch {
namespace {

using namespace refit_test;  // NOLINT(build/namespaces)

TEST(SecondPassTest, WindowsShrinkToTheFit) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 300, 0.5, 0.0);
  const PixelUndistorter und(Camera());
  const Eigen::Matrix<double, 6, 1> sigma = Vec6(2e-3, 2e-3, 2e-3, 0.01, 0.01, 0.01);
  const CameraMotion prior = Prior(sigma, sigma);
  MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                              PredictionOptions(), und, MotionRefitOptions());
  ASSERT_TRUE(r.ok) << r.reason;
  PredictionOptions po;
  po.min_half_size = 0.0;
  const SceneNearDepth scene;
  const Eigen::Vector2d uv(300.0, 200.0);
  const KeypointPrediction first = KeypointPredictor(und, prior, po).Predict(uv, 3.0);
  const KeypointPrediction tight = SecondPassPredictor(und, r, po, scene).Predict(uv, 3.0);
  // 1 px keypoints: the window is about the keypoints' noise, sqrt(9.21 * 2) = 4.3 px.
  EXPECT_LT(tight.max_x - tight.min_x, 0.6f * (first.max_x - first.min_x));
  EXPECT_LT(0.5f * (tight.max_x - tight.min_x), 4.6f);
  EXPECT_LT(SearchArea({tight}), 0.4 * SearchArea({first}));
  // The segments keep the first pass's near end.
  SceneNearDepth moved;
  moved.moved = true;
  moved.segment_min_depth_m = 2.0;
  const KeypointPrediction seg = SecondPassPredictor(und, r, po, moved).Predict(uv, std::nan(""));
  ASSERT_EQ(seg.status, PredictionStatus::kWithoutDepth);
  const Eigen::Vector3d near_b = r.motion.cam_b_from_cam_a * Camera().Unproject(uv, 2.0);
  const Eigen::Vector2d near(Camera().fx * near_b.x() / near_b.z() + Camera().cx,
                             Camera().fy * near_b.y() / near_b.z() + Camera().cy);
  EXPECT_LT((seg.segment_start.cast<double>() - near).norm(), 5.0);
  r.ok = false;
  EXPECT_THROW(SecondPassPredictor(und, r, po, scene), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
