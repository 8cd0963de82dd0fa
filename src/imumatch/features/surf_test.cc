#include "imumatch/features/surf.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/features/homography_eval.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

const char* kOpenCvData = "/usr/share/doc/opencv-doc/examples/data";

cv::Mat LoadGray(const std::string& path) {
  cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw std::runtime_error("cannot read test image " + path);
  return img;
}

const cv::Mat& TumImage() {
  static const cv::Mat img = LoadGray(testing::DataPath("tum_fr1_xyz_pair/img_prev.png"));
  return img;
}

// Image with a bright isotropic Gaussian blob of standard deviation sigma centred at (cx, cy).
cv::Mat GaussianBlob(cv::Size size, double cx, double cy, double sigma, double amplitude) {
  cv::Mat img(size, CV_8U);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
      img.at<uint8_t>(y, x) =
          cv::saturate_cast<uint8_t>(30.0 + amplitude * std::exp(-r2 / (2 * sigma * sigma)));
    }
  }
  return img;
}

double AngleDiffDeg(double a, double b) {
  double d = std::fmod(a - b, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d < -180.0) d += 360.0;
  return d;
}

struct MatchResult {
  std::vector<cv::DMatch> matches;
  std::vector<cv::Point2f> pts1, pts2;
};

MatchResult RatioMatch(const std::vector<cv::KeyPoint>& kp1, const cv::Mat& d1,
                       const std::vector<cv::KeyPoint>& kp2, const cv::Mat& d2, int norm) {
  MatchResult out;
  cv::BFMatcher matcher(norm);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(d1, d2, knn, 2);
  for (const auto& m : knn) {
    if (m.size() == 2 && m[0].distance < 0.8f * m[1].distance) {
      out.matches.push_back(m[0]);
      out.pts1.push_back(kp1[m[0].queryIdx].pt);
      out.pts2.push_back(kp2[m[0].trainIdx].pt);
    }
  }
  return out;
}

cv::Point2d Apply(const cv::Matx33d& h, const cv::Point2d& p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

// Largest distance between where the estimated and the true homographies map the image corners.
double CornerError(const cv::Matx33d& estimated, const cv::Matx33d& truth, cv::Size size) {
  const std::vector<cv::Point2d> corners = {
      {0, 0}, {size.width - 1.0, 0}, {0, size.height - 1.0}, {size.width - 1.0, size.height - 1.0}};
  double worst = 0.0;
  for (const cv::Point2d& c : corners) {
    worst = std::max(worst, cv::norm(Apply(estimated, c) - Apply(truth, c)));
  }
  return worst;
}

TEST(SurfOptionsTest, CheckRejectsBadValues) {
  SurfOptions ok;
  EXPECT_NO_THROW(ok.Check());
  SurfOptions bad = ok;
  bad.hessian_threshold = -1;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.hessian_threshold = std::nan("");
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.n_octaves = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.n_intervals = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.max_keypoints = -5;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  EXPECT_THROW(Surf{bad}, InvalidArgument);
}

TEST(SurfTest, Feature2DProperties) {
  cv::Ptr<Surf> surf = Surf::Create();
  EXPECT_EQ(surf->descriptorSize(), 64);
  EXPECT_EQ(surf->descriptorType(), CV_32F);
  EXPECT_EQ(surf->defaultNorm(), cv::NORM_L2);
}

TEST(SurfTest, RejectsEmptyOrWrongTypeImages) {
  cv::Ptr<Surf> surf = Surf::Create();
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  EXPECT_THROW(surf->detectAndCompute(cv::Mat(), cv::noArray(), kps, desc), InvalidArgument);
  EXPECT_THROW(surf->detect(cv::Mat(50, 50, CV_32F, cv::Scalar(1)), kps), InvalidArgument);
}

TEST(SurfTest, TinyImagesAndFarKeypointsAreHandled) {
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(5, 3), cv::Size(26, 40)}) {
    cv::Mat img(size, CV_8U);
    cv::randu(img, 0, 255);
    std::vector<cv::KeyPoint> kps;
    cv::Mat desc;
    Surf::Create()->detectAndCompute(img, cv::noArray(), kps, desc);
    EXPECT_TRUE(kps.empty());
    EXPECT_EQ(desc.rows, 0);
  }
  // Keypoints far outside the image or absurdly large cannot be described, upright or not.
  for (const bool upright : {false, true}) {
    SurfOptions options;
    options.upright = upright;
    std::vector<cv::KeyPoint> kps = {cv::KeyPoint(-500.f, 10.f, 20.f),
                                     cv::KeyPoint(100.f, 1e30f, 20.f),
                                     cv::KeyPoint(100.f, 100.f, 1e30f)};
    cv::Mat desc;
    Surf::Create(options)->compute(TumImage(), kps, desc);
    EXPECT_TRUE(kps.empty());
    EXPECT_EQ(desc.rows, 0);
  }
}

