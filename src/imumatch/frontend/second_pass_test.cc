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

// B's pixel of A's keypoint uv_a at depth z (KinectDefault: no lens distortion).
Eigen::Vector2d InB(const Rigid3d& cam_b_from_cam_a, const Eigen::Vector2d& uv_a, double z) {
  const PinholeCamera c = Camera();
  const Eigen::Vector3d p = cam_b_from_cam_a * c.Unproject(uv_a, z);
  return Eigen::Vector2d(c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy);
}

TEST(SecondPassTest, MatchesExplainedByFitAreThoseWithinTheThreshold) {
  ASSERT_EQ(Camera().fx, Camera().fy);  // pixel distances = f x normalised distances
  const PixelUndistorter und(Camera());
  const Rigid3d motion = TrueMotion();
  const Eigen::Vector2d ua(300.0, 200.0), ua2(420.0, 310.0);
  const Eigen::Vector2d near = InB(motion, ua, 2.0);
  const Eigen::Vector2d along = (InB(motion, ua, 5.0) - near).normalized();  // epipolar line
  const Eigen::Vector2d across(-along.y(), along.x());
  std::vector<cv::KeyPoint> ka, kb;
  std::vector<Match> matches;
  std::vector<float> depths;
  auto add = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, float z) {
    AddMatch(a, b, &ka, &kb, &matches);
    depths.push_back(z);
  };
  add(ua, near, 2.0f);                                // 0: exact
  add(ua, near + 0.9 * along, 2.0f);                  // 1: 0.9 px from the reprojection
  add(ua, near + 3.0 * along, 2.0f);                  // 2: 3 px along the line
  add(ua, near + 1.1 * across, std::nanf(""));        // 3: no depth, 1.1 px off the line
  add(ua, near + 0.9 * across + 40.0 * along, 0.0f);  // 4: zero depth, 0.9 px off
  add(ua2, InB(motion, ua2, 7.0) + Eigen::Vector2d(0.5, 0.3), 1000.0f);  // 5: beyond max_depth
  const PredictionOptions po;
  auto kept = [&](const std::vector<Match>& ms) {
    std::vector<int> idx;
    for (const Match& m : ms) idx.push_back(m.query_idx);
    return idx;
  };
  EXPECT_EQ(kept(MatchesExplainedByFit(matches, motion, true, ka, depths, kb, und, po, 1.0)),
            (std::vector<int>{0, 1, 4, 5}));
  // Without depth every match is judged by its distance from the line: 2 is on it.
  EXPECT_EQ(kept(MatchesExplainedByFit(matches, motion, false, ka, depths, kb, und, po, 1.0)),
            (std::vector<int>{0, 1, 2, 4, 5}));
  EXPECT_EQ(kept(MatchesExplainedByFit(matches, motion, true, ka, {}, kb, und, po, 1.0)),
            (std::vector<int>{0, 1, 2, 4, 5}));
  // A wider threshold keeps 3 (1.1 px off the line) and 2 (3 px from the reprojection).
  EXPECT_EQ(MatchesExplainedByFit(matches, motion, true, ka, depths, kb, und, po, 3.5).size(),
            matches.size());
  // A motion without translation draws no epipolar line: matches without depth all stay.
  const Rigid3d turn(motion.rotation, Eigen::Vector3d::Zero());
  std::vector<float> none(depths.size(), std::nanf(""));
  EXPECT_EQ(MatchesExplainedByFit(matches, turn, true, ka, none, kb, und, po, 1.0).size(),
            matches.size());
}

}  // namespace
}  // namespace imumatch
