#include "imumatch/matching/subpixel_refinement.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/matching/matching_test_util.h"

namespace imumatch {
namespace {

// Textures and similarity warps with their exact point maps (matching_test_util.h).
using testing::SmoothTexture;
using testing::WarpedImage;
using testing::WarpSimilarity;

struct MatchSet {
  std::vector<cv::KeyPoint> kps_a, kps_b;
  std::vector<Match> matches;
  std::vector<Eigen::Vector2d> truth;
};
// Keypoints of A on whole pixels; their partners in B rounded to whole pixels (a detector's
// grid), up to 0.7 px from the truth.
MatchSet MakeMatches(const WarpedImage& w) {
  MatchSet s;
  for (int y = 50; y <= 190; y += 20) {
    for (int x = 50; x <= 270; x += 20) {
      const Eigen::Vector2d truth = w.Map(Eigen::Vector2d(x, y));
      s.kps_a.emplace_back(cv::Point2f(static_cast<float>(x), static_cast<float>(y)), 7.0f);
      s.kps_b.emplace_back(cv::Point2f(static_cast<float>(std::round(truth.x())),
                                       static_cast<float>(std::round(truth.y()))),
                           7.0f);
      Match m;
      m.query_idx = m.train_idx = static_cast<int>(s.truth.size());
      s.matches.push_back(m);
      s.truth.push_back(truth);
    }
  }
  return s;
}

PinholeCamera Camera() {
  PinholeCamera c;
  c.width = 320;
  c.height = 240;
  return c;
}

double MeanError(const MatchSet& s, int* refined) {
  double sum = 0.0;
  *refined = 0;
  for (const Match& m : s.matches) {  // dropped matches leave the list: truth by query index
    if (!m.refined_uv_b.allFinite()) continue;
    ++*refined;
    sum += (m.refined_uv_b.cast<double>() - s.truth[static_cast<size_t>(m.query_idx)]).norm();
  }
  return *refined > 0 ? sum / *refined : 1e9;
}

TEST(SubpixelRefinement, RecoversASubPixelShift) {
  const cv::Mat a = SmoothTexture(7);
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(3.37, -1.62));
  MatchSet s = MakeMatches(w);
  double before = 0.0;
  for (size_t i = 0; i < s.truth.size(); ++i) {
    before += (Eigen::Vector2d(s.kps_b[i].pt.x, s.kps_b[i].pt.y) - s.truth[i]).norm();
  }
  before /= static_cast<double>(s.truth.size());
  const SubpixelStats stats =
      RefineMatches(a, w.b, s.kps_a, s.kps_b, {}, Camera(), SubpixelOptions(), s.matches);
  int refined = 0;
  const double after = MeanError(s, &refined);
  EXPECT_EQ(stats.refined, static_cast<int>(s.matches.size()));
  EXPECT_EQ(refined, stats.refined);
  EXPECT_GT(before, 0.3);  // rounding to whole pixels: mean 0.38 px off
  EXPECT_LT(after, 0.05);
}

TEST(SubpixelRefinement, ThePredictedRotationMakesARolledPatchRefinable) {
  // 25 degrees of roll between the frames: an unwarped 11x11 patch no longer fits, the patch
  // warped by the prediction's local affine map does.
  const cv::Mat a = SmoothTexture(11);
  const WarpedImage w = WarpSimilarity(a, 25.0, 1.0, Eigen::Vector2d(0.4, 0.2));
  MatchSet with = MakeMatches(w), without = MakeMatches(w);
  std::vector<KeypointPrediction> predictions(with.kps_a.size());
  for (KeypointPrediction& p : predictions) {
    p.status = PredictionStatus::kWithDepth;
    p.local_affine = w.a.cast<float>();
  }
  RefineMatches(a, w.b, with.kps_a, with.kps_b, predictions, Camera(), SubpixelOptions(),
                with.matches);
  RefineMatches(a, w.b, without.kps_a, without.kps_b, {}, Camera(), SubpixelOptions(),
                without.matches);
  int refined_with = 0, refined_without = 0;
  const double err_with = MeanError(with, &refined_with);
  const double err_without = MeanError(without, &refined_without);
  EXPECT_GE(refined_with, static_cast<int>(with.matches.size()) * 9 / 10);
  EXPECT_LT(err_with, 0.1);
  // Without the rotation the alignment fails or lands off.
  EXPECT_TRUE(refined_without < refined_with / 2 || err_without > 3.0 * err_with)
      << refined_without << " refined, mean error " << err_without;
}

TEST(SubpixelRefinement, ExposureChangeCancels) {
  const cv::Mat a = SmoothTexture(3);
  WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(-2.25, 0.8));
  w.b.convertTo(w.b, CV_8U, 0.6, 10.0);  // gain 0.6, bias 10
  MatchSet s = MakeMatches(w);
  RefineMatches(a, w.b, s.kps_a, s.kps_b, {}, Camera(), SubpixelOptions(), s.matches);
  int refined = 0;
  EXPECT_LT(MeanError(s, &refined), 0.06);
  EXPECT_EQ(refined, static_cast<int>(s.matches.size()));
}

