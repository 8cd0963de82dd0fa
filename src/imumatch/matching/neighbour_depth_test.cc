#include "imumatch/matching/neighbour_depth.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

// Points of two surfaces seen exactly in A and B: a near wall (depth 1.5-2 m) over the left
// half of image A and a far one (6-9 m) over the right half. Partner i of A is keypoint i of B.
struct TwoWallScene {
  PinholeCamera camera = PinholeCamera::KinectDefault();
  std::vector<KeypointInfo> kps_a, kps_b;
  std::vector<double> depths;
};

// 0.15 m sideways and a small rotation: from the default near end (0.1 m) a segment would cross
// the image; between 1.5 and 9 m it spans 525 x 0.15 x (1/1.5 - 1/9) = 44 px.
const Rigid3d kNeighbourMotion(FromEulerZYX(0.01, -0.02, 0.01), Eigen::Vector3d(0.15, 0.0, 0.02));

TwoWallScene MakeTwoWallScene(int n, uint32_t seed) {
  TwoWallScene s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uu(20, 619), uv(20, 459), unit(0, 1);
  while (static_cast<int>(s.kps_a.size()) < n) {
    const Eigen::Vector2d pa(uu(rng), uv(rng));
    const double z = pa.x() < 320 ? 1.5 + 0.5 * unit(rng) : 6.0 + 3.0 * unit(rng);
    const auto pb = s.camera.Project(kNeighbourMotion * s.camera.Unproject(pa, z));
    if (!pb || !s.camera.IsInside(*pb, 1.0)) continue;
    s.kps_a.push_back({static_cast<float>(pa.x()), static_cast<float>(pa.y()), -1.0f, 0.0f, 0});
    s.kps_b.push_back({static_cast<float>(pb->x()), static_cast<float>(pb->y()), -1.0f, 0.0f, 0});
    s.depths.push_back(z);
  }
  return s;
}

CameraMotion ExactMotion() {
  CameraMotion m;
  m.cam_b_from_cam_a = kNeighbourMotion;
  return m;
}

float SegmentLength(const KeypointPrediction& p) {
  return (p.segment_end - p.segment_start).norm();
}

