#include "imumatch/matching/scene_depth.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

// Points at known depths in front of camera A, seen exactly in B after true_motion; one random
// 256-bit descriptor per point, the same in both frames (partner i of A is keypoint i of B).
struct Scene {
  PinholeCamera camera = PinholeCamera::KinectDefault();
  std::vector<KeypointInfo> kps_a, kps_b;
  std::vector<float> depths;
  cv::Mat desc_a, desc_b;
};

// `near_fraction` of the points at depths in near_range, the others in far_range.
Scene MakeScene(int n, const Rigid3d& true_motion, double near_fraction,
                std::pair<double, double> near_range, std::pair<double, double> far_range,
                uint32_t seed) {
  Scene s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uu(20, 619), uv(20, 459), unit(0, 1);
  std::uniform_int_distribution<int> byte(0, 255);
  s.desc_a = cv::Mat(n, 32, CV_8U);
  while (static_cast<int>(s.kps_a.size()) < n) {
    const bool near = unit(rng) < near_fraction;
    const auto [lo, hi] = near ? near_range : far_range;
    const double z = lo + (hi - lo) * unit(rng);
    const Eigen::Vector2d pa(uu(rng), uv(rng));
    const auto pb = s.camera.Project(true_motion * s.camera.Unproject(pa, z));
    if (!pb || !s.camera.IsInside(*pb, 1.0)) continue;
    const int row = static_cast<int>(s.kps_a.size());
    for (int k = 0; k < 32; ++k) s.desc_a.at<uint8_t>(row, k) = static_cast<uint8_t>(byte(rng));
    s.kps_a.push_back({static_cast<float>(pa.x()), static_cast<float>(pa.y()), -1.0f, 0.0f, 0});
    s.kps_b.push_back({static_cast<float>(pb->x()), static_cast<float>(pb->y()), -1.0f, 0.0f, 0});
    s.depths.push_back(static_cast<float>(z));
  }
  s.desc_b = s.desc_a.clone();
  return s;
}

struct SceneRun {
  SceneNearDepth near;
  std::vector<KeypointPrediction> predictions;
  int partners_inside = 0;  // predictions whose region holds the true partner
  int correct = 0;
  int64_t points_scanned = 0;
};

SceneRun Predict(const Scene& s, const CameraMotion& motion, const PredictionOptions& po,
                 const std::vector<float>& depths) {
  SceneRun r;
  const KeypointPredictor predictor(s.camera, motion, po);
  GridIndex grid;
  const GuidedMatcherOptions mo;
  grid.Build(s.kps_b, s.camera.width, s.camera.height, static_cast<float>(mo.grid_cell_size));
  GuidedSearchScratch scratch;
  r.near = PredictKeypointsInScene(predictor, s.kps_a, depths, DescriptorView::FromMat(s.desc_a),
                                   s.kps_b, grid, DescriptorView::FromMat(s.desc_b), mo,
                                   &r.predictions, &scratch);
  for (size_t i = 0; i < s.kps_a.size(); ++i) {
    r.partners_inside +=
        r.predictions[i].HasWindow() && r.predictions[i].Contains(s.kps_b[i].x, s.kps_b[i].y);
  }
  const MatchResult m = MatchGuided(r.predictions, s.kps_a, DescriptorView::FromMat(s.desc_a),
                                    s.kps_b, grid, DescriptorView::FromMat(s.desc_b), mo, &scratch);
  for (const Match& x : m.matches) r.correct += x.query_idx == x.train_idx;
  r.points_scanned = m.stats.points_scanned;
  return r;
}

CameraMotion Given(const Rigid3d& r) {
  CameraMotion m;
  m.cam_b_from_cam_a = r;
  return m;
}

// 0.3 m sideways: from 0.1 m a segment would cross the whole image.
const Rigid3d kMotion(FromEulerZYX(0.01, -0.02, 0.01), Eigen::Vector3d(0.3, 0.0, 0.02));

