#include "imumatch/matching/guided_candidates.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/matching_test_util.h"
#include "imumatch/matching/predictor.h"
#include "imumatch/matching/scene_depth.h"

namespace imumatch {
namespace {

TEST(GuidedCandidatesTest, HoldsBInTheGridsSlotOrder) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // Angles as a detector may give them and as the window tests must read them.
  const float angles[] = {10.0f, 359.5f, 400.0f, 720.0f, -30.0f, nan, -1.0f};
  const float angles_read[] = {10.0f, 359.5f, 40.0f, 0.0f, -1.0f, -1.0f, -1.0f};
  const float sizes[] = {5.0f, 0.0f, -2.0f, nan, 31.0f};
  const float sizes_read[] = {5.0f, 0.0f, 0.0f, 0.0f, 31.0f};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> ux(0.0f, 639.0f), uy(0.0f, 479.0f), ud(0.0f, 1.0f);
  const int m = 300;
  std::vector<KeypointInfo> kps(m);
  cv::Mat desc(m, 128, CV_32F);
  for (int j = 0; j < m; ++j) {
    kps[j] = KeypointInfo{ux(rng), uy(rng), angles[j % 7], sizes[j % 5], 0};
    for (int d = 0; d < 128; ++d) desc.at<float>(j, d) = ud(rng);
  }
  GridIndex grid;
  grid.Build(kps, 640, 480, 8.0f);
  GuidedCandidates c;
  PrepareGuidedCandidates(kps, grid, DescriptorView::FromMat(desc), &c);
  ASSERT_EQ(c.count(), m);
  EXPECT_EQ(c.bytes, 512);
  EXPECT_EQ(c.norm, DescriptorNorm::kL2);
  EXPECT_EQ(c.grid, &grid);
  EXPECT_EQ(c.reference_size, ReferenceKeypointSize(kps));
  const DescriptorView view = c.descriptor_view();
  EXPECT_EQ(view.rows, m);
  std::vector<int> seen(m, 0);
  int last_cell = -1;
  for (int k = 0; k < m; ++k) {
    const int j = grid.slot_index(k);
    ASSERT_GE(j, 0);
    ASSERT_LT(j, m);
    ++seen[j];
    EXPECT_EQ(c.x[k], kps[j].x);
    EXPECT_EQ(c.y[k], kps[j].y);
    EXPECT_EQ(c.angle_deg[k], angles_read[j % 7]) << "angle " << kps[j].angle_deg;
    EXPECT_EQ(c.size[k], sizes_read[j % 5]) << "size " << kps[j].size;
    EXPECT_EQ(std::memcmp(view.Row(k), desc.ptr(j), 512), 0) << "slot " << k;
    // Slots run through the grid's cells in order: a window's candidates are contiguous.
    const int cell = grid.CellOf(c.x[k], c.y[k]);
    EXPECT_GE(cell, last_cell);
    last_cell = cell;
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), m);

  // Preparing again into the same object (another frame B, binary descriptors) reuses it.
  std::vector<KeypointInfo> fewer(kps.begin(), kps.begin() + 40);
  cv::Mat orb(40, 32, CV_8U, cv::Scalar(0x5a));
  GridIndex grid2;
  grid2.Build(fewer, 640, 480, 8.0f);
  PrepareGuidedCandidates(fewer, grid2, DescriptorView::FromMat(orb), &c);
  EXPECT_EQ(c.count(), 40);
  EXPECT_EQ(c.descriptors.size(), 40u * 32u);
  EXPECT_EQ(c.norm, DescriptorNorm::kHamming);
  EXPECT_EQ(c.grid, &grid2);
}

// n points 0.8-4 m away seen by a camera that turns and moves; B holds every point's partner
// (descriptor with 2 bits flipped) plus as many random distractors, shuffled.
testing::SyntheticPair MakePreparedScene(int n, uint32_t seed) {
  const Rigid3d motion(FromEulerZYX(0.02, -0.01, 0.03), Eigen::Vector3d(0.06, -0.02, 0.04));
  CameraMotion given;
  given.cam_b_from_cam_a = motion;
  return testing::MakePair(n, n, motion, given, seed, 2);
}

void ExpectSameSearch(const MatchResult& a, const MatchResult& b) {
  ASSERT_EQ(a.matches.size(), b.matches.size());
  for (size_t k = 0; k < a.matches.size(); ++k) {
    EXPECT_EQ(a.matches[k].query_idx, b.matches[k].query_idx);
    EXPECT_EQ(a.matches[k].train_idx, b.matches[k].train_idx);
    EXPECT_EQ(a.matches[k].distance, b.matches[k].distance);
  }
  EXPECT_EQ(a.outcomes, b.outcomes);
  EXPECT_EQ(a.stats.distances_computed, b.stats.distances_computed);
}