TEST(NeighbourDepthTest, MatchedInverseDepthsFromTheDepthOrTheEpipolarLine) {
  const TwoWallScene s = MakeTwoWallScene(6, 3);
  const KeypointPredictor predictor(s.camera, ExactMotion(), PredictionOptions());
  std::vector<Match> matches(4);
  for (int i = 0; i < 3; ++i) matches[i].query_idx = matches[i].train_idx = i;
  matches[3].query_idx = 3;  // a track: no keypoint of B
  matches[3].train_idx = -1;

  // Without depths: where the partner lies along its line (exact projections, float positions).
  std::vector<double> rho = MatchedInverseDepths(predictor, s.kps_a, {}, matches, s.kps_b);
  ASSERT_EQ(rho.size(), 6u);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(rho[i], 1.0 / s.depths[i], 2e-3) << i;
  EXPECT_TRUE(std::isnan(rho[3]));  // a track without depth
  EXPECT_TRUE(std::isnan(rho[4]));  // not matched
  EXPECT_TRUE(std::isnan(rho[5]));

  // With depths: 1 / depth exactly, the track's too; a depth outside [min_depth, max_depth]
  // counts as none.
  std::vector<float> depths(6, 2.5f);
  depths[1] = 0.0f;
  rho = MatchedInverseDepths(predictor, s.kps_a, depths, matches, s.kps_b);
  EXPECT_DOUBLE_EQ(rho[0], 1.0 / 2.5);
  EXPECT_NEAR(rho[1], 1.0 / s.depths[1], 2e-3);
  EXPECT_DOUBLE_EQ(rho[3], 1.0 / 2.5);
  EXPECT_TRUE(std::isnan(rho[4]));

  // A partner beyond infinity along the line (behind the point at infinity), where the translation
  // pointing the other way would put it at half its inverse depth: 0 (noise) when the motion's
  // translation is known, that negative inverse depth when its sign is open.
  std::vector<KeypointInfo> b = s.kps_b;
  const double rho_beyond = -0.5 / s.depths[0];
  const Eigen::Vector3d bearing = s.camera.Unproject({s.kps_a[0].x, s.kps_a[0].y}, 1.0);
  const auto beyond = s.camera.Project(kNeighbourMotion.rotation * bearing +
                                       rho_beyond * kNeighbourMotion.translation);
  ASSERT_TRUE(beyond.has_value());
  b[0].x = static_cast<float>(beyond->x());
  b[0].y = static_cast<float>(beyond->y());
  rho = MatchedInverseDepths(predictor, s.kps_a, {}, {matches[0]}, b);
  EXPECT_EQ(rho[0], 0.0);
  CameraMotion open = ExactMotion();  // 15 cm known to 10 cm per axis
  open.covariance.bottomRightCorner<3, 3>() = 0.01 * Eigen::Matrix3d::Identity();
  const KeypointPredictor open_predictor(s.camera, open, PredictionOptions());
  ASSERT_TRUE(open_predictor.TranslationSignOpen());
  rho = MatchedInverseDepths(open_predictor, s.kps_a, {}, {matches[0]}, b);
  EXPECT_NEAR(rho[0], rho_beyond, 2e-3);

  std::vector<Match> bad(1);
  bad[0].query_idx = 6;
  bad[0].train_idx = 0;
  EXPECT_THROW(MatchedInverseDepths(predictor, s.kps_a, {}, bad, s.kps_b), InvalidArgument);
  bad[0].query_idx = 0;
  bad[0].train_idx = 6;
  EXPECT_THROW(MatchedInverseDepths(predictor, s.kps_a, {}, bad, s.kps_b), InvalidArgument);
  EXPECT_THROW(MatchedInverseDepths(predictor, s.kps_a, {1.0f}, matches, s.kps_b), InvalidArgument);
}