TEST(SceneDepthTest, MovesTheNearEndToHalfTheNearestPilotDepth) {
  const Scene s = MakeScene(400, kMotion, 0.0, {0, 0}, {4.0, 10.0}, 7);
  PredictionOptions po;
  const SceneRun adapted = Predict(s, Given(kMotion), po, {});
  po.scene_near.enabled = false;
  const SceneRun fixed = Predict(s, Given(kMotion), po, {});

  EXPECT_EQ(adapted.near.pilot_queries, 100);
  EXPECT_EQ(adapted.near.pilot_matches, 100);
  // The nearest point lies beyond 4 m: on the ladder 0.1 x 2^k the deepest near end whose capsule
  // still holds it is 3.2 m (from 6.4 m its partner is 525 x 0.3 x (1/4 - 1/6.4) = 15 px off the
  // segment, wider than the capsule); the segments start at half of it.
  EXPECT_DOUBLE_EQ(adapted.near.near_depth_m, 3.2);
  EXPECT_DOUBLE_EQ(adapted.near.segment_min_depth_m, 1.6);
  EXPECT_TRUE(adapted.near.moved);
  EXPECT_FALSE(fixed.near.moved);
  EXPECT_EQ(fixed.near.pilot_queries, 0);
  EXPECT_DOUBLE_EQ(fixed.near.segment_min_depth_m, 0.1);
  // Every partner stays in its region, and every point is still matched, reading far fewer
  // points of B.
  EXPECT_EQ(adapted.partners_inside, 400);
  EXPECT_EQ(fixed.partners_inside, 400);
  EXPECT_EQ(adapted.correct, fixed.correct);
  EXPECT_GT(adapted.correct, 390);
  EXPECT_LT(adapted.points_scanned * 2, fixed.points_scanned);
}

TEST(SceneDepthTest, KeepsANearObjectInsideItsCapsules) {
  // 10 % of the points on an object at 0.5-0.7 m: the pilot samples it, the near end stays
  // below it (0.4 m on the ladder, segments from 0.2 m) and every partner stays inside.
  const Scene s = MakeScene(600, kMotion, 0.1, {0.5, 0.7}, {4.0, 10.0}, 11);
  const SceneRun r = Predict(s, Given(kMotion), PredictionOptions(), {});
  EXPECT_TRUE(r.near.moved);
  EXPECT_DOUBLE_EQ(r.near.near_depth_m, 0.4);
  EXPECT_DOUBLE_EQ(r.near.segment_min_depth_m, 0.2);
  EXPECT_EQ(r.partners_inside, 600);
}

TEST(SceneDepthTest, ANearPointCoveredOnlyByTheCapsulesWidthStillBoundsTheNearEnd) {
  // 1.8 cm of translation: a point at 2.5 m moves 525 x 0.018 / 2.5 = 3.8 px off the point at
  // infinity, inside the capsules' 4.3 px half width even from a near end at 51.2 m (the ladder's
  // top), while points at 1.2-1.3 m move 7.3-7.9 px. Three of those come first in A, where the
  // evenly spread pilot (its first index is n / 200) does not look. The nearest pilot depth must
  // then come from where the 2.5 m points lie along the line, not from the ladder: the segments
  // start at half of 2.4-2.6 m and keep the nearer points.
  const Rigid3d motion(FromEulerZYX(0.01, -0.02, 0.01), Eigen::Vector3d(0.018, 0.0, 0.002));
  Scene s = MakeScene(3, motion, 1.0, {1.2, 1.3}, {0, 0}, 23);
  const Scene rest = MakeScene(600, motion, 0.1, {2.4, 2.6}, {20.0, 40.0}, 29);
  s.kps_a.insert(s.kps_a.end(), rest.kps_a.begin(), rest.kps_a.end());
  s.kps_b.insert(s.kps_b.end(), rest.kps_b.begin(), rest.kps_b.end());
  cv::vconcat(s.desc_a, rest.desc_a, s.desc_a);
  s.desc_b = s.desc_a.clone();
  const SceneRun r = Predict(s, Given(motion), PredictionOptions(), {});
  EXPECT_TRUE(r.near.moved);
  EXPECT_GT(r.near.near_depth_m, 2.3);
  EXPECT_LT(r.near.near_depth_m, 2.7);
  EXPECT_EQ(r.partners_inside, 603);
}

