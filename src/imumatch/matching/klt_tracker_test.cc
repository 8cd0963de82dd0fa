#include "imumatch/matching/klt_tracker.h"

#include <cmath>

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

// Keypoints of A on a grid well inside the image (their partners stay inside for the motions
// below).
std::vector<cv::KeyPoint> GridKeypoints() {
  std::vector<cv::KeyPoint> kps;
  for (int y = 70; y <= 170; y += 20) {
    for (int x = 90; x <= 230; x += 20) {
      kps.emplace_back(cv::Point2f(static_cast<float>(x), static_cast<float>(y)), 7.0f);
    }
  }
  return kps;
}

// A prediction with depth: the truth moved by `error`, a square window of half size `half`,
// the predicted affine map = the true one (rotation).
KeypointPrediction WithDepth(const Eigen::Vector2d& truth, const Eigen::Vector2d& error, float half,
                             const Eigen::Matrix2d& affine) {
  KeypointPrediction p;
  p.status = PredictionStatus::kWithDepth;
  p.uv = (truth + error).cast<float>();
  p.segment_start = p.segment_end = p.uv;
  p.min_x = p.uv.x() - half;
  p.max_x = p.uv.x() + half;
  p.min_y = p.uv.y() - half;
  p.max_y = p.uv.y() + half;
  p.local_affine = affine.cast<float>();
  return p;
}

// A prediction without depth: the segment along x from `before` px before the truth to `after`
// px past it (the point at infinity), capsule radius 3 px.
KeypointPrediction AlongX(const Eigen::Vector2f& truth, float before, float after) {
  KeypointPrediction p;
  p.status = PredictionStatus::kWithoutDepth;
  p.segment_start = truth + Eigen::Vector2f(-before, 0.0f);
  p.segment_end = truth + Eigen::Vector2f(after, 0.0f);
  p.uv = p.segment_end;
  p.radius = 3.0f;
  p.min_x = p.segment_start.x() - 3.0f;
  p.max_x = p.segment_end.x() + 3.0f;
  p.min_y = truth.y() - 3.0f;
  p.max_y = truth.y() + 3.0f;
  return p;
}

std::vector<KeypointPrediction> Predictions(const WarpedImage& w,
                                            const std::vector<cv::KeyPoint>& kps,
                                            const Eigen::Vector2d& error, float half) {
  std::vector<KeypointPrediction> out;
  for (const cv::KeyPoint& k : kps) {
    out.push_back(WithDepth(w.Map(Eigen::Vector2d(k.pt.x, k.pt.y)), error, half, w.a));
  }
  return out;
}

// Tracks within tol px of the truth.
int Correct(const TrackResult& r, const WarpedImage& w, const std::vector<cv::KeyPoint>& kps,
            double tol) {
  int n = 0;
  for (const Match& m : r.tracks) {
    EXPECT_EQ(m.train_idx, -1);
    const cv::KeyPoint& k = kps[static_cast<size_t>(m.query_idx)];
    const Eigen::Vector2d truth = w.Map(Eigen::Vector2d(k.pt.x, k.pt.y));
    if ((m.refined_uv_b.cast<double>() - truth).norm() <= tol) ++n;
  }
  return n;
}

PixelUndistorter Undistorter() {
  PinholeCamera c;
  c.width = 320;
  c.height = 240;
  return PixelUndistorter(c);
}

TEST(KltTrackerTest, SeededTracksLandOnTheTruth) {
  const cv::Mat a = SmoothTexture(1);
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(12.3, -7.6));
  const auto kps = GridKeypoints();
  const auto pa = TrackingPyramid::Build(a, 3), pb = TrackingPyramid::Build(w.b, 3);
  // The seed 3 px off, inside a +-6 px window.
  const TrackResult r =
      TrackSeeded(pa, pb, kps, Predictions(w, kps, {2.4, -1.8}, 6.0f), Undistorter(), KltOptions());
  EXPECT_EQ(r.stats.queries, static_cast<int>(kps.size()));
  EXPECT_EQ(r.stats.OutcomeSum(), r.stats.queries);
  EXPECT_EQ(r.stats.tracked, static_cast<int>(r.tracks.size()));
  EXPECT_EQ(r.stats.tracked, static_cast<int>(kps.size()));
  EXPECT_EQ(Correct(r, w, kps, 0.1), static_cast<int>(kps.size()));
  for (const Match& m : r.tracks) EXPECT_LT(m.distance, 0.05f);  // 1 - correlation
}