TEST(SurfTest, FlatImageHasNoKeypoints) {
  cv::Ptr<Surf> surf = Surf::Create();
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  surf->detectAndCompute(cv::Mat(120, 160, CV_8U, cv::Scalar(77)), cv::noArray(), kps, desc);
  EXPECT_TRUE(kps.empty());
  EXPECT_EQ(desc.rows, 0);
}

// Blob detection on synthetic images. For a Gaussian blob of standard deviation sigma the
// scale-normalised determinant of the *Gaussian* Hessian peaks at scale sigma, but SURF's box
// filters peak earlier. Summing the box lobes over the sampled unit-amplitude blob by hand (the
// blob is separable; at the centre Dxy = 0 and Dxx = Dyy) for sigma = 4 gives Dxx * Dyy = 0.598,
// 0.739, 0.603 at L = 15, 21, 27: the maximum is at L = 21, s = 1.2 * 21 / 9 = 2.8 = 0.7 sigma.
// The ratio is the same at every scale (scale covariance), which is what matching relies on.
TEST(SurfTest, FindsGaussianBlobAtItsPositionAndScale) {
  std::vector<double> ratios;
  for (const double sigma : {2.5, 4.0, 6.0, 9.0}) {
    SCOPED_TRACE("sigma " + std::to_string(sigma));
    const double cx = 120.3;
    const double cy = 101.6;
    const cv::Mat img = GaussianBlob(cv::Size(240, 200), cx, cy, sigma, 180.0);
    std::vector<cv::KeyPoint> kps;
    Surf::Create()->detect(img, kps);
    ASSERT_FALSE(kps.empty());
    const cv::KeyPoint& best = kps.front();  // strongest first
    EXPECT_NEAR(best.pt.x, cx, 0.05 * sigma + 0.3);
    EXPECT_NEAR(best.pt.y, cy, 0.05 * sigma + 0.3);
    const double s = 1.2 * best.size / 9.0;
    ratios.push_back(s / sigma);
    EXPECT_NEAR(s / sigma, 0.72, 0.08) << "size " << best.size;
    EXPECT_EQ(best.class_id, -1);  // bright blob: negative Laplacian
    EXPECT_GT(best.response, 100.f);
    // Dark blob: same position and scale, positive Laplacian.
    cv::Mat dark = 255 - img;
    std::vector<cv::KeyPoint> dark_kps;
    Surf::Create()->detect(dark, dark_kps);
    ASSERT_FALSE(dark_kps.empty());
    EXPECT_NEAR(dark_kps.front().pt.x, best.pt.x, 1e-3);
    EXPECT_NEAR(dark_kps.front().size, best.size, 1e-3);
    EXPECT_EQ(dark_kps.front().class_id, 1);
  }
  const auto [lo, hi] = std::minmax_element(ratios.begin(), ratios.end());
  EXPECT_LT(*hi / *lo, 1.12);
}

TEST(SurfTest, DescriptorsAreUnitLengthAndKeypointsSortedByResponse) {
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  Surf::Create()->detectAndCompute(TumImage(), cv::noArray(), kps, desc);
  ASSERT_GT(kps.size(), 300u);
  ASSERT_EQ(desc.rows, static_cast<int>(kps.size()));
  ASSERT_EQ(desc.cols, 64);
  ASSERT_EQ(desc.type(), CV_32F);
  for (int i = 0; i < desc.rows; ++i) EXPECT_NEAR(cv::norm(desc.row(i)), 1.0, 1e-4);
  for (size_t i = 1; i < kps.size(); ++i) EXPECT_GE(kps[i - 1].response, kps[i].response);
  for (const cv::KeyPoint& kp : kps) {
    EXPECT_GE(kp.angle, 0.f);
    EXPECT_LT(kp.angle, 360.f);
    EXPECT_GE(kp.size,
              9.f * (1.f - 0.67f));  // at least the 9x9 filter minus one interpolation step
    EXPECT_GE(kp.octave, 0);
    EXPECT_LT(kp.octave, 4);
    EXPECT_GE(kp.response, 100.f);
    EXPECT_TRUE(kp.class_id == 1 || kp.class_id == -1);
    EXPECT_GE(kp.pt.x, 0.f);
    EXPECT_GE(kp.pt.y, 0.f);
    EXPECT_LT(kp.pt.x, 640.f);
    EXPECT_LT(kp.pt.y, 480.f);
  }
}