TEST(GuidedCandidatesTest, OnePreparationServesThePilotAndEverySearch) {
  const testing::SyntheticPair s = MakePreparedScene(400, 11);
  const GuidedMatcherOptions mo;
  GridIndex grid;
  grid.Build(s.kps_b, s.camera.width, s.camera.height, static_cast<float>(mo.grid_cell_size));
  GuidedCandidates prepared;
  PrepareGuidedCandidates(s.kps_b, grid, DescriptorView::FromMat(s.desc_b), &prepared);
  const DescriptorView da = DescriptorView::FromMat(s.desc_a);
  const DescriptorView db = DescriptorView::FromMat(s.desc_b);
  GuidedSearchScratch scratch;

  // With depth: every point's partner, as from B's keypoints directly.
  const std::vector<KeypointPrediction> with_depth =
      PredictKeypoints(s.camera, s.motion, s.kps_a, s.depth_a, PredictionOptions());
  const MatchResult r1 = MatchGuided(with_depth, s.kps_a, da, prepared, mo, &scratch);
  int correct = 0;
  for (const Match& m : r1.matches) correct += m.train_idx == s.partner[m.query_idx];
  EXPECT_EQ(correct, 400);
  EXPECT_EQ(r1.matches.size(), 400u);
  ExpectSameSearch(r1, MatchGuided(with_depth, s.kps_a, da, s.kps_b, grid, db, mo));

  // Without depth (the scene's pilot runs: 400 keypoints lack depth), the same prepared B.
  const KeypointPredictor predictor(s.camera, s.motion, PredictionOptions());
  std::vector<KeypointPrediction> from_prepared, from_keypoints;
  const SceneNearDepth near_prepared = PredictKeypointsInScene(
      predictor, s.kps_a, {}, da, s.kps_b, prepared, mo, &from_prepared, &scratch);
  GuidedSearchScratch other;
  const SceneNearDepth near_keypoints = PredictKeypointsInScene(
      predictor, s.kps_a, {}, da, s.kps_b, grid, db, mo, &from_keypoints, &other);
  EXPECT_EQ(near_prepared.pilot_queries, 100);
  EXPECT_GE(near_prepared.pilot_matches, 90);
  EXPECT_EQ(near_prepared.pilot_matches, near_keypoints.pilot_matches);
  EXPECT_EQ(near_prepared.segment_min_depth_m, near_keypoints.segment_min_depth_m);
  // The points lie 0.8-4 m away: the segments start beyond the configured 0.1 m, short of 1 m.
  EXPECT_TRUE(near_prepared.moved);
  EXPECT_GT(near_prepared.segment_min_depth_m, 0.2);
  EXPECT_LT(near_prepared.segment_min_depth_m, 1.0);
  ASSERT_EQ(from_prepared.size(), from_keypoints.size());
  for (size_t i = 0; i < from_prepared.size(); ++i) {
    EXPECT_EQ(from_prepared[i].radius, from_keypoints[i].radius);
    EXPECT_EQ(from_prepared[i].segment_start, from_keypoints[i].segment_start);
  }
  const MatchResult r2 = MatchGuided(from_prepared, s.kps_a, da, prepared, mo, &scratch);
  correct = 0;
  for (const Match& m : r2.matches) correct += m.train_idx == s.partner[m.query_idx];
  EXPECT_GE(correct, 390);
  EXPECT_LE(static_cast<int>(r2.matches.size()) - correct, 2);
  ExpectSameSearch(r2, MatchGuided(from_prepared, s.kps_a, da, s.kps_b, grid, db, mo));
}

TEST(GuidedCandidatesTest, RefusesWhatDoesNotFit) {
  const testing::SyntheticPair s = MakePreparedScene(30, 12);
  GridIndex grid;
  grid.Build(s.kps_b, s.camera.width, s.camera.height, 8.0f);
  GuidedCandidates c;
  const DescriptorView da = DescriptorView::FromMat(s.desc_a);
  const std::vector<KeypointPrediction> p =
      PredictKeypoints(s.camera, s.motion, s.kps_a, s.depth_a, PredictionOptions());
  GuidedSearchScratch scratch;
  // Not prepared.
  EXPECT_THROW(MatchGuided(p, s.kps_a, da, c, GuidedMatcherOptions(), &scratch), InvalidArgument);
  // Descriptors of A's count for B's keypoints.
  EXPECT_THROW(PrepareGuidedCandidates(s.kps_b, grid, da, &c), InvalidArgument);
  // A grid over other keypoints.
  GridIndex grid_a;
  grid_a.Build(s.kps_a, s.camera.width, s.camera.height, 8.0f);
  EXPECT_THROW(PrepareGuidedCandidates(s.kps_b, grid_a, DescriptorView::FromMat(s.desc_b), &c),
               InvalidArgument);
  PrepareGuidedCandidates(s.kps_b, grid, DescriptorView::FromMat(s.desc_b), &c);
  EXPECT_NO_THROW(MatchGuided(p, s.kps_a, da, c, GuidedMatcherOptions(), &scratch));
  // The grid rebuilt over fewer points after preparing.
  std::vector<KeypointInfo> fewer(s.kps_b.begin(), s.kps_b.begin() + 10);
  grid.Build(fewer, s.camera.width, s.camera.height, 8.0f);
  EXPECT_THROW(MatchGuided(p, s.kps_a, da, c, GuidedMatcherOptions(), &scratch), InvalidArgument);
  grid.Build(s.kps_b, s.camera.width, s.camera.height, 8.0f);
  // Float descriptors in A against binary ones in B.
  const cv::Mat sift(30, 128, CV_32F, cv::Scalar(0.5f));
  EXPECT_THROW(
      MatchGuided(p, s.kps_a, DescriptorView::FromMat(sift), c, GuidedMatcherOptions(), &scratch),
      InvalidArgument);
  // The scene's pilot with keypoints of B that are not the prepared ones.
  const KeypointPredictor predictor(s.camera, s.motion, PredictionOptions());
  std::vector<KeypointPrediction> out;
  EXPECT_THROW(PredictKeypointsInScene(predictor, s.kps_a, {}, da, fewer, c, GuidedMatcherOptions(),
                                       &out, &scratch),
               InvalidArgument);
}

}  // namespace
}  // namespace imumatch