TEST(KltTrackerTest, InPlaneRotationNeedsThePredictedWarp) {
  const cv::Mat a = SmoothTexture(2);
  // 22.5 deg about the image centre (a roll of 45 deg/s over 0.5 s).
  const WarpedImage w = WarpSimilarity(a, 22.5, 1.0, Eigen::Vector2d(3.0, 2.0));
  const auto kps = GridKeypoints();
  const auto pa = TrackingPyramid::Build(a, 3), pb = TrackingPyramid::Build(w.b, 3);
  const auto preds = Predictions(w, kps, {1.5, -1.0}, 5.0f);
  const TrackResult warped = TrackSeeded(pa, pb, kps, preds, Undistorter(), KltOptions());
  KltOptions axis_aligned;
  axis_aligned.warp_patch = false;
  const TrackResult plain = TrackSeeded(pa, pb, kps, preds, Undistorter(), axis_aligned);
  const TrackResult unseeded = TrackOpenCvLk(a, w.b, kps, KltOptions());
  const int n = static_cast<int>(kps.size());
  EXPECT_GE(Correct(warped, w, kps, 0.1), n * 95 / 100);
  EXPECT_EQ(Correct(warped, w, kps, 0.1), static_cast<int>(warped.tracks.size()));
  // An axis-aligned patch does not look like its rotated self.
  EXPECT_LT(Correct(plain, w, kps, 0.1), n / 2);
  EXPECT_LT(Correct(unseeded, w, kps, 0.1), n / 2);
}

TEST(KltTrackerTest, ExposureGainAndBiasCancel) {
  const cv::Mat a = SmoothTexture(3);
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(-4.2, 5.1), 0.6, 12.0);
  const auto kps = GridKeypoints();
  const auto pa = TrackingPyramid::Build(a, 3), pb = TrackingPyramid::Build(w.b, 3);
  const TrackResult r =
      TrackSeeded(pa, pb, kps, Predictions(w, kps, {1.0, 1.0}, 5.0f), Undistorter(), KltOptions());
  EXPECT_EQ(Correct(r, w, kps, 0.1), static_cast<int>(kps.size()));
}

TEST(KltTrackerTest, WithoutDepthTheEpipolarSegmentSeedsTheTrack) {
  const cv::Mat a = SmoothTexture(4);
  const WarpedImage w =
      WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(25.0, 0.0));  // the truth 25 px along x
  const auto kps = GridKeypoints();
  std::vector<KeypointPrediction> preds;
  for (const cv::KeyPoint& k : kps) {
    // The segment runs along x through the truth, 60 px long, the point at infinity 10 px past
    // the truth and the near end 50 px before it; capsule radius 3 px.
    const Eigen::Vector2f truth = w.Map(Eigen::Vector2d(k.pt.x, k.pt.y)).cast<float>();
    preds.push_back(AlongX(truth, 50.0f, 10.0f));
  }
  const auto pa = TrackingPyramid::Build(a, 3), pb = TrackingPyramid::Build(w.b, 3);
  const TrackResult r = TrackSeeded(pa, pb, kps, preds, Undistorter(), KltOptions());
  const int n = static_cast<int>(kps.size());
  EXPECT_GE(Correct(r, w, kps, 0.1), n * 95 / 100);
  EXPECT_EQ(Correct(r, w, kps, 0.1), static_cast<int>(r.tracks.size()));  // no wrong track
}

TEST(KltTrackerTest, RepeatedTextureAlongTheSegmentIsAmbiguous) {
  // A texture repeating every 24 px along x; B is A shifted by 5 px. Each segment spans the truth
  // and both of its repeats 24 px to either side.
  cv::Mat tile = SmoothTexture(9)(cv::Rect(0, 0, 24, 240)).clone();
  cv::Mat a;
  cv::repeat(tile, 1, 14, a);
  a = a(cv::Rect(0, 0, 320, 240)).clone();
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(5.0, 0.0));
  const auto kps = GridKeypoints();
  std::vector<KeypointPrediction> preds;
  for (const cv::KeyPoint& k : kps) {
    const Eigen::Vector2f truth = w.Map(Eigen::Vector2d(k.pt.x, k.pt.y)).cast<float>();
    preds.push_back(AlongX(truth, 30.0f, 30.0f));
  }
  const auto pa = TrackingPyramid::Build(a, 3), pb = TrackingPyramid::Build(w.b, 3);
  KltOptions options;
  options.max_segment_starts = 3;
  const TrackResult r = TrackSeeded(pa, pb, kps, preds, Undistorter(), options);
  EXPECT_GE(r.stats.ambiguous, static_cast<int>(kps.size()) * 9 / 10);
  // The tracks it keeps are right.
  EXPECT_EQ(Correct(r, w, kps, 0.1), static_cast<int>(r.tracks.size()));
}

