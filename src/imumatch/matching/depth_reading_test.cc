#include "imumatch/matching/depth_reading.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

TEST(DepthReadingTest, SampleDepthModes) {
  cv::Mat raw = cv::Mat::zeros(5, 5, CV_16U);
  // 3x3 around (2,2): centre 0 (hole), neighbours 5000 (1 m) .. with one at 2500 (0.5 m) on the
  // right and 15000 (3 m) below.
  for (int r = 1; r <= 3; ++r) {
    for (int c = 1; c <= 3; ++c) raw.at<uint16_t>(r, c) = 5000;
  }
  raw.at<uint16_t>(2, 2) = 0;
  raw.at<uint16_t>(2, 3) = 2500;
  raw.at<uint16_t>(3, 2) = 15000;
  // Nearest: the hole is skipped; (2.4, 2.0) is nearest to (3, 2) -> 0.5 m.
  EXPECT_FLOAT_EQ(SampleDepth(raw, 5000.0, 2.4f, 2.0f, DepthSampling::kNearest), 0.5f);
  EXPECT_FLOAT_EQ(SampleDepth(raw, 5000.0, 2.0f, 2.4f, DepthSampling::kNearest), 3.0f);
  EXPECT_FLOAT_EQ(SampleDepth(raw, 5000.0, 1.0f, 1.0f, DepthSampling::kNearest), 1.0f);
  EXPECT_FLOAT_EQ(SampleDepth(raw, 5000.0, 2.0f, 2.0f, DepthSampling::kMin3x3), 0.5f);
  // 8 valid readings: 0.5, 1 x6, 3 -> lower median 1.
  EXPECT_FLOAT_EQ(SampleDepth(raw, 5000.0, 2.0f, 2.0f, DepthSampling::kMedian3x3), 1.0f);
  EXPECT_TRUE(std::isnan(SampleDepth(raw, 5000.0, 20.0f, 2.0f, DepthSampling::kNearest)));
  cv::Mat holes = cv::Mat::zeros(5, 5, CV_16U);
  EXPECT_TRUE(std::isnan(SampleDepth(holes, 5000.0, 2.0f, 2.0f, DepthSampling::kMedian3x3)));
  cv::Mat metres(5, 5, CV_32F, cv::Scalar(2.0f));
  metres.at<float>(2, 2) = std::nanf("");
  EXPECT_FLOAT_EQ(SampleDepth(metres, 5000.0, 2.0f, 2.0f, DepthSampling::kNearest), 2.0f);
  std::vector<cv::KeyPoint> kps = {cv::KeyPoint(1.0f, 1.0f, 7.0f), cv::KeyPoint(9.0f, 9.0f, 7.0f)};
  const std::vector<float> d = SampleDepths(raw, 5000.0, kps, DepthSampling::kNearest);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_FLOAT_EQ(d[0], 1.0f);
  EXPECT_TRUE(std::isnan(d[1]));
  EXPECT_THROW(SampleDepth(cv::Mat::zeros(3, 3, CV_8U), 5000.0, 1, 1, DepthSampling::kNearest),
               InvalidArgument);
}

// SampleDepths visits the keypoints row by row (for the cache); each keypoint must still get
// exactly what SampleDepth gives it alone: random positions, on the border, off the image and
// NaN, both depth types, every mode.
TEST(DepthReadingTest, SampleDepthsEqualsSampleDepthPerKeypoint) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> ux(-3.0f, 82.0f), uy(-3.0f, 62.0f);
  cv::Mat raw(60, 80, CV_16UC1);
  cv::randu(raw, 0, 9000);
  raw.setTo(0, raw < 1500);  // holes
  cv::Mat metres;
  raw.convertTo(metres, CV_32F, 1.0 / 5000.0);
  std::vector<KeypointInfo> infos(500);
  std::vector<cv::KeyPoint> cv_points(infos.size());
  for (size_t i = 0; i < infos.size(); ++i) {
    float x = ux(rng), y = uy(rng);
    if (i % 50 == 0) y = std::numeric_limits<float>::quiet_NaN();
    if (i % 37 == 0) y = 59.49f;
    if (i % 41 == 0) y = -0.5f;
    infos[i] = {x, y, 0.0f, 7.0f, 0};
    cv_points[i].pt = cv::Point2f(x, y);
  }
  for (const DepthSampling mode :
       {DepthSampling::kNearest, DepthSampling::kMin3x3, DepthSampling::kMedian3x3}) {
    for (const cv::Mat& depth : {raw, metres}) {
      const double scale = depth.type() == CV_16UC1 ? 5000.0 : 1.0;
      const std::vector<float> a = SampleDepths(depth, scale, infos, mode);
      const std::vector<float> b = SampleDepths(depth, scale, cv_points, mode);
      int valid = 0;
      for (size_t i = 0; i < infos.size(); ++i) {
        const float one = SampleDepth(depth, scale, infos[i].x, infos[i].y, mode);
        valid += std::isfinite(one);
        EXPECT_TRUE((std::isnan(one) && std::isnan(a[i])) || one == a[i]) << i;
        EXPECT_TRUE((std::isnan(one) && std::isnan(b[i])) || one == b[i]) << i;
      }
      EXPECT_GT(valid, 300);
    }
  }
}

}  // namespace
}  // namespace imumatch
