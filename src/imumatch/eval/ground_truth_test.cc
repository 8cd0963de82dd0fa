#include "imumatch/eval/ground_truth.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

PinholeCamera TestCamera() {
  PinholeCamera c;
  c.width = 640;
  c.height = 480;
  c.fx = c.fy = 500.0;
  c.cx = 320.0;
  c.cy = 240.0;
  return c;
}

std::vector<cv::KeyPoint> Kps(std::initializer_list<cv::Point2f> pts) {
  std::vector<cv::KeyPoint> out;
  for (const auto& p : pts) out.emplace_back(p, 7.0f);
  return out;
}

TEST(GroundTruthTest, DepthReprojectionResidualIsHandComputed) {
  // p_a = (0, 0, 2) at the principal point; t = (0.1, 0, 0) moves it to u = 320 + 500 * 0.05.
  const Rigid3d b_from_a(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0.0, 0.0));
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
  const PairGroundTruth gt(TestCamera(), b_from_a, depth, Kps({{320, 240}}),
                           Kps({{346, 240}, {345, 242}, {360, 240}}));
  ASSERT_TRUE(gt.ProjectedInB(0).has_value());
  EXPECT_NEAR(gt.ProjectedInB(0)->x(), 345.0, 1e-9);
  EXPECT_NEAR(gt.ProjectedInB(0)->y(), 240.0, 1e-9);
  const MatchResidual r0 = gt.Judge(0, 0);
  EXPECT_EQ(r0.kind, ResidualKind::kDepth);
  EXPECT_NEAR(r0.residual_px, 1.0, 1e-5);
  EXPECT_NEAR(gt.Judge(0, 1).residual_px, 2.0, 1e-5);
  EXPECT_NEAR(gt.Judge(0, 2).residual_px, 15.0, 1e-5);
  EXPECT_EQ(gt.num_with_depth(), 1);
  // Candidates within 10 px: b0 (1 px) and b1 (2 px), sorted by distance; b2 is 15 px away.
  ASSERT_EQ(gt.candidates().size(), 2u);
  EXPECT_EQ(gt.candidates()[0].b, 0);
  EXPECT_EQ(gt.candidates()[1].b, 1);
  EXPECT_THROW(gt.Judge(1, 0), InvalidArgument);
}

TEST(GroundTruthTest, RawDepthUsesDepthScale) {
  const Rigid3d b_from_a(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0.0, 0.0));
  cv::Mat depth(480, 640, CV_16U, cv::Scalar(10000));  // 10000 / 5000 = 2 m
  const PairGroundTruth gt(TestCamera(), b_from_a, depth, Kps({{320, 240}}), Kps({{345, 240}}));
  EXPECT_NEAR(gt.Judge(0, 0).residual_px, 0.0, 1e-5);
}

TEST(GroundTruthTest, WithoutDepthUsesEpipolarLineDistance) {
  // Sideways translation, no rotation: epipolar lines are the image rows v = v_a.
  const Rigid3d b_from_a(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0.0, 0.0));
  const PairGroundTruth gt(TestCamera(), b_from_a, cv::Mat(), Kps({{100, 200}}),
                           Kps({{400, 203}, {50, 200}}));
  const MatchResidual r = gt.Judge(0, 0);
  EXPECT_EQ(r.kind, ResidualKind::kEpipolar);
  EXPECT_NEAR(r.residual_px, 3.0, 1e-4);
  EXPECT_NEAR(gt.Judge(0, 1).residual_px, 0.0, 1e-4);  // on the line: epipolar judging accepts it
  EXPECT_EQ(gt.num_with_depth(), 0);
  EXPECT_TRUE(gt.candidates().empty());
}

TEST(GroundTruthTest, PureRotationUsesInfiniteHomography) {
  // Rotation about the camera y axis by atan(0.1): the principal point moves to u = 320 + 50.
  const double angle = std::atan(0.1);
  const Rigid3d b_from_a(Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY())),
                         Eigen::Vector3d::Zero());
  const PairGroundTruth gt(TestCamera(), b_from_a, cv::Mat(), Kps({{320, 240}}), Kps({{370, 244}}));
  const MatchResidual r = gt.Judge(0, 0);
  EXPECT_EQ(r.kind, ResidualKind::kEpipolar);
  EXPECT_NEAR(r.residual_px, 4.0, 1e-4);
}

