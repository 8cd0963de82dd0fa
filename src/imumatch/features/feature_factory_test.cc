#include "imumatch/features/feature_factory.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

const std::vector<DetectorKind> kAllKinds = {DetectorKind::kSift,  DetectorKind::kSurf,
                                             DetectorKind::kOrb,   DetectorKind::kFastBrief,
                                             DetectorKind::kAkaze, DetectorKind::kBrisk};

const cv::Mat& TumColorImage() {
  static const cv::Mat img = [] {
    const std::string path = testing::DataPath("tum_fr1_xyz_pair/img_prev.png");
    cv::Mat m = cv::imread(path, cv::IMREAD_COLOR);
    if (m.empty()) throw std::runtime_error("cannot read " + path);
    return m;
  }();
  return img;
}

TEST(DetectorKindTest, ParsesEveryNameCaseInsensitively) {
  EXPECT_EQ(ParseDetectorKind("sift"), DetectorKind::kSift);
  EXPECT_EQ(ParseDetectorKind("SURF"), DetectorKind::kSurf);
  EXPECT_EQ(ParseDetectorKind("Orb"), DetectorKind::kOrb);
  EXPECT_EQ(ParseDetectorKind("fast"), DetectorKind::kFastBrief);
  EXPECT_EQ(ParseDetectorKind("FAST_BRIEF"), DetectorKind::kFastBrief);
  EXPECT_EQ(ParseDetectorKind("akaze"), DetectorKind::kAkaze);
  EXPECT_EQ(ParseDetectorKind("brisk"), DetectorKind::kBrisk);
}

TEST(DetectorKindTest, UnknownNameThrowsListingValidNames) {
  for (const std::string bad : {"", "harris", "sift ", "fast-brief"}) {
    try {
      ParseDetectorKind(bad);
      ADD_FAILURE() << "no exception for '" << bad << "'";
    } catch (const InvalidArgument& e) {
      const std::string what = e.what();
      for (const char* name : {"sift", "surf", "orb", "fast_brief", "akaze", "brisk"}) {
        EXPECT_NE(what.find(name), std::string::npos) << what;
      }
    }
  }
}

TEST(DetectorKindTest, ToStringRoundTripsAndBinaryFlag) {
  for (const DetectorKind kind : kAllKinds) {
    EXPECT_EQ(ParseDetectorKind(ToString(kind)), kind);
  }
  EXPECT_FALSE(IsBinaryDescriptor(DetectorKind::kSift));
  EXPECT_FALSE(IsBinaryDescriptor(DetectorKind::kSurf));
  EXPECT_TRUE(IsBinaryDescriptor(DetectorKind::kOrb));
  EXPECT_TRUE(IsBinaryDescriptor(DetectorKind::kFastBrief));
  EXPECT_TRUE(IsBinaryDescriptor(DetectorKind::kAkaze));
  EXPECT_TRUE(IsBinaryDescriptor(DetectorKind::kBrisk));
  EXPECT_THROW(ToString(static_cast<DetectorKind>(42)), InvalidArgument);
}

TEST(FeatureOptionsTest, CheckRejectsBadValues) {
  FeatureOptions ok;
  EXPECT_NO_THROW(ok.Check());
  FeatureOptions bad = ok;
  bad.max_keypoints = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad.max_keypoints = 2147483647;  // would allocate without bound
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad.max_keypoints = FeatureOptions::kMaxKeypoints;
  EXPECT_NO_THROW(bad.Check());
  bad = ok;
  bad.orb_scale_factor = 1.0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.fast_threshold = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.surf.hessian_threshold = -3;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.akaze_threshold = 0;
  EXPECT_THROW(bad.Check(), InvalidArgument);
  bad = ok;
  bad.kind = static_cast<DetectorKind>(-1);
  EXPECT_THROW(bad.Check(), InvalidArgument);
  EXPECT_THROW(CreateFeature2D(bad), InvalidArgument);
}

TEST(CreateFeature2DTest, DescriptorTypesMatchTheKind) {
  for (const DetectorKind kind : kAllKinds) {
    SCOPED_TRACE(ToString(kind));
    FeatureOptions options;
    options.kind = kind;
    cv::Ptr<cv::Feature2D> f = CreateFeature2D(options);
    ASSERT_TRUE(f);
    EXPECT_EQ(f->descriptorType() == CV_8U, IsBinaryDescriptor(kind));
    EXPECT_EQ(f->defaultNorm() == cv::NORM_HAMMING, IsBinaryDescriptor(kind));
  }
}

TEST(ExtractFeaturesTest, EveryKindCapsSortsAndDescribes) {
  for (const DetectorKind kind : kAllKinds) {
    SCOPED_TRACE(ToString(kind));
    FeatureOptions options;
    options.kind = kind;
    options.max_keypoints = 150;
    const Features f = ExtractFeatures(TumColorImage(), options);
    EXPECT_EQ(f.keypoints.size(), 150u);  // the image has far more than 150 of every kind
    ASSERT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
    EXPECT_EQ(f.descriptors.type(), IsBinaryDescriptor(kind) ? CV_8U : CV_32F);
    for (size_t i = 1; i < f.keypoints.size(); ++i) {
      EXPECT_GE(f.keypoints[i - 1].response, f.keypoints[i].response);
    }
    for (const cv::KeyPoint& kp : f.keypoints) {
      EXPECT_TRUE(kp.pt.x >= 0.f && kp.pt.x < 640.f && kp.pt.y >= 0.f && kp.pt.y < 480.f);
    }
  }
}

