#include "imumatch/matching/baseline_matchers.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

cv::Mat RandomBinary(int rows, int bytes, std::mt19937& rng) {
  cv::Mat m(rows, bytes, CV_8U);
  cv::randu(m, 0, 256);
  (void)rng;
  return m;
}

// B = A's rows with a few flipped bits, shuffled, plus random rows.
void MakeBinaryPair(int n, int extra, int bytes, uint64_t seed, cv::Mat& a, cv::Mat& b) {
  cv::RNG cv_rng(seed);
  cv::theRNG() = cv_rng;
  std::mt19937 rng(static_cast<uint32_t>(seed));
  a = RandomBinary(n, bytes, rng);
  b = RandomBinary(n + extra, bytes, rng);
  std::uniform_int_distribution<int> bit(0, bytes * 8 - 1);
  for (int i = 0; i < n; ++i) {
    a.row(i).copyTo(b.row(n + extra - 1 - i));
    for (int f = 0; f < 10; ++f) {
      const int k = bit(rng);
      b.at<uint8_t>(n + extra - 1 - i, k / 8) ^= static_cast<uint8_t>(1u << (k % 8));
    }
  }
}

void ExpectSameNearest(const std::vector<Match>& ours, const std::vector<cv::DMatch>& cv_matches,
                       const cv::Mat& a, const cv::Mat& b, int norm) {
  ASSERT_EQ(ours.size(), cv_matches.size());
  int same_index = 0;
  for (size_t i = 0; i < ours.size(); ++i) {
    EXPECT_EQ(ours[i].query_idx, cv_matches[i].queryIdx);
    EXPECT_NEAR(ours[i].distance, cv_matches[i].distance, 1e-3 * (1.0f + ours[i].distance));
    // Indices may differ only on exact ties: then both are at the same distance.
    if (ours[i].train_idx == cv_matches[i].trainIdx) {
      ++same_index;
    } else {
      EXPECT_NEAR(cv::norm(a.row(ours[i].query_idx), b.row(ours[i].train_idx), norm),
                  cv::norm(a.row(ours[i].query_idx), b.row(cv_matches[i].trainIdx), norm), 1e-2);
    }
  }
  EXPECT_GT(same_index, static_cast<int>(ours.size()) * 9 / 10);
}

// Every path this CPU can run gives the scalar path's matches bit for bit: indices, distances and
// second distances, with and without the ratio test and cross check.
void ExpectAllKernelsEqual(const cv::Mat& a, const cv::Mat& b, const std::string& what) {
  const std::vector<BruteForceKernel> kernels = AvailableBruteForceKernels();
  ASSERT_EQ(kernels.front(), BruteForceKernel::kScalar);
  for (const double ratio : {1.0, 0.8}) {
    for (const bool cross : {false, true}) {
      BruteForceOptions o;
      o.ratio = ratio;
      o.cross_check = cross;
      o.kernel = BruteForceKernel::kScalar;
      const std::vector<Match> reference = MatchBruteForce(a, b, o);
      if (ratio == 1.0 && !cross) {
        ASSERT_EQ(reference.size(), static_cast<size_t>(a.rows)) << what;
      }
      for (BruteForceKernel k : kernels) {
        o.kernel = k;
        const std::vector<Match> got = MatchBruteForce(a, b, o);
        ASSERT_EQ(got.size(), reference.size()) << what << " " << ToString(k);
        for (size_t i = 0; i < got.size(); ++i) {
          ASSERT_EQ(got[i].query_idx, reference[i].query_idx) << what << " " << ToString(k);
          ASSERT_EQ(got[i].train_idx, reference[i].train_idx) << what << " " << ToString(k);
          ASSERT_EQ(got[i].distance, reference[i].distance) << what << " " << ToString(k);
          ASSERT_EQ(got[i].second_distance, reference[i].second_distance)
              << what << " " << ToString(k);
        }
      }
    }
  }
}

TEST(BaselineMatchersTest, EveryKernelEqualsTheScalarPathBitForBit) {
  std::printf("brute-force paths on this CPU (%s):", CpuFeaturesString().c_str());
  for (BruteForceKernel k : AvailableBruteForceKernels()) std::printf(" %s", ToString(k));
  std::printf("\n");
  // Binary: 32 (ORB, BRIEF), 61 padded to 64 (AKAZE), 64 bytes (BRISK); row counts that are not
  // multiples of any block or lane count; duplicate rows make exact ties.
  for (int bytes : {32, 61, 64}) {
    cv::Mat a, b;
    MakeBinaryPair(203, 150, bytes, 5 + bytes, a, b);
    if (bytes == 61) {
      cv::Mat pa = cv::Mat::zeros(a.rows, 64, CV_8U), pb = cv::Mat::zeros(b.rows, 64, CV_8U);
      a.copyTo(pa(cv::Rect(0, 0, 61, a.rows)));
      b.copyTo(pb(cv::Rect(0, 0, 61, b.rows)));
      a = pa;
      b = pb;
    }
    b.row(3).copyTo(b.row(7));  // a tie at the same distance from every query
    ExpectAllKernelsEqual(a, b, std::to_string(bytes) + " bytes");
    ExpectAllKernelsEqual(a.rowRange(0, 1), b.rowRange(0, 9), "1 x 9");
  }
  // Float: 64 (SURF) and 128 (SIFT) dims, and 70 (a tail after the last 16).
  cv::RNG rng(11);
  for (int dims : {64, 128, 70}) {
    cv::Mat a(157, dims, CV_32F), b(131, dims, CV_32F);
    rng.fill(a, cv::RNG::UNIFORM, 0.0, 1.0);
    rng.fill(b, cv::RNG::UNIFORM, 0.0, 1.0);
    a.row(4).copyTo(b.row(9));
    b.row(9).copyTo(b.row(20));  // an exact tie
    // NaN in train rows: their distances are NaN, which no path may keep as best or second.
    b.row(30).setTo(std::numeric_limits<float>::quiet_NaN());
    b.at<float>(31, dims - 1) = std::numeric_limits<float>::quiet_NaN();
    ExpectAllKernelsEqual(a, b, std::to_string(dims) + " floats");
  }
}