TEST(GroundTruthTest, PointBehindCameraBIsUnjudgeable) {
  const Rigid3d b_from_a(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.0, -3.0));
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(1.0f));
  const PairGroundTruth gt(TestCamera(), b_from_a, depth, Kps({{320, 240}}), Kps({{320, 240}}));
  EXPECT_EQ(gt.Judge(0, 0).kind, ResidualKind::kUnjudgeable);
  EXPECT_EQ(CountCorrect({gt.Judge(0, 0)}, 100.0).correct, 0);
}

TEST(GroundTruthTest, FundamentalMatrixHoldsForTrueCorrespondences) {
  const PinholeCamera cam = TestCamera();
  const Rigid3d b_from_a(Eigen::Quaterniond(ExpSO3(Eigen::Vector3d(0.02, -0.05, 0.01))),
                         Eigen::Vector3d(0.3, -0.1, 0.2));
  const Eigen::Matrix3d f = FundamentalMatrix(cam, b_from_a);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(50, 590), v(50, 430), z(1.0, 5.0);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d xa(u(rng), v(rng));
    const auto xb = cam.Project(b_from_a * cam.Unproject(xa, z(rng)));
    ASSERT_TRUE(xb.has_value());
    EXPECT_LT(EpipolarDistance(f, xa, *xb), 1e-8);
    EXPECT_GT(EpipolarDistance(f, xa, *xb + Eigen::Vector2d(0, 5)), 0.1);
  }
}

TEST(GroundTruthTest, PossibleCorrespondencesAreOneToOne) {
  const std::vector<GtCandidate> c = {{0, 0, 0.5f}, {1, 0, 0.7f}, {1, 1, 1.2f}, {2, 2, 3.0f}};
  EXPECT_EQ(CountPossibleCorrespondences(c, 0.6), 1);
  EXPECT_EQ(CountPossibleCorrespondences(c, 1.5), 2);  // a1 cannot reuse b0, takes b1
  EXPECT_EQ(CountPossibleCorrespondences(c, 5.0), 3);
  EXPECT_EQ(CountPossibleCorrespondences({}, 5.0), 0);
}

TEST(GroundTruthTest, CountCorrectAtThreshold) {
  const std::vector<MatchResidual> r = {{ResidualKind::kDepth, 0.5f},
                                        {ResidualKind::kDepth, 2.0f},
                                        {ResidualKind::kEpipolar, 1.0f},
                                        {ResidualKind::kUnjudgeable, INFINITY}};
  const JudgedCounts c = CountCorrect(r, 1.5);
  EXPECT_EQ(c.matches, 4);
  EXPECT_EQ(c.correct, 2);
  EXPECT_EQ(c.wrong, 2);
  EXPECT_EQ(c.judged_by_depth, 2);
  EXPECT_EQ(c.correct_by_depth, 1);
  EXPECT_EQ(CountCorrect(r, 3.0).correct, 3);
}

TEST(GroundTruthTest, AutoThresholdIsMedianPlusThreeMadSigma) {
  AutoThresholdOptions o;
  o.min_samples = 5;
  // 50 px is beyond the 20 px gate. Kept {1..5}: median 3, MAD 1 -> 3 + 3 * 1.4826 = 7.4478.
  const AutoThreshold t = ComputeAutoThreshold({5, 1, 4, 50, 2, 3}, o);
  EXPECT_EQ(t.samples, 5);
  EXPECT_NEAR(t.median_px, 3.0, 1e-12);
  EXPECT_NEAR(t.mad_sigma_px, 1.4826, 1e-12);
  EXPECT_NEAR(t.threshold_px, 7.4478, 1e-9);
  EXPECT_FALSE(t.clamped);
  EXPECT_FALSE(t.fallback);
  // Tight residuals clamp to 2 px; too few fall back.
  const AutoThreshold tight = ComputeAutoThreshold({0.5f, 0.5f, 0.5f, 0.5f, 0.5f}, o);
  EXPECT_DOUBLE_EQ(tight.threshold_px, 2.0);
  EXPECT_TRUE(tight.clamped);
  const AutoThreshold few = ComputeAutoThreshold({1.0f, 2.0f}, o);
  EXPECT_TRUE(few.fallback);
  EXPECT_DOUBLE_EQ(few.threshold_px, o.fallback_px);
  EXPECT_NE(t.Describe().find("7.45"), std::string::npos);
}

}  // namespace
}  // namespace imumatch