TEST(NeighbourDepthTest, InverseDepthRangeEndsWhereThePointsAtThoseDepthsProject) {
  const TwoWallScene s = MakeTwoWallScene(1, 5);
  PredictionOptions po;
  po.window_mode = WindowMode::kFixed;  // the segment's ends are not moved out by the noise
  const KeypointPredictor predictor(s.camera, ExactMotion(), po);
  const Eigen::Vector2d uv(s.kps_a[0].x, s.kps_a[0].y);
  const KeypointPrediction p = predictor.PredictInInverseDepthRange(uv, 1.0 / 8.0, 1.0 / 2.0);
  ASSERT_EQ(p.status, PredictionStatus::kWithoutDepth);
  const auto at = [&](double z) {
    return *s.camera.Project(kNeighbourMotion * s.camera.Unproject(uv, z));
  };
  EXPECT_NEAR(p.segment_start.x(), at(2.0).x(), 1e-3);  // the near end first
  EXPECT_NEAR(p.segment_start.y(), at(2.0).y(), 1e-3);
  EXPECT_NEAR(p.segment_end.x(), at(8.0).x(), 1e-3);
  EXPECT_NEAR(p.segment_end.y(), at(8.0).y(), 1e-3);
  // The scale interval is that of the range: z_a / z_b at both ends.
  const Eigen::Vector3d p2 = kNeighbourMotion * s.camera.Unproject(uv, 2.0);
  const Eigen::Vector3d p8 = kNeighbourMotion * s.camera.Unproject(uv, 8.0);
  const double s2 = s.camera.Unproject(uv, 2.0).norm() / p2.norm();
  const double s8 = s.camera.Unproject(uv, 8.0).norm() / p8.norm();
  EXPECT_NEAR(p.scale_min, std::min(s2, s8), 1e-5);
  EXPECT_NEAR(p.scale_max, std::max(s2, s8), 1e-5);

  // Cut to the configured segment [0.1 m, inf) when the translation is known (its sign is not
  // open): a range reaching beyond infinity ends there.
  const KeypointPrediction whole = predictor.Predict(uv, std::nan(""));
  const KeypointPrediction far = predictor.PredictInInverseDepthRange(uv, -1.0, 1.0 / 8.0);
  EXPECT_NEAR(far.segment_end.x(), whole.segment_end.x(), 1e-4);
  EXPECT_NEAR(far.segment_end.y(), whole.segment_end.y(), 1e-4);
  EXPECT_NEAR(far.segment_start.x(), at(8.0).x(), 1e-3);
  // With the translation's sign open, a range reaching below zero is kept there, beyond the
  // rotation-only point, down to the configured segment mirrored (-1 / 0.1 m).
  CameraMotion open = ExactMotion();
  open.covariance.bottomRightCorner<3, 3>() = 0.01 * Eigen::Matrix3d::Identity();
  const KeypointPredictor open_predictor(s.camera, open, po);
  const auto at_rho = [&](double rho) {
    return *s.camera.Project(kNeighbourMotion.rotation * s.camera.Unproject(uv, 1.0) +
                             rho * kNeighbourMotion.translation);
  };
  for (const auto& [lo, hi] : {std::pair{-0.5, -0.125}, std::pair{-0.25, 0.5}}) {
    const KeypointPrediction q = open_predictor.PredictInInverseDepthRange(uv, lo, hi);
    ASSERT_EQ(q.status, PredictionStatus::kWithoutDepth);
    EXPECT_NEAR(q.segment_start.x(), at_rho(hi).x(), 1e-3) << lo;
    EXPECT_NEAR(q.segment_start.y(), at_rho(hi).y(), 1e-3) << lo;
    EXPECT_NEAR(q.segment_end.x(), at_rho(lo).x(), 1e-3) << lo;
    EXPECT_NEAR(q.segment_end.y(), at_rho(lo).y(), 1e-3) << lo;
  }
  PredictionOptions near2 = po;  // configured segment [2 m, inf): the floor is -0.5
  near2.segment_min_depth = 2.0;
  const KeypointPrediction deep =
      KeypointPredictor(s.camera, open, near2).PredictInInverseDepthRange(uv, -5.0, -0.25);
  ASSERT_EQ(deep.status, PredictionStatus::kWithoutDepth);
  ASSERT_TRUE(s.camera.IsInside(at_rho(-0.5)));
  EXPECT_NEAR(deep.segment_start.x(), at_rho(-0.25).x(), 1e-3);
  EXPECT_NEAR(deep.segment_end.x(), at_rho(-0.5).x(), 1e-3);
  EXPECT_NEAR(deep.segment_end.y(), at_rho(-0.5).y(), 1e-3);
  // A range that does not meet the configured segment, or NaN: the configured segment.
  for (const auto& [lo, hi] : {std::pair{20.0, 30.0}, std::pair{std::nan(""), 1.0}}) {
    const KeypointPrediction q = predictor.PredictInInverseDepthRange(uv, lo, hi);
    EXPECT_EQ(q.status, whole.status);
    EXPECT_EQ(q.segment_start, whole.segment_start);
    EXPECT_EQ(q.segment_end, whole.segment_end);
    EXPECT_EQ(q.radius, whole.radius);
  }
}

