#include "imumatch/features/orb_split.h"

#include <map>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "imumatch/core/error.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

cv::Mat TumGray() {
  const std::string path = testing::DataPath("tum_fr1_xyz_pair/img_prev.png");
  cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (m.empty()) throw std::runtime_error("cannot read " + path);
  return m;
}

TEST(OrbSplitTest, SplitLevelHoldsSixtyPercentOfTheCost) {
  // 8 levels of 1.2: pixel shares 0.325, 0.225, 0.156, ...; keypoint shares 0.217, 0.181, 0.151,
  // ...; mean 0.271, 0.203, 0.154: levels 0-1 hold 47 %, levels 0-2 63 %.
  EXPECT_EQ(OrbSplitLevel(1.2f, 8), 3);
  // 3 levels of 2: pixel shares 0.76, 0.19, 0.05, keypoint shares 0.57, 0.29, 0.14: level 0
  // holds 67 %.
  EXPECT_EQ(OrbSplitLevel(2.0f, 3), 1);
  EXPECT_EQ(OrbSplitLevel(1.2f, 2), 1);
  EXPECT_EQ(OrbSplitLevel(1.2f, 1), 1);
}

// Against cv::ORB with the same parameters on a real image: the levels below the split are the
// same keypoints with the same descriptors; the deeper ones nearly (their pyramid images may be a
// pixel narrower); per-octave counts as cv::ORB's.
TEST(OrbSplitTest, AgreesWithOpenCvOrbLevelByLevel) {
  const cv::Mat gray = TumGray();
  OrbSplitParams p;  // 1000, 1.2, 8, 20: the defaults of FeatureOptions
  std::vector<cv::KeyPoint> ref, split;
  cv::Mat ref_desc, split_desc;
  cv::ORB::create(p.max_keypoints, p.scale_factor, p.n_levels, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                  p.fast_threshold)
      ->detectAndCompute(gray, cv::noArray(), ref, ref_desc);
  DetectAndComputeOrbSplit(gray, p, &split, &split_desc);
  ASSERT_EQ(split_desc.rows, static_cast<int>(split.size()));
  ASSERT_EQ(split_desc.cols, 32);
  EXPECT_NEAR(static_cast<double>(split.size()), static_cast<double>(ref.size()), 10.0);
  std::map<int, int> ref_count, split_count;
  for (const auto& k : ref) ++ref_count[k.octave];
  for (const auto& k : split) ++split_count[k.octave];
  for (int o = 0; o < p.n_levels; ++o) {
    EXPECT_NEAR(split_count[o], ref_count[o], 2) << "octave " << o;
  }
  // Partners: same octave, position within 0.01 px below the split, within 1.5 px x the level's
  // scale above it.
  const int split_level = OrbSplitLevel(p.scale_factor, p.n_levels);
  int same_low = 0, low = 0, near_high = 0, high = 0, descriptor_ok = 0;
  for (int i = 0; i < static_cast<int>(ref.size()); ++i) {
    const cv::KeyPoint& r = ref[i];
    const bool below = r.octave < split_level;
    (below ? low : high)++;
    const float tolerance = below ? 0.01f : 1.5f * std::pow(p.scale_factor, r.octave);
    for (int j = 0; j < static_cast<int>(split.size()); ++j) {
      const cv::KeyPoint& s = split[j];
      if (s.octave != r.octave || cv::norm(s.pt - r.pt) > tolerance) continue;
      if (below) {
        ++same_low;
        descriptor_ok += cv::norm(ref_desc.row(i), split_desc.row(j), cv::NORM_HAMMING) == 0;
      } else {
        ++near_high;
        descriptor_ok += cv::norm(ref_desc.row(i), split_desc.row(j), cv::NORM_HAMMING) <= 64;
      }
      break;
    }
  }
  EXPECT_GE(same_low, low - 2);
  EXPECT_GE(near_high, 0.9 * high) << near_high << " of " << high;
  EXPECT_GE(descriptor_ok, 0.9 * (low + high));
}

TEST(OrbSplitTest, SameResultWithOneOrTwoThreadsAndThroughExtractFeatures) {
  const cv::Mat gray = TumGray();
  const int threads = cv::getNumThreads();
  std::vector<cv::KeyPoint> a, b;
  cv::Mat da, db;
  cv::setNumThreads(1);
  DetectAndComputeOrbSplit(gray, OrbSplitParams(), &a, &da);
  cv::setNumThreads(2);
  DetectAndComputeOrbSplit(gray, OrbSplitParams(), &b, &db);
  cv::setNumThreads(threads);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].pt, b[i].pt);
    EXPECT_EQ(a[i].octave, b[i].octave);
  }
  EXPECT_EQ(cv::norm(da, db, cv::NORM_HAMMING), 0.0);
  // ExtractFeatures with threads = 2: the same features, strongest first, capped.
  FeatureOptions o;
  o.threads = 2;
  const Features f = ExtractFeatures(gray, o);
  EXPECT_LE(static_cast<int>(f.keypoints.size()), o.max_keypoints);
  EXPECT_GE(static_cast<int>(f.keypoints.size()), o.max_keypoints * 95 / 100);
  for (size_t i = 1; i < f.keypoints.size(); ++i) {
    EXPECT_GE(f.keypoints[i - 1].response, f.keypoints[i].response);
  }
  o.threads = 0;
  EXPECT_THROW(o.Check(), InvalidArgument);
}

TEST(OrbSplitTest, RejectsBadInput) {
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  EXPECT_THROW(DetectAndComputeOrbSplit(cv::Mat(), OrbSplitParams(), &k, &d), InvalidArgument);
  EXPECT_THROW(DetectAndComputeOrbSplit(cv::Mat(10, 10, CV_32F), OrbSplitParams(), &k, &d),
               InvalidArgument);
  OrbSplitParams bad;
  bad.scale_factor = 1.0f;
  EXPECT_THROW(DetectAndComputeOrbSplit(TumGray(), bad, &k, &d), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
