#include "imumatch/matching/depth_edges.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// 100 x 60 raw depth (1000 units per metre): a wall at 2 m, a step to a far wall at 10 m from
// column 50 on, and a hole (no reading) over rows 0-9 of columns 0-29.
cv::Mat StepImage() {
  cv::Mat d(60, 100, CV_16UC1, cv::Scalar(2000));
  d.colRange(50, 100).setTo(10000);
  d(cv::Rect(0, 0, 30, 10)).setTo(0);
  return d;
}

std::vector<cv::KeyPoint> At(const std::vector<cv::Point2f>& pts) {
  std::vector<cv::KeyPoint> k;
  for (const cv::Point2f& p : pts) k.emplace_back(p, 7.0f);
  return k;
}

TEST(DepthEdgesTest, ClearsReadingsWithinTheRadiusOfAJumpOrAHole) {
  const cv::Mat d = StepImage();
  // Distances to the step (columns 49 | 50) and to the hole (row 9 / 10) counted by hand.
  const std::vector<cv::KeyPoint> k = At({
      {20.0f, 40.0f},  // 29 px from the step, 30 rows below the hole: kept
      {44.0f, 40.0f},  // column 44 + 5 = 49: the window ends on the near side: kept
      {45.0f, 40.0f},  // 45 + 5 = 50 reaches the far wall: cleared
      {55.0f, 40.0f},  // 55 - 5 = 50: only the far wall: kept
      {54.0f, 40.0f},  // 54 - 5 = 49 reaches the near wall: cleared
      {20.0f, 15.0f},  // rows 10..20: no hole: kept
      {20.0f, 14.4f},  // rounds to row 14, rows 9..19 hold the hole's last row: cleared
      {35.0f, 12.0f},  // columns 30..40: right of the hole: kept
      {34.0f, 12.0f},  // columns 29..39 and rows 7..17: the hole's corner: cleared
  });
  std::vector<float> z = {2, 2, 2, 10, 10, 2, 2, 2, 2};
  const std::vector<float> before = z;
  DepthEdgeOptions o;
  ASSERT_EQ(o.radius_px, 5);
  const int cleared = ClearDepthsNearEdges(d, 1000.0, k, o, &z);
  EXPECT_EQ(cleared, 4);
  const std::vector<bool> expect_cleared = {false, false, true,  false, true,
                                            false, true,  false, true};
  for (size_t i = 0; i < z.size(); ++i) {
    if (expect_cleared[i]) {
      EXPECT_TRUE(std::isnan(z[i])) << i;
    } else {
      EXPECT_EQ(z[i], before[i]) << i;
    }
  }
}

TEST(DepthEdgesTest, ASmoothSlopeIsNoEdgeAndTheRatioDecides) {
  // Metres, CV_32F: depth grows by 2 % per column from 1 m (a floor seen obliquely).
  cv::Mat d(40, 80, CV_32FC1);
  for (int r = 0; r < d.rows; ++r) {
    for (int c = 0; c < d.cols; ++c) d.at<float>(r, c) = std::pow(1.02f, static_cast<float>(c));
  }
  const std::vector<cv::KeyPoint> k = At({{40.0f, 20.0f}});
  // Across 11 columns the ratio is 1.02^10 = 1.219: below the default 1.25.
  std::vector<float> z = {d.at<float>(20, 40)};
  EXPECT_EQ(ClearDepthsNearEdges(d, 1.0, k, DepthEdgeOptions(), &z), 0);
  EXPECT_FALSE(std::isnan(z[0]));
  DepthEdgeOptions tight;
  tight.max_depth_ratio = 1.2;
  EXPECT_EQ(ClearDepthsNearEdges(d, 1.0, k, tight, &z), 1);
  EXPECT_TRUE(std::isnan(z[0]));
  // A NaN reading in a float image is a hole.
  d.at<float>(18, 43) = kNaN;
  z = {1.0f};
  EXPECT_EQ(ClearDepthsNearEdges(d, 1.0, k, DepthEdgeOptions(), &z), 1);
}

TEST(DepthEdgesTest, LeavesMissingDepthsKeypointsOutsideTheImageAndDisabledAlone) {
  const cv::Mat d = StepImage();
  const std::vector<cv::KeyPoint> k = At({{45.0f, 40.0f}, {-3.0f, 40.0f}, {45.0f, 40.0f}});
  std::vector<float> z = {kNaN, 2.0f, 2.0f};
  EXPECT_EQ(ClearDepthsNearEdges(d, 1000.0, k, DepthEdgeOptions(), &z), 1);
  EXPECT_TRUE(std::isnan(z[0]));
  EXPECT_EQ(z[1], 2.0f);
  EXPECT_TRUE(std::isnan(z[2]));
  DepthEdgeOptions off;
  off.enabled = false;
  z = {2.0f, 2.0f, 2.0f};
  EXPECT_EQ(ClearDepthsNearEdges(d, 1000.0, k, off, &z), 0);
  EXPECT_EQ(z[2], 2.0f);
  // Radius 0: only the keypoint's own pixel, which has a reading.
  DepthEdgeOptions zero;
  zero.radius_px = 0;
  EXPECT_EQ(ClearDepthsNearEdges(d, 1000.0, k, zero, &z), 0);
}

TEST(DepthEdgesTest, RejectsBadArguments) {
  const cv::Mat d = StepImage();
  const std::vector<cv::KeyPoint> k = At({{20.0f, 40.0f}});
  std::vector<float> z = {2.0f};
  std::vector<float> two = {2.0f, 2.0f};
  EXPECT_THROW(ClearDepthsNearEdges(d, 1000.0, k, DepthEdgeOptions(), &two), InvalidArgument);
  EXPECT_THROW(ClearDepthsNearEdges(cv::Mat(), 1000.0, k, DepthEdgeOptions(), &z), InvalidArgument);
  EXPECT_THROW(ClearDepthsNearEdges(cv::Mat(10, 10, CV_8UC1, cv::Scalar(1)), 1000.0, k,
                                    DepthEdgeOptions(), &z),
               InvalidArgument);
  EXPECT_THROW(ClearDepthsNearEdges(d, 0.0, k, DepthEdgeOptions(), &z), InvalidArgument);
  EXPECT_THROW(ClearDepthsNearEdges(d, 1000.0, k, DepthEdgeOptions(), nullptr), InvalidArgument);
  DepthEdgeOptions bad;
  bad.max_depth_ratio = 0.9;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = DepthEdgeOptions();
  bad.radius_px = -1;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