TEST(BaselineMatchersTest, AKernelTheCpuLacksIsRefused) {
  const auto kernels = AvailableBruteForceKernels();
  for (BruteForceKernel k :
       {BruteForceKernel::kPopcnt, BruteForceKernel::kAvx2, BruteForceKernel::kAvx512}) {
    if (std::find(kernels.begin(), kernels.end(), k) != kernels.end()) continue;
    BruteForceOptions o;
    o.kernel = k;
    EXPECT_THROW(MatchBruteForce(cv::Mat::zeros(2, 32, CV_8U), cv::Mat::zeros(2, 32, CV_8U), o),
                 InvalidArgument);
  }
}

TEST(BaselineMatchersTest, OwnBruteForceEqualsOpenCvForBinary) {
  for (int bytes : {32, 64, 16}) {
    cv::Mat a, b;
    MakeBinaryPair(203, 150, bytes, 17 + bytes, a, b);  // 203: not a multiple of the query block
    cv::BFMatcher bf(cv::NORM_HAMMING);
    std::vector<cv::DMatch> expected;
    bf.match(a, b, expected);
    ExpectSameNearest(MatchBruteForce(a, b, BruteForceOptions()), expected, a, b, cv::NORM_HAMMING);
    // Second neighbour = OpenCV's knn k=2.
    std::vector<std::vector<cv::DMatch>> knn;
    bf.knnMatch(a, b, knn, 2);
    const std::vector<Match> ours = MatchBruteForce(a, b, BruteForceOptions());
    for (size_t i = 0; i < ours.size(); ++i) EXPECT_EQ(ours[i].second_distance, knn[i][1].distance);
  }
}

TEST(BaselineMatchersTest, OwnBruteForceEqualsOpenCvForFloat) {
  cv::theRNG() = cv::RNG(5);
  for (int dims : {128, 64, 36}) {
    cv::Mat a(157, dims, CV_32F), b(301, dims, CV_32F);
    cv::randu(a, 0.0f, 100.0f);
    cv::randu(b, 0.0f, 100.0f);
    cv::BFMatcher bf(cv::NORM_L2);
    std::vector<cv::DMatch> expected;
    bf.match(a, b, expected);
    ExpectSameNearest(MatchBruteForce(a, b, BruteForceOptions()), expected, a, b, cv::NORM_L2);
  }
}

TEST(BaselineMatchersTest, RatioCrossCheckAndOpenCvWrappersAgree) {
  cv::Mat a, b;
  MakeBinaryPair(300, 300, 32, 99, a, b);
  BruteForceOptions ratio;
  ratio.ratio = 0.8;
  const std::vector<Match> ours = MatchBruteForce(a, b, ratio);
  const std::vector<Match> knn = MatchOpenCvKnnRatio(a, b, 0.8);
  ASSERT_EQ(ours.size(), knn.size());
  for (size_t k = 0; k < ours.size(); ++k) {
    EXPECT_EQ(ours[k].query_idx, knn[k].query_idx);
    EXPECT_EQ(ours[k].distance, knn[k].distance);
  }
  // Every planted pair (10 flipped bits vs ~128 for random rows) passes the ratio test.
  EXPECT_EQ(static_cast<int>(ours.size()), 300);
  for (const Match& m : ours) EXPECT_EQ(m.train_idx, 600 - 1 - m.query_idx);
  BruteForceOptions cross;
  cross.cross_check = true;
  const std::vector<Match> ours_cc = MatchBruteForce(a, b, cross);
  const std::vector<Match> cv_cc = MatchOpenCvCrossCheck(a, b);
  ASSERT_EQ(ours_cc.size(), cv_cc.size());
  for (size_t k = 0; k < ours_cc.size(); ++k) {
    EXPECT_EQ(ours_cc[k].query_idx, cv_cc[k].query_idx);
    EXPECT_EQ(ours_cc[k].train_idx, cv_cc[k].train_idx);
  }
  BruteForceOptions tight;
  tight.max_distance = 5.0;  // below the 10 flipped bits
  EXPECT_TRUE(MatchBruteForce(a, b, tight).empty());
  EXPECT_EQ(MatchOpenCvBruteForce(a, b).size(), 300u);
  // FLANN LSH is approximate: it still finds most planted pairs, and only correct ones.
  const std::vector<Match> lsh = MatchFlannLsh(a, b, FlannLshOptions());
  int correct = 0;
  for (const Match& m : lsh) correct += m.train_idx == 600 - 1 - m.query_idx;
  EXPECT_GE(correct, 200);
  EXPECT_GE(correct, static_cast<int>(lsh.size()) - 3);
  EXPECT_THROW(
      MatchFlannLsh(cv::Mat::zeros(3, 8, CV_32F), cv::Mat::zeros(3, 8, CV_32F), FlannLshOptions()),
      InvalidArgument);
  EXPECT_THROW(MatchBruteForce(a, cv::Mat::zeros(3, 64, CV_8U), BruteForceOptions()),
               InvalidArgument);
  EXPECT_TRUE(MatchBruteForce(a, cv::Mat(), BruteForceOptions()).empty());
}

}  // namespace
}  // namespace imumatch