TEST(SceneDepthTest, HoldsWhenTheTranslationIsOffWithinItsUncertainty) {
  // The camera moved 1 cm along x; the IMU says 1 cm along y (1 sigma: 1 cm per axis). Along the
  // given epipolar lines the partners do not move at all (they triangulate at infinity); the 10 %
  // of the points at 0.5-0.6 m lie 9-10.5 px across them, which only the width of a capsule with
  // a near end around 1 m covers (its half width is 3.03 x 525 x 0.01 / z_near px). The ladder
  // measures exactly that, so the segments keep a near end that holds them.
  const Rigid3d truth(FromEulerZYX(0.01, -0.02, 0.01), Eigen::Vector3d(0.01, 0.0, 0.0));
  const Scene s = MakeScene(500, truth, 0.1, {0.5, 0.6}, {4.0, 10.0}, 13);
  CameraMotion given = Given(Rigid3d(truth.rotation, Eigen::Vector3d(0.0, 0.01, 0.0)));
  given.covariance.bottomRightCorner<3, 3>() = Eigen::Matrix3d::Identity() * 0.01 * 0.01;
  PredictionOptions po;
  po.scene_near.enabled = false;
  const SceneRun fixed = Predict(s, given, po, {});
  const SceneRun adapted = Predict(s, given, PredictionOptions(), {});
  EXPECT_EQ(fixed.partners_inside, 500);
  EXPECT_TRUE(adapted.near.moved);
  EXPECT_LE(adapted.near.near_depth_m, 1.6);
  EXPECT_EQ(adapted.partners_inside, 500);
  EXPECT_LT(adapted.points_scanned, fixed.points_scanned);
}

TEST(SceneDepthTest, KeypointsWithDepthOrFewWithoutNeedNoPilot) {
  const Scene s = MakeScene(300, kMotion, 0.0, {0, 0}, {4.0, 10.0}, 17);
  const SceneRun r = Predict(s, Given(kMotion), PredictionOptions(), s.depths);
  EXPECT_EQ(r.near.pilot_queries, 0);
  EXPECT_FALSE(r.near.moved);
  const std::vector<KeypointPrediction> plain =
      PredictKeypoints(s.camera, Given(kMotion), s.kps_a, s.depths, PredictionOptions());
  ASSERT_EQ(plain.size(), r.predictions.size());
  for (size_t i = 0; i < plain.size(); ++i) {
    EXPECT_EQ(plain[i].status, PredictionStatus::kWithDepth);
    EXPECT_EQ(plain[i].uv, r.predictions[i].uv);
  }
  EXPECT_EQ(r.partners_inside, 300);
  // 150 keypoints without depth (fewer than twice the pilot): the pilot would not pay for itself.
  const Scene few = MakeScene(150, kMotion, 0.0, {0, 0}, {4.0, 10.0}, 17);
  const SceneRun f = Predict(few, Given(kMotion), PredictionOptions(), {});
  EXPECT_EQ(f.near.pilot_queries, 0);
  EXPECT_DOUBLE_EQ(f.near.segment_min_depth_m, 0.1);
  EXPECT_EQ(f.partners_inside, 150);
}

TEST(SceneDepthTest, TooFewPilotMatchesKeepTheConfiguredNearEnd) {
  // B's descriptors unrelated to A's: the pilot matches nothing, nothing is learned.
  Scene s = MakeScene(200, kMotion, 0.0, {0, 0}, {4.0, 10.0}, 19);
  cv::randu(s.desc_b, 0, 256);
  const SceneRun r = Predict(s, Given(kMotion), PredictionOptions(), {});
  EXPECT_EQ(r.near.pilot_queries, 100);
  EXPECT_LT(r.near.pilot_matches, 20);
  EXPECT_TRUE(std::isnan(r.near.near_depth_m));
  EXPECT_FALSE(r.near.moved);
  EXPECT_DOUBLE_EQ(r.near.segment_min_depth_m, 0.1);
}

TEST(SceneDepthTest, OptionsAreChecked) {
  PredictionOptions po;
  po.scene_near.pilot_queries = 0;
  EXPECT_THROW(po.Check(), InvalidArgument);
  po = PredictionOptions();
  po.scene_near.near_margin = 1.5;
  EXPECT_THROW(po.Check(), InvalidArgument);
  po = PredictionOptions();
  po.scene_near.near_quantile = 1.0;
  EXPECT_THROW(po.Check(), InvalidArgument);
  po = PredictionOptions();
  po.scene_near.pilot_ratio = 0.0;
  EXPECT_THROW(po.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