TEST(SurfTest, MaxKeypointsKeepsTheStrongest) {
  std::vector<cv::KeyPoint> all;
  Surf::Create()->detect(TumImage(), all);
  SurfOptions options;
  options.max_keypoints = 200;
  std::vector<cv::KeyPoint> capped;
  Surf::Create(options)->detect(TumImage(), capped);
  ASSERT_GT(all.size(), 200u);
  ASSERT_EQ(capped.size(), 200u);
  for (size_t i = 0; i < capped.size(); ++i) {
    EXPECT_EQ(capped[i].pt, all[i].pt);
    EXPECT_EQ(capped[i].response, all[i].response);
  }
}

TEST(SurfTest, HigherThresholdGivesASubset) {
  std::vector<cv::KeyPoint> low;
  std::vector<cv::KeyPoint> high;
  SurfOptions options;
  Surf::Create(options)->detect(TumImage(), low);
  options.hessian_threshold = 1000;
  Surf::Create(options)->detect(TumImage(), high);
  ASSERT_FALSE(high.empty());
  EXPECT_LT(high.size(), low.size());
  for (const cv::KeyPoint& kp : high) EXPECT_GT(kp.response, 1000.f);
}

TEST(SurfTest, ComputeOnDetectedKeypointsReproducesDetectAndCompute) {
  cv::Ptr<Surf> surf = Surf::Create();
  std::vector<cv::KeyPoint> kps;
  cv::Mat desc;
  surf->detectAndCompute(TumImage(), cv::noArray(), kps, desc);
  std::vector<cv::KeyPoint> kps2 = kps;
  for (cv::KeyPoint& kp : kps2) kp.angle = -1.f;  // orientation is recomputed
  cv::Mat desc2;
  surf->compute(TumImage(), kps2, desc2);
  ASSERT_EQ(kps2.size(), kps.size());
  EXPECT_EQ(cv::norm(desc, desc2, cv::NORM_INF), 0.0);
  for (size_t i = 0; i < kps.size(); ++i) EXPECT_EQ(kps[i].angle, kps2[i].angle);
}

TEST(SurfTest, ComputeDropsInvalidKeypoints) {
  std::vector<cv::KeyPoint> kps = {cv::KeyPoint(100.f, 100.f, 20.f), cv::KeyPoint(50.f, 60.f, 0.f),
                                   cv::KeyPoint(200.f, 150.f, 15.f)};
  cv::Mat desc;
  Surf::Create()->compute(TumImage(), kps, desc);
  ASSERT_EQ(kps.size(), 2u);
  EXPECT_EQ(desc.rows, 2);
  EXPECT_EQ(kps[0].pt, cv::Point2f(100.f, 100.f));
  EXPECT_EQ(kps[1].pt, cv::Point2f(200.f, 150.f));
}

TEST(SurfTest, MaskRestrictsDetections) {
  cv::Mat mask = cv::Mat::zeros(TumImage().size(), CV_8U);
  mask(cv::Rect(0, 0, 320, 480)).setTo(255);
  std::vector<cv::KeyPoint> kps;
  Surf::Create()->detect(TumImage(), kps, mask);
  ASSERT_FALSE(kps.empty());
  for (const cv::KeyPoint& kp : kps) EXPECT_LT(kp.pt.x, 320.f);
}

TEST(SurfTest, UprightGivesZeroAnglesAndMatchesTranslation) {
  SurfOptions options;
  options.upright = true;
  cv::Ptr<Surf> surf = Surf::Create(options);
  const cv::Mat& img = TumImage();
  // Shift by (7, -4) pixels.
  const cv::Matx23d shift(1, 0, 7, 0, 1, -4);
  cv::Mat moved;
  cv::warpAffine(img, moved, shift, img.size(), cv::INTER_NEAREST, cv::BORDER_REFLECT);
  std::vector<cv::KeyPoint> kp1, kp2;
  cv::Mat d1, d2;
  surf->detectAndCompute(img, cv::noArray(), kp1, d1);
  surf->detectAndCompute(moved, cv::noArray(), kp2, d2);
  for (const cv::KeyPoint& kp : kp1) EXPECT_EQ(kp.angle, 0.f);
  const MatchResult m = RatioMatch(kp1, d1, kp2, d2, cv::NORM_L2);
  ASSERT_GT(m.matches.size(), 200u);
  int correct = 0;
  for (size_t i = 0; i < m.pts1.size(); ++i) {
    // Octave o samples every 2^o pixels: an odd shift moves the grid, interpolation absorbs it.
    const double tolerance = 0.4 * (1 << kp1[m.matches[i].queryIdx].octave) + 0.25;
    if (cv::norm(m.pts2[i] - m.pts1[i] - cv::Point2f(7.f, -4.f)) < tolerance) ++correct;
  }
  std::printf("upright, shift (7, -4): %zu matches, %d at the right place\n", m.matches.size(),
              correct);
  EXPECT_GT(correct, 0.9 * static_cast<double>(m.matches.size()));
}