TEST(SubpixelRefinement, APatchWithoutTextureIsRetriedLarger) {
  // The keypoint sits in a flat disc of radius 6.5 px inside a textured scene (the smooth centre
  // of a blob): the 9 x 9 patch sees no texture at all, the 17 x 17 one reaches the texture
  // around the disc and aligns.
  cv::Mat a = SmoothTexture(5);
  cv::circle(a, cv::Point(160, 120), 6, cv::Scalar(128), cv::FILLED);
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(1.3, -0.6));
  std::vector<cv::KeyPoint> kps_a = {cv::KeyPoint(cv::Point2f(160, 120), 20.0f)};
  std::vector<cv::KeyPoint> kps_b = {cv::KeyPoint(cv::Point2f(161, 119), 20.0f)};
  std::vector<Match> matches(1);
  matches[0].query_idx = matches[0].train_idx = 0;
  const SubpixelStats stats =
      RefineMatches(a, w.b, kps_a, kps_b, {}, Camera(), SubpixelOptions(), matches);
  ASSERT_EQ(stats.refined, 1);
  EXPECT_LT((matches[0].refined_uv_b - Eigen::Vector2f(161.3f, 119.4f)).norm(), 0.05f);
  // Starting at 5 x 5, the retry is the 9 x 9 patch, still inside the disc: unrefined. So the
  // default needed its retry.
  SubpixelOptions small;
  small.half_size = 2;
  std::vector<Match> again(1);
  again[0].query_idx = again[0].train_idx = 0;
  EXPECT_EQ(RefineMatches(a, w.b, kps_a, kps_b, {}, Camera(), small, again).failed_texture, 1);
}

TEST(SubpixelRefinement, ADriftingPatchIsRetriedLargerAndMustCorrelate) {
  // B's keypoints at A's positions, 3.5 px from their true partners (B = A moved by (3, -1.8)):
  // from that far some 9 x 9 patches slide off (4 of the 96 with this texture); the 17 x 17 patch
  // aligns them on the truth.
  const cv::Mat a = SmoothTexture(2);
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(3.0, -1.8));
  MatchSet with = MakeMatches(w);
  for (size_t i = 0; i < with.kps_b.size(); ++i) with.kps_b[i].pt = with.kps_a[i].pt;
  MatchSet without = with;
  SubpixelOptions no_retry;
  no_retry.retry_drifted_larger = false;
  const SubpixelStats s_without =
      RefineMatches(a, w.b, without.kps_a, without.kps_b, {}, Camera(), no_retry, without.matches);
  const SubpixelStats s_with =
      RefineMatches(a, w.b, with.kps_a, with.kps_b, {}, Camera(), SubpixelOptions(), with.matches);
  const int n = static_cast<int>(with.truth.size());
  ASSERT_GE(s_without.failed_convergence, 1);
  EXPECT_EQ(static_cast<int>(without.matches.size()), n - s_without.failed_convergence);
  EXPECT_EQ(s_without.recovered_larger, 0);
  EXPECT_EQ(s_with.recovered_larger, s_without.failed_convergence);
  EXPECT_EQ(s_with.failed_convergence, 0);
  ASSERT_EQ(static_cast<int>(with.matches.size()), n);
  int refined = 0;
  EXPECT_LT(MeanError(with, &refined), 0.06);
  EXPECT_EQ(refined, n);
  for (const Match& m : with.matches) {  // within half a pixel of the truth, from 3.5 px away
    EXPECT_LT((m.refined_uv_b.cast<double>() - with.truth[static_cast<size_t>(m.query_idx)]).norm(),
              0.5)
        << "query " << m.query_idx;
  }

  // False partners, 20 px away from the truth: the larger patch gives them no second chance
  // (the same matches survive as without the retry).
  MatchSet wrong = MakeMatches(w);
  for (cv::KeyPoint& kb : wrong.kps_b) kb.pt += cv::Point2f(20.0f, 0.0f);
  MatchSet wrong_without = wrong;
  const SubpixelStats s_wrong = RefineMatches(a, w.b, wrong.kps_a, wrong.kps_b, {}, Camera(),
                                              SubpixelOptions(), wrong.matches);
  const SubpixelStats s_wrong_without =
      RefineMatches(a, w.b, wrong_without.kps_a, wrong_without.kps_b, {}, Camera(), no_retry,
                    wrong_without.matches);
  EXPECT_GT(s_wrong.failed_convergence, n / 2);
  EXPECT_EQ(s_wrong.recovered_larger, 0);
  EXPECT_EQ(s_wrong.failed_convergence, s_wrong_without.failed_convergence);
  EXPECT_EQ(wrong.matches.size(), wrong_without.matches.size());
  SubpixelOptions bad;
  bad.retry_min_correlation = 1.5;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

TEST(SubpixelRefinement, FlatPatchesAndBordersAreLeftUnrefined) {
  cv::Mat flat(240, 320, CV_8U, cv::Scalar(128));
  std::vector<cv::KeyPoint> kps = {cv::KeyPoint(cv::Point2f(100, 100), 7.0f),
                                   cv::KeyPoint(cv::Point2f(1, 1), 7.0f)};
  std::vector<Match> matches(2);
  matches[0].query_idx = matches[0].train_idx = 0;
  matches[1].query_idx = matches[1].train_idx = 1;
  const SubpixelStats stats =
      RefineMatches(flat, flat, kps, kps, {}, Camera(), SubpixelOptions(), matches);
  EXPECT_EQ(stats.refined, 0);
  EXPECT_EQ(stats.failed_texture, 1);
  EXPECT_EQ(stats.failed_border, 1);
  EXPECT_FALSE(matches[0].refined_uv_b.allFinite());
  cv::Mat color(240, 320, CV_8UC3);
  EXPECT_THROW(RefineMatches(color, flat, kps, kps, {}, Camera(), SubpixelOptions(), matches),
               InvalidArgument);
}

}  // namespace
}  // namespace imumatch
