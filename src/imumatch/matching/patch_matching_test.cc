#include "imumatch/matching/patch_matching.h"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/matching/matching_test_util.h"

namespace imumatch {
namespace {

// Blurred Gaussian noise, 8-bit: texture everywhere, no repetition.
cv::Mat Noise(int seed) { return testing::SmoothTexture(seed, 1.8, 15.0, 240.0); }

// Frame B: A turned by angle_deg about (160, 120) and shifted; Map() is the truth.
struct PatchScene {
  cv::Mat a, b;
  Eigen::Matrix2f rot;
  Eigen::Vector2f t;
  Eigen::Vector2f Map(const Eigen::Vector2f& p) const { return rot * p + t; }
};
PatchScene MakePatchScene(double angle_deg, const Eigen::Vector2f& shift) {
  PatchScene s;
  s.a = Noise(7);
  const testing::WarpedImage w = testing::WarpSimilarity(s.a, angle_deg, 1.0, shift.cast<double>());
  s.b = w.b;
  s.rot = w.a.cast<float>();
  s.t = w.t.cast<float>();
  return s;
}

// Queries on a grid of A; in B each has its partner on the whole pixel nearest the truth (a
// detector's grid) and a decoy 6 px to the right. Descriptors all equal, so that the guided
// matcher's ratio test could not tell partner from decoy: every query starts as rejected by it.
struct Problem {
  std::vector<cv::KeyPoint> kps_a, kps_b;
  std::vector<KeypointInfo> ideal_a, ideal_b;
  std::vector<KeypointPrediction> predictions;
  std::vector<Eigen::Vector2f> truth;
  cv::Mat desc_a, desc_b;
  GridIndex grid;
  MatchResult result;
};
Problem MakeProblem(const PatchScene& s) {
  Problem p;
  for (int y = 40; y <= 200; y += 40) {
    for (int x = 40; x <= 260; x += 44) {
      const Eigen::Vector2f pa(static_cast<float>(x), static_cast<float>(y));
      const Eigen::Vector2f truth = s.Map(pa);
      p.truth.push_back(truth);
      p.kps_a.emplace_back(cv::Point2f(pa.x(), pa.y()), 8.0f, 30.0f);
      const cv::Point2f partner(std::round(truth.x()), std::round(truth.y()));
      p.kps_b.emplace_back(partner, 8.0f, 33.0f);
      p.kps_b.emplace_back(partner + cv::Point2f(6.0f, 0.0f), 8.0f, 33.0f);
      KeypointPrediction pr;
      pr.status = PredictionStatus::kWithDepth;
      pr.uv = truth;
      pr.min_x = truth.x() - 9.0f;
      pr.max_x = truth.x() + 9.0f;
      pr.min_y = truth.y() - 9.0f;
      pr.max_y = truth.y() + 9.0f;
      pr.local_affine = s.rot;
      p.predictions.push_back(pr);
    }
  }
  p.ideal_a = ToKeypointInfos(p.kps_a);
  p.ideal_b = ToKeypointInfos(p.kps_b);
  p.desc_a = cv::Mat::zeros(static_cast<int>(p.kps_a.size()), 32, CV_8U);
  p.desc_b = cv::Mat::zeros(static_cast<int>(p.kps_b.size()), 32, CV_8U);
  p.grid.Build(p.ideal_b, 320, 240, 8.0f);
  const int n = static_cast<int>(p.kps_a.size());
  p.result.outcomes.assign(static_cast<size_t>(n), QueryOutcome::kRatioTest);
  p.result.stats.queries = n;
  p.result.stats.ratio_test = n;
  return p;
}

PinholeCamera SceneCamera() {
  PinholeCamera c;
  c.width = 320;
  c.height = 240;
  return c;
}

PatchMatchingStats MatchAll(Problem& p, const PatchScene& s,
                            const PatchMatchingOptions& options = PatchMatchingOptions()) {
  return MatchByPatch(p.predictions, p.ideal_a, p.kps_a, DescriptorView::FromMat(p.desc_a),
                      p.ideal_b, p.grid, p.kps_b, DescriptorView::FromMat(p.desc_b), s.a, s.b,
                      SceneCamera(), GuidedMatcherOptions(), options, &p.result);
}

TEST(PatchMatchingTest, MatchesEachRejectedQueryToItsTruePartnerNotTheDecoy) {
  const PatchScene s = MakePatchScene(3.0, Eigen::Vector2f(2.4f, -1.3f));
  Problem p = MakeProblem(s);
  const int n = static_cast<int>(p.kps_a.size());
  const PatchMatchingStats st = MatchAll(p, s);
  EXPECT_EQ(st.queries, n);
  EXPECT_EQ(st.aligned, 2 * n);
  EXPECT_EQ(st.ambiguous, 0);
  ASSERT_EQ(st.matched, n);
  ASSERT_EQ(static_cast<int>(p.result.matches.size()), n);
  for (const Match& m : p.result.matches) {
    EXPECT_EQ(m.train_idx, 2 * m.query_idx) << "query " << m.query_idx << " took the decoy";
    // The aligned position is the truth (the partner keypoint sits up to 0.7 px off it).
    EXPECT_LT((m.refined_uv_b - p.truth[static_cast<size_t>(m.query_idx)]).norm(), 0.1f);
    EXPECT_EQ(p.result.outcomes[static_cast<size_t>(m.query_idx)], QueryOutcome::kMatched);
  }
  EXPECT_EQ(p.result.stats.ratio_test, 0);
  EXPECT_EQ(p.result.stats.matched, n);
  EXPECT_EQ(p.result.stats.OutcomeSum(), n);
}

TEST(PatchMatchingTest, TwoPlacesShowingThePatchMatchNeither) {
  PatchScene s = MakePatchScene(0.0, Eigen::Vector2f(1.6f, 0.7f));
  Problem p = MakeProblem(s);
  // Query 0's decoy moved to 9 px (inside a wider window), and B's neighbourhood of its partner
  // copied there: B shows the patch twice, 9 px apart, both copies intact.
  p.kps_b[1].pt = p.kps_b[0].pt + cv::Point2f(9.0f, 0.0f);
  p.ideal_b = ToKeypointInfos(p.kps_b);
  p.grid.Build(p.ideal_b, 320, 240, 8.0f);
  p.predictions[0].max_x += 3.0f;
  const cv::Point2f partner = p.kps_b[0].pt;
  const int x0 = static_cast<int>(partner.x) - 5, y0 = static_cast<int>(partner.y) - 10;
  const cv::Mat strip = s.b(cv::Rect(x0, y0, 10, 21)).clone();
  strip.copyTo(s.b(cv::Rect(x0 + 9, y0, 10, 21)));
  PatchMatchingOptions o;
  o.half_size = 3;  // 7 x 7 samples: inside the copied 10 x 21 strip
  const PatchMatchingStats st = MatchAll(p, s, o);
  EXPECT_GE(st.ambiguous, 1);
  for (const Match& m : p.result.matches) EXPECT_NE(m.query_idx, 0);
  EXPECT_EQ(p.result.outcomes[0], QueryOutcome::kRatioTest);
  EXPECT_GE(st.matched, static_cast<int>(p.kps_a.size()) - 2);
}

TEST(PatchMatchingTest, TheShiftLimitGrowsWithTheKeypointsScale) {
  // Every partner sits 3 px below the truth: for two keypoints of the finest scale (size 8, the
  // frames' smallest) a keypoint that far is another point (limit 2 px); for two found at 8x that
  // scale it is the rounding of their grid (sigma^2 = 1 + (64 - 1) / 12 px^2 each: limit 5 px).
  const PatchScene s = MakePatchScene(2.0, Eigen::Vector2f(1.5f, 0.5f));
  for (const bool grows : {true, false}) {
    Problem p = MakeProblem(s);
    const int n = static_cast<int>(p.kps_a.size());
    for (int i = 0; i < n; ++i) {
      const bool coarse = i % 2 == 1;
      cv::KeyPoint& partner = p.kps_b[static_cast<size_t>(2 * i)];
      partner.pt.y += 3.0f;
      p.kps_b[static_cast<size_t>(2 * i + 1)].pt.y += 3.0f;  // the decoy keeps its 6 px offset
      if (coarse) {
        p.kps_a[static_cast<size_t>(i)].size = 64.0f;
        partner.size = 64.0f;
        p.kps_b[static_cast<size_t>(2 * i + 1)].size = 64.0f;
      }
    }
    p.ideal_a = ToKeypointInfos(p.kps_a);
    p.ideal_b = ToKeypointInfos(p.kps_b);
    p.grid.Build(p.ideal_b, 320, 240, 8.0f);
    PatchMatchingOptions o;
    o.shift_grows_with_scale = grows;
    const PatchMatchingStats st = MatchAll(p, s, o);
    EXPECT_EQ(st.ambiguous, 0);
    int coarse_matched = 0;
    for (const Match& m : p.result.matches) {
      ASSERT_EQ(m.query_idx % 2, 1) << "fine query " << m.query_idx << " took a keypoint 3 px off";
      EXPECT_EQ(m.train_idx, 2 * m.query_idx) << "query " << m.query_idx << " took the decoy";
      EXPECT_LT((m.refined_uv_b - p.truth[static_cast<size_t>(m.query_idx)]).norm(), 0.1f);
      ++coarse_matched;
    }
    EXPECT_EQ(coarse_matched, grows ? n / 2 : 0) << (grows ? "growing" : "fixed") << " limit";
  }
}

TEST(PatchMatchingTest, AnUnrelatedFrameGivesNoMatch) {
  PatchScene s = MakePatchScene(0.0, Eigen::Vector2f(1.0f, 1.0f));
  s.b = Noise(99);
  Problem p = MakeProblem(s);
  const PatchMatchingStats st = MatchAll(p, s);
  EXPECT_EQ(st.matched, 0);
  EXPECT_TRUE(p.result.matches.empty());
  EXPECT_EQ(p.result.stats.ratio_test, static_cast<int>(p.kps_a.size()));
}

TEST(PatchMatchingTest, FirstLookMatchesKeepTheirQueriesAndKeypoints) {
  const PatchScene s = MakePatchScene(2.0, Eigen::Vector2f(-1.2f, 2.2f));
  Problem p = MakeProblem(s);
  // The first look matched query 0 to keypoint 2 (query 1's partner: a first look may err).
  // That match stands, and query 1 may not take keypoint 2 again.
  Match first;
  first.query_idx = 0;
  first.train_idx = 2;
  p.result.matches.push_back(first);
  p.result.outcomes[0] = QueryOutcome::kMatched;
  p.result.stats.ratio_test -= 1;
  p.result.stats.matched = 1;
  MatchAll(p, s);
  int from_query0 = 0;
  for (const Match& m : p.result.matches) {
    if (m.query_idx == 0) {
      ++from_query0;
      EXPECT_EQ(m.train_idx, 2);
    }
    EXPECT_NE(m.query_idx, 1) << "query 1's partner was taken";
  }
  EXPECT_EQ(from_query0, 1);
  EXPECT_EQ(p.result.stats.OutcomeSum(), static_cast<int>(p.kps_a.size()));
}

TEST(PatchMatchingTest, TheDescriptorThresholdGuardsWhenAskedTo) {
  const PatchScene s = MakePatchScene(1.0, Eigen::Vector2f(0.5f, 0.5f));
  Problem p = MakeProblem(s);
  p.desc_b.setTo(255);  // every candidate 256 bits away: beyond the Hamming threshold
  EXPECT_EQ(MatchAll(p, s).matched, static_cast<int>(p.kps_a.size()));  // the patch decides
  Problem q = MakeProblem(s);
  q.desc_b.setTo(255);
  PatchMatchingOptions o;
  o.require_distance_threshold = true;
  EXPECT_EQ(MatchAll(q, s, o).matched, 0);
}

// The library's per-frame loop: GuidedMatcherWorkspace::Match, then the second look taking the
// workspace. A camera rolls 20 deg about its optical axis (principal point at the image centre,
// no lens distortion): frame B is frame A turned about the principal point, so PatchScene::Map is
// the exact motion of every pixel. B also carries sensor noise, which moves ORB's descriptors more
// than the patches' correlation. Every match the look adds is judged against Map.
TEST(PatchMatchingTest, AfterTheWorkspacesMatchItAddsTrueMatches) {
  PatchScene s = MakePatchScene(20.0, Eigen::Vector2f::Zero());
  cv::Mat noise(s.b.size(), CV_16S);
  cv::RNG rng(11);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 6.0);
  cv::Mat b16;
  s.b.convertTo(b16, CV_16S);
  cv::Mat(b16 + noise).convertTo(s.b, CV_8U);  // saturating
  PinholeCamera camera = SceneCamera();
  camera.fx = camera.fy = 300.0;
  camera.cx = 160.0;  // the turn's centre
  camera.cy = 120.0;
  const double th = 20.0 * M_PI / 180.0;
  CameraMotion motion;
  motion.t_b_ns = 50'000'000;
  motion.cam_b_from_cam_a = Rigid3d(
      Eigen::Matrix3d(Eigen::AngleAxisd(th, Eigen::Vector3d::UnitZ())), Eigen::Vector3d::Zero());
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(500);
  std::vector<cv::KeyPoint> kps_a, kps_b;
  cv::Mat desc_a, desc_b;
  orb->detectAndCompute(s.a, cv::noArray(), kps_a, desc_a);
  orb->detectAndCompute(s.b, cv::noArray(), kps_b, desc_b);
  ASSERT_GT(kps_a.size(), 300u);
  GuidedMatcherWorkspace workspace;
  const GuidedMatcherOptions guided;
  MatchResult r = workspace.Match(camera, motion, kps_a, desc_a, cv::Mat(), kps_b, desc_b,
                                  PredictionOptions(), guided);
  const auto close_to_truth = [&](const Match& m, const Eigen::Vector2f& uv_b) {
    const cv::Point2f& pa = kps_a[static_cast<size_t>(m.query_idx)].pt;
    return (uv_b - s.Map(Eigen::Vector2f(pa.x, pa.y))).norm() < 1.5f;
  };
  int first_correct = 0;
  for (const Match& m : r.matches) {
    const cv::Point2f& pb = kps_b[static_cast<size_t>(m.train_idx)].pt;
    first_correct += close_to_truth(m, Eigen::Vector2f(pb.x, pb.y));
  }
  // The prediction holds: most of A's keypoints find their partner by the descriptors.
  EXPECT_GT(first_correct, static_cast<int>(kps_a.size()) / 3);
  const std::vector<QueryOutcome> before = r.outcomes;
  const PatchMatchingStats st = MatchByPatch(workspace, kps_a, desc_a, kps_b, desc_b, s.a, s.b,
                                             camera, guided, PatchMatchingOptions(), &r);
  EXPECT_GT(st.matched, 5);
  int added = 0, added_correct = 0;
  for (const Match& m : r.matches) {
    if (before[static_cast<size_t>(m.query_idx)] == QueryOutcome::kMatched) continue;
    ++added;
    added_correct += close_to_truth(m, m.refined_uv_b);
  }
  EXPECT_EQ(added, st.matched);
  EXPECT_GE(added_correct, added - 1) << added_correct << " of " << added;
  // Keypoints that are not the ones of the workspace's last call are refused.
  std::vector<cv::KeyPoint> fewer(kps_a.begin(), kps_a.end() - 1);
  EXPECT_THROW(MatchByPatch(workspace, fewer, desc_a.rowRange(0, desc_a.rows - 1), kps_b, desc_b,
                            s.a, s.b, camera, guided, PatchMatchingOptions(), &r),
               InvalidArgument);
}

TEST(PatchMatchingTest, RejectsBadInput) {
  const PatchScene s = MakePatchScene(0.0, Eigen::Vector2f(1.0f, 1.0f));
  Problem p = MakeProblem(s);
  p.predictions.pop_back();
  EXPECT_THROW(MatchAll(p, s), InvalidArgument);
  Problem q = MakeProblem(s);
  EXPECT_THROW(
      MatchByPatch(q.predictions, q.ideal_a, q.kps_a, DescriptorView::FromMat(q.desc_a), q.ideal_b,
                   q.grid, q.kps_b, DescriptorView::FromMat(q.desc_b), s.a, cv::Mat(),
                   SceneCamera(), GuidedMatcherOptions(), PatchMatchingOptions(), &q.result),
      InvalidArgument);
  PatchMatchingOptions o;
  o.min_correlation = 1.5;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = PatchMatchingOptions();
  o.max_shift_px = std::nan("");
  EXPECT_THROW(o.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