TEST(KltTrackerTest, TheWindowGatesTracks) {
  const cv::Mat a = SmoothTexture(5);
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(6.0, 0.0));
  const auto kps = GridKeypoints();
  // Windows of +-2 px centred 3 px off the truth: the truth is outside every one of them.
  const auto preds = Predictions(w, kps, {3.0, 0.0}, 2.0f);
  const auto pa = TrackingPyramid::Build(a, 3), pb = TrackingPyramid::Build(w.b, 3);
  const TrackResult gated = TrackSeeded(pa, pb, kps, preds, Undistorter(), KltOptions());
  EXPECT_TRUE(gated.tracks.empty());
  EXPECT_EQ(gated.stats.outside_window, static_cast<int>(kps.size()));
  KltOptions open;
  open.gate_by_window = false;
  const TrackResult free = TrackSeeded(pa, pb, kps, preds, Undistorter(), open);
  EXPECT_EQ(Correct(free, w, kps, 0.1), static_cast<int>(kps.size()));
}

TEST(KltTrackerTest, LargeMotionNeedsTheSeed) {
  const cv::Mat a = SmoothTexture(6);
  // 70 px: beyond the reach of an unseeded 3-level pyramid with a 21 x 21 window on this
  // texture, trivial from a seed 2 px off.
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(70.0, 0.0));
  std::vector<cv::KeyPoint> kps;
  for (int y = 70; y <= 170; y += 20) {
    for (int x = 30; x <= 150; x += 20) kps.emplace_back(cv::Point2f(x, y), 7.0f);
  }
  const auto pa = TrackingPyramid::Build(a, 3), pb = TrackingPyramid::Build(w.b, 3);
  const TrackResult seeded =
      TrackSeeded(pa, pb, kps, Predictions(w, kps, {2.0, 0.0}, 5.0f), Undistorter(), KltOptions());
  KltOptions vins;
  vins.half_size = 10;
  vins.min_correlation = -1.0;
  const TrackResult unseeded = TrackOpenCvLk(a, w.b, kps, vins);
  EXPECT_EQ(Correct(seeded, w, kps, 0.1), static_cast<int>(kps.size()));
  EXPECT_LT(Correct(unseeded, w, kps, 0.5), static_cast<int>(kps.size()) / 4);
}

TEST(KltTrackerTest, UnseededTrackerFollowsSmallMotion) {
  const cv::Mat a = SmoothTexture(7);
  const WarpedImage w = WarpSimilarity(a, 0.0, 1.0, Eigen::Vector2d(4.5, -3.2));
  const auto kps = GridKeypoints();
  const TrackResult r = TrackOpenCvLk(a, w.b, kps, KltOptions());
  EXPECT_EQ(r.stats.OutcomeSum(), static_cast<int>(kps.size()));
  EXPECT_EQ(Correct(r, w, kps, 0.1), static_cast<int>(kps.size()));
  for (const Match& m : r.tracks) EXPECT_FALSE(m.predicted_uv.allFinite());
}

TEST(KltTrackerTest, NoPredictionAndBadInput) {
  const cv::Mat a = SmoothTexture(8);
  const auto kps = GridKeypoints();
  const auto pa = TrackingPyramid::Build(a, 2);
  std::vector<KeypointPrediction> none(kps.size());  // kInvalid
  const TrackResult r = TrackSeeded(pa, pa, kps, none, Undistorter(), KltOptions());
  EXPECT_EQ(r.stats.no_prediction, static_cast<int>(kps.size()));
  EXPECT_TRUE(r.tracks.empty());
  // Sizes that disagree, empty and colour images, bad options.
  const auto small = TrackingPyramid::Build(a(cv::Rect(0, 0, 160, 120)).clone(), 2);
  EXPECT_THROW(TrackSeeded(pa, small, kps, none, Undistorter(), KltOptions()), InvalidArgument);
  EXPECT_THROW(TrackSeeded(pa, pa, kps, {}, Undistorter(), KltOptions()), InvalidArgument);
  EXPECT_THROW(TrackingPyramid::Build(cv::Mat(), 2), InvalidArgument);
  EXPECT_THROW(TrackingPyramid::Build(cv::Mat(10, 10, CV_8UC3), 2), InvalidArgument);
  EXPECT_THROW(TrackOpenCvLk(a, a(cv::Rect(0, 0, 100, 100)).clone(), kps, KltOptions()),
               InvalidArgument);
  KltOptions bad;
  bad.half_size = 1;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = KltOptions();
  bad.max_forward_backward_px = std::nan("");
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