TEST(NeighbourDepthTest, SegmentsShrinkToTheWallTheirNeighboursLieOnAndKeepEveryPartner) {
  const TwoWallScene s = MakeTwoWallScene(800, 7);
  const KeypointPredictor predictor(s.camera, ExactMotion(), PredictionOptions());
  std::vector<KeypointPrediction> before, predictions;
  PredictKeypoints(predictor, s.kps_a, {}, &before);
  // Every other keypoint matched to its true partner; the rest are what the second pass looks for.
  std::vector<Match> matches;
  for (int i = 0; i < 800; i += 2) {
    matches.emplace_back();
    matches.back().query_idx = matches.back().train_idx = i;
  }
  const std::vector<double> rho = MatchedInverseDepths(predictor, s.kps_a, {}, matches, s.kps_b);
  const int narrowed = PredictKeypointsInRanges(
      predictor, s.kps_a, {}, NeighbourInverseDepthRanges(s.kps_a, rho, NeighbourDepthOptions()),
      &predictions);

  int inside_before = 0, inside_after = 0, edge_inside = 0, edge = 0;
  double length_before = 0.0, length_after = 0.0;
  for (size_t i = 0; i < s.kps_a.size(); ++i) {
    ASSERT_TRUE(before[i].HasWindow());
    inside_before += before[i].Contains(s.kps_b[i].x, s.kps_b[i].y);
    inside_after += predictions[i].Contains(s.kps_b[i].x, s.kps_b[i].y);
    length_before += SegmentLength(before[i]);
    length_after += SegmentLength(predictions[i]);
    // Keypoints within a cell of the walls' border have neighbours on both walls.
    if (std::fabs(s.kps_a[i].x - 320.0f) < 24.0f) {
      ++edge;
      edge_inside += predictions[i].Contains(s.kps_b[i].x, s.kps_b[i].y);
    }
  }
  // 400 matched points over 640 x 480: 6.8 in a 72 px square on average; a few keypoints have
  // fewer than 3 (Poisson: about 4 %) and keep their segments.
  EXPECT_GT(narrowed, 740);
  int kept = 0;
  for (size_t i = 0; i < s.kps_a.size(); ++i) {
    kept += predictions[i].segment_start == before[i].segment_start &&
            predictions[i].segment_end == before[i].segment_end;
  }
  EXPECT_EQ(kept, 800 - narrowed);
  EXPECT_EQ(inside_before, 800);
  EXPECT_EQ(inside_after, 800);
  EXPECT_GT(edge, 50);
  EXPECT_EQ(edge_inside, edge);
  // The near wall's segments span about half its 1.5-2 m range widened to 0.75-4 m, the far
  // one's 3-18 m; from 0.1 m to infinity they crossed most of the image.
  EXPECT_LT(length_after, 0.25 * length_before);
}