class SurfRotationTest : public ::testing::TestWithParam<double> {};

TEST_P(SurfRotationTest, RecoversRotationHomographyAndAngles) {
  const double degrees = GetParam();
  const cv::Mat& img = TumImage();
  const cv::Point2f centre(0.5f * (img.cols - 1), 0.5f * (img.rows - 1));
  const cv::Mat rot = cv::getRotationMatrix2D(centre, degrees, 1.0);
  cv::Mat rotated;
  cv::warpAffine(img, rotated, rot, img.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::Matx33d truth = cv::Matx33d::eye();
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 3; ++c) truth(r, c) = rot.at<double>(r, c);
  }

  SurfOptions options;
  options.max_keypoints = 1000;
  cv::Ptr<Surf> surf = Surf::Create(options);
  std::vector<cv::KeyPoint> kp1, kp2;
  cv::Mat d1, d2;
  surf->detectAndCompute(img, cv::noArray(), kp1, d1);
  surf->detectAndCompute(rotated, cv::noArray(), kp2, d2);
  const MatchResult m = RatioMatch(kp1, d1, kp2, d2, cv::NORM_L2);
  ASSERT_GT(m.matches.size(), 100u);
  std::vector<uint8_t> inliers;
  const cv::Mat h =
      cv::findHomography(m.pts1, m.pts2, cv::USAC_ACCURATE, 3.0, inliers, 2000, 0.999);
  ASSERT_FALSE(h.empty());
  const int n_inliers = cv::countNonZero(inliers);
  int n_true = 0;  // matches consistent with the true rotation
  for (size_t i = 0; i < m.pts1.size(); ++i) {
    n_true += cv::norm(Apply(truth, m.pts1[i]) - cv::Point2d(m.pts2[i])) < 3.0 ? 1 : 0;
  }
  const double true_ratio = static_cast<double>(n_true) / m.matches.size();
  std::printf("rotation %.0f deg: %zu/%zu keypoints, %zu matches, %d inliers, %d correct (%.2f)\n",
              degrees, kp1.size(), kp2.size(), m.matches.size(), n_inliers, n_true, true_ratio);
  EXPECT_GT(true_ratio, 0.65);
  EXPECT_GT(n_inliers, 0.8 * n_true);
  // The corners lie partly outside the rotated content: the homography is extrapolated there.
  const double corner_error = CornerError(cv::Matx33d(h), truth, img.size());
  std::printf("  corner error %.2f px\n", corner_error);
  EXPECT_LT(corner_error, 3.0);

  // Keypoint angles follow the image rotation: a counter-clockwise rotation by a on screen
  // subtracts a from OpenCV angles (measured clockwise, y down).
  std::vector<double> angle_errors;
  std::vector<double> size_ratios;
  for (size_t i = 0; i < m.matches.size(); ++i) {
    if (!inliers[i]) continue;
    const cv::KeyPoint& a = kp1[m.matches[i].queryIdx];
    const cv::KeyPoint& b = kp2[m.matches[i].trainIdx];
    angle_errors.push_back(std::abs(AngleDiffDeg(b.angle, a.angle - degrees)));
    size_ratios.push_back(b.size / a.size);
  }
  std::sort(angle_errors.begin(), angle_errors.end());
  std::sort(size_ratios.begin(), size_ratios.end());
  std::printf("  angle error: median %.2f deg, 90%% %.2f deg\n",
              angle_errors[angle_errors.size() / 2], angle_errors[angle_errors.size() * 9 / 10]);
  // Box filters and the axis-aligned sampling grid make SURF orientations a few degrees noisier
  // at 30 and 60 degrees than at multiples of 90 (where the filters map onto themselves).
  EXPECT_LT(angle_errors[angle_errors.size() / 2], 6.0);
  EXPECT_LT(angle_errors[angle_errors.size() * 9 / 10], 15.0);
  EXPECT_NEAR(size_ratios[size_ratios.size() / 2], 1.0, 0.08);
}

