#include "imumatch/features/brief.h"

#include <algorithm>
#include <cstdio>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

const cv::Mat& TumImage() {
  static const cv::Mat img = [] {
    const std::string path = testing::DataPath("tum_fr1_xyz_pair/img_prev.png");
    cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (m.empty()) throw std::runtime_error("cannot read " + path);
    return m;
  }();
  return img;
}

int Hamming(const cv::Mat& a, const cv::Mat& b) {
  return static_cast<int>(cv::norm(a, b, cv::NORM_HAMMING));
}

std::vector<cv::KeyPoint> FastKeypoints(const cv::Mat& img, size_t max_count) {
  std::vector<cv::KeyPoint> kps;
  cv::FastFeatureDetector::create(20, true)->detect(img, kps);
  cv::KeyPointsFilter::runByImageBorder(kps, img.size(), Brief::kBorder);
  std::stable_sort(kps.begin(), kps.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
    return a.response > b.response;
  });
  if (kps.size() > max_count) kps.resize(max_count);
  return kps;
}

TEST(BriefPatternTest, IsAFixedIsotropicGaussianPatternInsideThePatch) {
  const std::array<BriefTest, 256>& pattern = BriefPattern();
  double sum = 0.0;
  double sum_sq = 0.0;
  std::set<std::tuple<int, int, int, int>> distinct;
  for (const BriefTest& t : pattern) {
    for (const int v : {t.x1, t.y1, t.x2, t.y2}) {
      EXPECT_GE(v, -23);
      EXPECT_LE(v, 23);
      sum += v;
      sum_sq += static_cast<double>(v) * v;
    }
    distinct.insert({t.x1, t.y1, t.x2, t.y2});
  }
  const double n = 4.0 * 256;
  const double mean = sum / n;
  const double variance = sum_sq / n - mean * mean;
  // sigma^2 = S^2 / 25 = 92.16; the standard error of the variance over 1024 draws is about 4.
  EXPECT_NEAR(mean, 0.0, 1.0);
  EXPECT_NEAR(variance, 92.16, 12.0);
  EXPECT_GT(distinct.size(), 250u);
  // Same pattern on every call (a static table), and fixed across runs: the first test.
  EXPECT_EQ(&BriefPattern(), &pattern);
}

TEST(BriefTest, Feature2DProperties) {
  cv::Ptr<Brief> brief = Brief::Create();
  EXPECT_EQ(brief->descriptorSize(), 32);
  EXPECT_EQ(brief->descriptorType(), CV_8U);
  EXPECT_EQ(brief->defaultNorm(), cv::NORM_HAMMING);
}

TEST(BriefTest, DetectThrows) {
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  EXPECT_THROW(Brief::Create()->detect(TumImage(), kps), InvalidArgument);
  EXPECT_THROW(Brief::Create()->detectAndCompute(TumImage(), cv::noArray(), kps, desc),
               InvalidArgument);
}

TEST(BriefTest, EmptyOrWrongTypeImageThrows) {
  std::vector<cv::KeyPoint> kps = {cv::KeyPoint(50.f, 50.f, 7.f)};
  cv::Mat desc;
  EXPECT_THROW(Brief::Create()->compute(cv::Mat(), kps, desc), InvalidArgument);
  EXPECT_THROW(Brief::Create()->compute(cv::Mat(100, 100, CV_16U, cv::Scalar(0)), kps, desc),
               InvalidArgument);
}

// OpenCV's rule (KeyPointsFilter::runByImageBorder): keep a keypoint when its rounded position
// lies in [28, width - 28) x [28, height - 28).
TEST(BriefTest, RemovesKeypointsCloseToTheBorderLikeOpenCv) {
  const cv::Mat& img = TumImage();  // 640 x 480
  std::vector<cv::KeyPoint> kps = {
      cv::KeyPoint(27.6f, 100.f, 7.f),  cv::KeyPoint(27.4f, 100.f, 7.f),
      cv::KeyPoint(611.4f, 100.f, 7.f), cv::KeyPoint(611.6f, 100.f, 7.f),
      cv::KeyPoint(300.f, 28.f, 7.f),   cv::KeyPoint(300.f, 451.f, 7.f),
      cv::KeyPoint(300.f, 452.f, 7.f),  cv::KeyPoint(300.f, 10.f, 7.f)};
  cv::Mat desc;
  Brief::Create()->compute(img, kps, desc);
  ASSERT_EQ(kps.size(), 4u);
  EXPECT_EQ(desc.rows, 4);
  EXPECT_EQ(kps[0].pt, cv::Point2f(27.6f, 100.f));
  EXPECT_EQ(kps[1].pt, cv::Point2f(611.4f, 100.f));
  EXPECT_EQ(kps[2].pt, cv::Point2f(300.f, 28.f));
  EXPECT_EQ(kps[3].pt, cv::Point2f(300.f, 451.f));
}