TEST(NeighbourDepthTest, AKeypointWithTooFewNeighboursKeepsItsSegment) {
  TwoWallScene s = MakeTwoWallScene(3, 9);
  // Three keypoints far apart (cells not adjacent): each has only itself as a neighbour.
  s.kps_a[0].x = 50.0f;
  s.kps_a[0].y = 50.0f;
  s.kps_a[1].x = 300.0f;
  s.kps_a[1].y = 240.0f;
  s.kps_a[2].x = 590.0f;
  s.kps_a[2].y = 430.0f;
  const KeypointPredictor predictor(s.camera, ExactMotion(), PredictionOptions());
  std::vector<KeypointPrediction> before, predictions;
  PredictKeypoints(predictor, s.kps_a, {}, &before);
  const std::vector<double> rho = {0.5, 0.25, 0.0};
  NeighbourDepthOptions options;
  std::vector<InverseDepthRange> ranges = NeighbourInverseDepthRanges(s.kps_a, rho, options);
  for (const InverseDepthRange& r : ranges) EXPECT_FALSE(r.valid());
  EXPECT_EQ(PredictKeypointsInRanges(predictor, s.kps_a, {}, ranges, &predictions), 0);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(predictions[i].segment_start, before[i].segment_start);
    EXPECT_EQ(predictions[i].segment_end, before[i].segment_end);
  }
  // With one neighbour enough, each is cut to its own inverse depth widened 2x each side: 2 m
  // -> 1-4 m, 4 m -> 2-8 m, and infinity stays a point there.
  options.min_neighbours = 1;
  ranges = NeighbourInverseDepthRanges(s.kps_a, rho, options);
  EXPECT_DOUBLE_EQ(ranges[0].rho_far, 0.25);
  EXPECT_DOUBLE_EQ(ranges[0].rho_near, 1.0);
  EXPECT_DOUBLE_EQ(ranges[1].rho_far, 0.125);
  EXPECT_DOUBLE_EQ(ranges[1].rho_near, 0.5);
  EXPECT_DOUBLE_EQ(ranges[2].rho_far, 0.0);
  EXPECT_DOUBLE_EQ(ranges[2].rho_near, 0.0);
  EXPECT_EQ(PredictKeypointsInRanges(predictor, s.kps_a, {}, ranges, &predictions), 3);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_LT(SegmentLength(predictions[i]), SegmentLength(before[i]));
  }
  // Negative inverse depths (partners beyond the rotation-only point) widen away from zero too:
  // [-0.5, -0.25] -> [-1.0, -0.125], [-0.25, 0.5] -> [-0.5, 1.0].
  {
    options.min_neighbours = 2;
    std::vector<KeypointInfo> pair = {s.kps_a[0], s.kps_a[0]};
    pair[1].x += 1.0f;
    std::vector<InverseDepthRange> r =
        NeighbourInverseDepthRanges(pair, std::vector<double>{-0.5, -0.25}, options);
    EXPECT_DOUBLE_EQ(r[0].rho_far, -1.0);
    EXPECT_DOUBLE_EQ(r[0].rho_near, -0.125);
    r = NeighbourInverseDepthRanges(pair, std::vector<double>{-0.25, 0.5}, options);
    EXPECT_DOUBLE_EQ(r[1].rho_far, -0.5);
    EXPECT_DOUBLE_EQ(r[1].rho_near, 1.0);
    options.min_neighbours = 1;
  }
  // A keypoint with a usable depth is predicted from it, whatever its range.
  const std::vector<float> depths = {2.0f, std::nanf(""), 0.0f};
  EXPECT_EQ(PredictKeypointsInRanges(predictor, s.kps_a, depths, ranges, &predictions), 2);
  EXPECT_EQ(predictions[0].status, PredictionStatus::kWithDepth);
  // Disabled: no ranges.
  options.enabled = false;
  ranges = NeighbourInverseDepthRanges(s.kps_a, rho, options);
  EXPECT_EQ(PredictKeypointsInRanges(predictor, s.kps_a, {}, ranges, &predictions), 0);
}

TEST(NeighbourDepthTest, RejectsBadOptionsAndSizes) {
  NeighbourDepthOptions o;
  EXPECT_NO_THROW(o.Check());
  o.cell_px = 0.0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = NeighbourDepthOptions();
  o.min_neighbours = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = NeighbourDepthOptions();
  o.range_factor = 0.5;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o.range_factor = std::nan("");
  EXPECT_THROW(o.Check(), InvalidArgument);

  const TwoWallScene s = MakeTwoWallScene(4, 11);
  EXPECT_THROW(NeighbourInverseDepthRanges(s.kps_a, {0.1, 0.1}, NeighbourDepthOptions()),
               InvalidArgument);
  EXPECT_THROW(NeighbourInverseDepthRanges(s.kps_a, {0.1, 0.1, 0.1, 0.1}, o), InvalidArgument);
  const KeypointPredictor predictor(s.camera, ExactMotion(), PredictionOptions());
  std::vector<KeypointPrediction> predictions;
  EXPECT_THROW(PredictKeypointsInRanges(predictor, s.kps_a, {}, std::vector<InverseDepthRange>(3),
                                        &predictions),
               InvalidArgument);
  EXPECT_THROW(PredictKeypointsInRanges(predictor, s.kps_a, {1.0f}, {}, &predictions),
               InvalidArgument);
  // No ranges at all: PredictKeypoints.
  std::vector<KeypointPrediction> plain;
  PredictKeypoints(predictor, s.kps_a, {}, &plain);
  EXPECT_EQ(PredictKeypointsInRanges(predictor, s.kps_a, {}, {}, &predictions), 0);
  ASSERT_EQ(predictions.size(), plain.size());
  for (size_t i = 0; i < plain.size(); ++i)
    EXPECT_EQ(predictions[i].segment_end, plain[i].segment_end);
}

}  // namespace
}  // namespace imumatch