INSTANTIATE_TEST_SUITE_P(Angles, SurfRotationTest, ::testing::Values(30.0, 60.0, 90.0));

TEST(SurfTest, ScaleByTwoDoublesKeypointSizes) {
  const cv::Mat& img = TumImage();
  // Upscale the central 320x240 crop by 2 so both images show the same content at 640x480.
  const cv::Rect crop(160, 120, 320, 240);
  cv::Mat small = img(crop).clone();
  cv::Mat big;
  cv::resize(small, big, cv::Size(), 2.0, 2.0, cv::INTER_CUBIC);
  // pixel centres: x_big = 2 * x_small + 0.5
  const cv::Matx33d truth(2, 0, 0.5, 0, 2, 0.5, 0, 0, 1);
  cv::Ptr<Surf> surf = Surf::Create();
  std::vector<cv::KeyPoint> kp1, kp2;
  cv::Mat d1, d2;
  surf->detectAndCompute(small, cv::noArray(), kp1, d1);
  surf->detectAndCompute(big, cv::noArray(), kp2, d2);
  const MatchResult m = RatioMatch(kp1, d1, kp2, d2, cv::NORM_L2);
  ASSERT_GT(m.matches.size(), 40u);
  std::vector<uint8_t> inliers;
  const cv::Mat h =
      cv::findHomography(m.pts1, m.pts2, cv::USAC_ACCURATE, 3.0, inliers, 2000, 0.999);
  ASSERT_FALSE(h.empty());
  const double inlier_ratio = static_cast<double>(cv::countNonZero(inliers)) / m.matches.size();
  std::printf("scale 2: %zu/%zu keypoints, %zu matches, inlier ratio %.2f\n", kp1.size(),
              kp2.size(), m.matches.size(), inlier_ratio);
  EXPECT_GT(inlier_ratio, 0.5);
  EXPECT_LT(CornerError(cv::Matx33d(h), truth, small.size()), 4.0);
  std::vector<double> ratios;
  for (size_t i = 0; i < m.matches.size(); ++i) {
    if (inliers[i]) {
      ratios.push_back(kp2[m.matches[i].trainIdx].size / kp1[m.matches[i].queryIdx].size);
    }
  }
  std::sort(ratios.begin(), ratios.end());
  EXPECT_NEAR(ratios[ratios.size() / 2], 2.0, 0.2);
}

// graf1 -> graf3 of the Oxford affine dataset (viewpoint change of about 40 degrees): prints the
// quality of SURF, SIFT and ORB and checks that SURF's matching precision is reasonable.
TEST(SurfTest, GraffitiPrecisionComparableToSift) {
  const cv::Mat graf1 = LoadGray(std::string(kOpenCvData) + "/graf1.png");
  const cv::Mat graf3 = LoadGray(std::string(kOpenCvData) + "/graf3.png");
  cv::FileStorage fs(std::string(kOpenCvData) + "/H1to3p.xml", cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened());
  cv::Mat h13;
  fs.getFirstTopLevelNode() >> h13;
  ASSERT_EQ(h13.rows, 3);
  double precision[3] = {0, 0, 0};
  const DetectorKind kinds[3] = {DetectorKind::kSurf, DetectorKind::kSift, DetectorKind::kOrb};
  for (int k = 0; k < 3; ++k) {
    FeatureOptions options;
    options.kind = kinds[k];
    options.max_keypoints = 1000;
    const Features f1 = ExtractFeatures(graf1, options);
    const Features f2 = ExtractFeatures(graf3, options);
    const HomographyEval e =
        EvaluateOnHomography(f1, f2, h13, graf1.size(), graf3.size(),
                             IsBinaryDescriptor(kinds[k]) ? cv::NORM_HAMMING : cv::NORM_L2);
    std::printf("graf1->graf3 %-5s: repeatability %.3f, %d matches, %d correct, precision %.3f\n",
                ToString(kinds[k]).c_str(), e.repeatability, e.matches, e.correct_matches,
                e.precision);
    precision[k] = e.precision;
    EXPECT_GT(e.correct_matches, 20);
  }
  EXPECT_GT(precision[0], 0.5 * precision[1]);
  EXPECT_GT(precision[0], 0.4);
}

}  // namespace
}  // namespace imumatch