// On a linear ramp I = x + 2y the 9x9 box mean at (u, v) is u + 2v, so every bit is known from
// the pattern alone: bit k = (x1 + 2 y1 < x2 + 2 y2).
TEST(BriefTest, BitsFollowThePatternOnALinearRamp) {
  cv::Mat ramp(80, 80, CV_8U);
  for (int y = 0; y < ramp.rows; ++y) {
    for (int x = 0; x < ramp.cols; ++x) ramp.at<uint8_t>(y, x) = static_cast<uint8_t>(x + 2 * y);
  }
  std::vector<cv::KeyPoint> kps = {cv::KeyPoint(40.f, 39.f, 7.f)};
  cv::Mat desc;
  Brief::Create()->compute(ramp, kps, desc);
  ASSERT_EQ(desc.rows, 1);
  const std::array<BriefTest, 256>& pattern = BriefPattern();
  int ones = 0;
  for (int k = 0; k < 256; ++k) {
    const BriefTest& t = pattern[k];
    const bool expected = t.x1 + 2 * t.y1 < t.x2 + 2 * t.y2;
    const bool actual = (desc.at<uint8_t>(0, k / 8) >> (k % 8)) & 1;
    EXPECT_EQ(actual, expected) << "test " << k;
    ones += actual;
  }
  EXPECT_GT(ones, 90);  // roughly balanced
  EXPECT_LT(ones, 166);
}

TEST(BriefTest, SamePatchGivesSameDescriptor) {
  const cv::Mat patch = TumImage()(cv::Rect(200, 150, 64, 64));
  cv::Mat canvas(300, 300, CV_8U, cv::Scalar(0));
  patch.copyTo(canvas(cv::Rect(10, 20, 64, 64)));
  patch.copyTo(canvas(cv::Rect(150, 170, 64, 64)));
  std::vector<cv::KeyPoint> kps = {cv::KeyPoint(42.f, 52.f, 7.f), cv::KeyPoint(182.f, 202.f, 7.f)};
  cv::Mat desc;
  Brief::Create()->compute(canvas, kps, desc);
  ASSERT_EQ(desc.rows, 2);
  EXPECT_EQ(Hamming(desc.row(0), desc.row(1)), 0);
}

TEST(BriefTest, HammingSmallForNoisyCopyAndNearHalfForUnrelatedPatches) {
  const cv::Mat& img = TumImage();
  cv::Mat noise(img.size(), CV_16S);
  cv::RNG rng(12345);
  rng.fill(noise, cv::RNG::NORMAL, 0, 4);
  cv::Mat noisy;
  cv::Mat img16;
  img.convertTo(img16, CV_16S);
  cv::Mat sum16 = img16 + noise;
  sum16.convertTo(noisy, CV_8U);  // saturates

  std::vector<cv::KeyPoint> kps = FastKeypoints(img, 300);
  ASSERT_GT(kps.size(), 100u);
  std::vector<cv::KeyPoint> kps_noisy = kps;
  cv::Mat d;
  cv::Mat d_noisy;
  Brief::Create()->compute(img, kps, d);
  Brief::Create()->compute(noisy, kps_noisy, d_noisy);
  ASSERT_EQ(d.rows, d_noisy.rows);
  double same = 0.0;
  double unrelated = 0.0;
  int n_unrelated = 0;
  for (int i = 0; i < d.rows; ++i) {
    same += Hamming(d.row(i), d_noisy.row(i));
    // Pair with a keypoint at least 48 px away (non-overlapping patches).
    const int j = (i + d.rows / 2) % d.rows;
    if (cv::norm(kps[i].pt - kps[j].pt) >= 48.0) {
      unrelated += Hamming(d.row(i), d.row(j));
      ++n_unrelated;
    }
  }
  same /= d.rows;
  unrelated /= n_unrelated;
  std::printf("mean Hamming: noisy copy %.1f, unrelated %.1f (%d pairs)\n", same, unrelated,
              n_unrelated);
  EXPECT_LT(same, 20.0);
  EXPECT_NEAR(unrelated, 128.0, 30.0);
}

TEST(BriefTest, MatchesRecoverTranslationAndBrightnessChange) {
  const cv::Mat& img = TumImage();
  const cv::Point2f shift(5.f, 3.f);
  cv::Mat moved;
  cv::warpAffine(img, moved, cv::Matx23d(1, 0, shift.x, 0, 1, shift.y), img.size(),
                 cv::INTER_NEAREST, cv::BORDER_REFLECT);
  moved.convertTo(moved, CV_8U, 1.0, 25.0);  // brighter (saturating)
  std::vector<cv::KeyPoint> kp1 = FastKeypoints(img, 500);
  std::vector<cv::KeyPoint> kp2 = FastKeypoints(moved, 500);
  cv::Mat d1;
  cv::Mat d2;
  Brief::Create()->compute(img, kp1, d1);
  Brief::Create()->compute(moved, kp2, d2);
  cv::BFMatcher matcher(cv::NORM_HAMMING, true);
  std::vector<cv::DMatch> matches;
  matcher.match(d1, d2, matches);
  ASSERT_GT(matches.size(), 100u);
  int correct = 0;
  std::vector<float> dx;
  std::vector<float> dy;
  for (const cv::DMatch& m : matches) {
    const cv::Point2f d = kp2[m.trainIdx].pt - kp1[m.queryIdx].pt;
    dx.push_back(d.x);
    dy.push_back(d.y);
    if (cv::norm(d - shift) < 1e-3) ++correct;
  }
  std::nth_element(dx.begin(), dx.begin() + dx.size() / 2, dx.end());
  std::nth_element(dy.begin(), dy.begin() + dy.size() / 2, dy.end());
  std::printf("translation: %zu cross-checked matches, %d exact\n", matches.size(), correct);
  EXPECT_EQ(dx[dx.size() / 2], shift.x);
  EXPECT_EQ(dy[dy.size() / 2], shift.y);
  EXPECT_GT(correct, 0.8 * static_cast<double>(matches.size()));
}

}  // namespace
}  // namespace imumatch
