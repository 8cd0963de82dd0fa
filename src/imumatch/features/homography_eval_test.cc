#include "imumatch/features/homography_eval.h"

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

// Three keypoints per image, a translation by (5, 0) and hand-made descriptors:
//   image 1: (10,10) e0, (50,50) e1, (90,90) e2
//   image 2: (15,10) e0, (55,52.5) 0.9 e1 + 0.1 e2, (200,200) e3
// Mapped into image 2, the points of image 1 land at (15,10), (55,50), (95,90): all inside the
// 100x100 image; mapped back, the points of image 2 land at (10,10), (50,52.5), (195,200): two
// inside. Nearest neighbours: q0 -> t0 (distance 0, ratio 0), q1 -> t1 (0.141 vs 1.414), q2 -> t1
// (1.273 vs 1.414: ratio 0.9, rejected at 0.8).
struct Fixture {
  Features f1;
  Features f2;
  cv::Mat h = (cv::Mat_<double>(3, 3) << 1, 0, 5, 0, 1, 0, 0, 0, 1);
  Fixture() {
    f1.keypoints = {cv::KeyPoint(10, 10, 5), cv::KeyPoint(50, 50, 5), cv::KeyPoint(90, 90, 5)};
    f2.keypoints = {cv::KeyPoint(15, 10, 5), cv::KeyPoint(55, 52.5f, 5), cv::KeyPoint(200, 200, 5)};
    f1.descriptors = (cv::Mat_<float>(3, 4) << 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0);
    f2.descriptors = (cv::Mat_<float>(3, 4) << 1, 0, 0, 0, 0, 0.9f, 0.1f, 0, 0, 0, 0, 1);
  }
};

TEST(HomographyEvalTest, HandComputedCounts) {
  const Fixture fx;
  const HomographyEval e =
      EvaluateOnHomography(fx.f1, fx.f2, fx.h, cv::Size(100, 100), cv::Size(100, 100), cv::NORM_L2);
  EXPECT_EQ(e.keypoints1, 3);
  EXPECT_EQ(e.keypoints2, 3);
  EXPECT_EQ(e.common1, 3);
  EXPECT_EQ(e.common2, 2);
  EXPECT_EQ(e.repeated, 2);                // (15,10) exact, (55,50) vs (55,52.5): 2.5 px
  EXPECT_DOUBLE_EQ(e.repeatability, 1.0);  // 2 / min(3, 2)
  EXPECT_EQ(e.matches, 2);
  EXPECT_EQ(e.correct_matches, 2);
  EXPECT_DOUBLE_EQ(e.precision, 1.0);
}

TEST(HomographyEvalTest, TighterToleranceAndRatio) {
  const Fixture fx;
  HomographyEvalOptions options;
  options.pixel_tolerance = 2.0;
  const HomographyEval e = EvaluateOnHomography(fx.f1, fx.f2, fx.h, cv::Size(100, 100),
                                                cv::Size(100, 100), cv::NORM_L2, options);
  EXPECT_EQ(e.repeated, 1);
  EXPECT_DOUBLE_EQ(e.repeatability, 0.5);
  EXPECT_EQ(e.matches, 2);
  EXPECT_EQ(e.correct_matches, 1);
  EXPECT_DOUBLE_EQ(e.precision, 0.5);
  options.pixel_tolerance = 3.0;
  options.ratio = 0.95;  // q2 -> t1 now passes (ratio 0.9) but is wrong
  const HomographyEval e2 = EvaluateOnHomography(fx.f1, fx.f2, fx.h, cv::Size(100, 100),
                                                 cv::Size(100, 100), cv::NORM_L2, options);
  EXPECT_EQ(e2.matches, 3);
  EXPECT_EQ(e2.correct_matches, 2);
}

TEST(HomographyEvalTest, RejectsBadInput) {
  const Fixture fx;
  EXPECT_THROW(EvaluateOnHomography(fx.f1, fx.f2, cv::Mat::eye(2, 3, CV_64F), cv::Size(100, 100),
                                    cv::Size(100, 100), cv::NORM_L2),
               InvalidArgument);
  EXPECT_THROW(EvaluateOnHomography(fx.f1, fx.f2, cv::Mat::zeros(3, 3, CV_64F), cv::Size(100, 100),
                                    cv::Size(100, 100), cv::NORM_L2),
               InvalidArgument);
  HomographyEvalOptions bad;
  bad.ratio = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