TEST(ExtractFeaturesTest, EveryKindDetectsOnlyInsideTheMaskAndKeepsItsCap) {
  // A disc of radius 200 px about the centre (as a fisheye's field of view), for every kind and
  // ORB split over two tasks too: every keypoint inside (to the pixel the mask is read at), and
  // still the cap, taken from inside.
  cv::Mat mask = cv::Mat::zeros(480, 640, CV_8U);
  cv::circle(mask, cv::Point(320, 240), 200, cv::Scalar(255), cv::FILLED);
  std::vector<FeatureOptions> all;
  for (const DetectorKind kind : kAllKinds) {
    all.emplace_back();
    all.back().kind = kind;
  }
  all.push_back(all[2]);
  ASSERT_EQ(all.back().kind, DetectorKind::kOrb);
  all.back().threads = 2;
  for (FeatureOptions& options : all) {
    SCOPED_TRACE(ToString(options.kind) + " threads " + std::to_string(options.threads));
    options.max_keypoints = 150;
    const Features f = ExtractFeatures(TumColorImage(), options, mask);
    EXPECT_EQ(f.keypoints.size(), 150u);
    ASSERT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
    for (const cv::KeyPoint& kp : f.keypoints) {
      // cv::KeyPointsFilter::runByPixelsMask reads the mask at the rounded-down position; the
      // deeper ORB levels at their own (coarser) pixels: within a level's pixel of the disc.
      EXPECT_LT(std::hypot(kp.pt.x - 320.0, kp.pt.y - 240.0), 200.0 + 4.0) << kp.pt;
    }
  }
  // A mask of another size or type is refused.
  FeatureOptions options;
  EXPECT_THROW(ExtractFeatures(TumColorImage(), options, cv::Mat::zeros(240, 320, CV_8U)),
               InvalidArgument);
  EXPECT_THROW(ExtractFeatures(TumColorImage(), options, cv::Mat::zeros(480, 640, CV_32F)),
               InvalidArgument);
}

TEST(ExtractFeaturesTest, GrayAndBgrGiveTheSameFeatures) {
  cv::Mat gray;
  cv::cvtColor(TumColorImage(), gray, cv::COLOR_BGR2GRAY);
  for (const DetectorKind kind : {DetectorKind::kSurf, DetectorKind::kFastBrief}) {
    FeatureOptions options;
    options.kind = kind;
    options.max_keypoints = 200;
    const Features a = ExtractFeatures(TumColorImage(), options);
    const Features b = ExtractFeatures(gray, options);
    ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
    EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_INF), 0.0);
  }
}

// AKAZE, BRISK and FAST+BRIEF cap after detection: the capped set is the strongest prefix of a
// larger cap.
TEST(ExtractFeaturesTest, CapKeepsTheStrongest) {
  for (const DetectorKind kind :
       {DetectorKind::kAkaze, DetectorKind::kBrisk, DetectorKind::kFastBrief}) {
    SCOPED_TRACE(ToString(kind));
    FeatureOptions options;
    options.kind = kind;
    options.max_keypoints = 400;
    const Features many = ExtractFeatures(TumColorImage(), options);
    options.max_keypoints = 50;
    const Features few = ExtractFeatures(TumColorImage(), options);
    ASSERT_EQ(few.keypoints.size(), 50u);
    ASSERT_GT(many.keypoints.size(), 50u);
    for (size_t i = 0; i < few.keypoints.size(); ++i) {
      EXPECT_EQ(few.keypoints[i].response, many.keypoints[i].response);
    }
    EXPECT_GE(few.keypoints.back().response, many.keypoints[50].response);
  }
}

TEST(ExtractFeaturesTest, RejectsEmptyAndNon8BitImages) {
  FeatureOptions options;
  EXPECT_THROW(ExtractFeatures(cv::Mat(), options), InvalidArgument);
  EXPECT_THROW(ExtractFeatures(cv::Mat(100, 100, CV_32F, cv::Scalar(0)), options), InvalidArgument);
  FeatureOptions bad;
  bad.max_keypoints = -1;
  EXPECT_THROW(ExtractFeatures(TumColorImage(), bad), InvalidArgument);
}

TEST(ExtractFeaturesTest, TinyImagesGiveNoFeaturesOrAnImumatchError) {
  for (const DetectorKind kind : kAllKinds) {
    for (const cv::Size size : {cv::Size(1, 1), cv::Size(7, 5), cv::Size(40, 30)}) {
      SCOPED_TRACE(ToString(kind) + " " + std::to_string(size.width));
      cv::Mat img(size, CV_8U);
      cv::randu(img, 0, 255);
      FeatureOptions options;
      options.kind = kind;
      if ((kind == DetectorKind::kSurf || kind == DetectorKind::kFastBrief) && size.width < 27) {
        // Our own code: no features (neither the 27-pixel SURF filters nor the 57-pixel BRIEF
        // patch fit), no error.
        const Features f = ExtractFeatures(img, options);
        EXPECT_TRUE(f.keypoints.empty());
        EXPECT_EQ(f.descriptors.rows, 0);
        continue;
      }
      try {
        const Features f = ExtractFeatures(img, options);
        EXPECT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
      } catch (const InvalidArgument&) {
        // acceptable: OpenCV's assertion translated into a clear imumatch error
      }
    }
  }
}

TEST(ExtractFeaturesTest, FlatImageGivesNoFeatures) {
  for (const DetectorKind kind : kAllKinds) {
    SCOPED_TRACE(ToString(kind));
    FeatureOptions options;
    options.kind = kind;
    const Features f = ExtractFeatures(cv::Mat(120, 160, CV_8U, cv::Scalar(90)), options);
    EXPECT_TRUE(f.keypoints.empty());
    EXPECT_EQ(f.descriptors.rows, 0);
  }
}

}  // namespace
}  // namespace imumatch
