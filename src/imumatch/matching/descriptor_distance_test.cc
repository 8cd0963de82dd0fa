#include "imumatch/matching/descriptor_distance.h"

#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

TEST(DescriptorDistanceTest, HammingHandComputed) {
  // 32 bytes: a = all zeros, b has 0xFF in byte 0 (8 bits), 0x01 in byte 9 (1 bit), 0x0F in
  // byte 31 (4 bits) -> 13 bits differ.
  cv::Mat a = cv::Mat::zeros(1, 32, CV_8U), b = cv::Mat::zeros(1, 32, CV_8U);
  b.at<uint8_t>(0, 0) = 0xFF;
  b.at<uint8_t>(0, 9) = 0x01;
  b.at<uint8_t>(0, 31) = 0x0F;
  EXPECT_EQ(HammingDistance(a.ptr(), b.ptr(), 32), 13u);
  const DescriptorView va = DescriptorView::FromMat(a);
  EXPECT_EQ(va.norm, DescriptorNorm::kHamming);
  EXPECT_EQ(va.bytes, 32);
  EXPECT_EQ(va.dims(), 256);
  EXPECT_EQ(SelectCostFunction(DescriptorNorm::kHamming, 32)(a.ptr(), b.ptr(), 32), 13.0f);
  // All bits differ.
  cv::Mat c(1, 32, CV_8U, cv::Scalar(0xFF));
  EXPECT_EQ(HammingDistance(a.ptr(), c.ptr(), 32), 256u);
}

TEST(DescriptorDistanceTest, HammingMatchesOpenCvNormForSeveralLengths) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int bytes : {8, 16, 32, 48, 64, 488 / 8 * 8}) {
    const DescriptorCostFn fn = SelectCostFunction(DescriptorNorm::kHamming, bytes);
    for (int trial = 0; trial < 50; ++trial) {
      cv::Mat a(1, bytes, CV_8U), b(1, bytes, CV_8U);
      for (int k = 0; k < bytes; ++k) {
        a.at<uint8_t>(0, k) = static_cast<uint8_t>(byte(rng));
        b.at<uint8_t>(0, k) = static_cast<uint8_t>(byte(rng));
      }
      const double expected = cv::norm(a, b, cv::NORM_HAMMING);
      EXPECT_EQ(HammingDistance(a.ptr(), b.ptr(), bytes), static_cast<uint32_t>(expected));
      EXPECT_EQ(fn(a.ptr(), b.ptr(), bytes), static_cast<float>(expected)) << bytes;
    }
  }
}

TEST(DescriptorDistanceTest, L2HandComputedAndOpenCv) {
  // (1,2,3) vs (4,6,3): squared distance 9 + 16 = 25, distance 5.
  const float a3[3] = {1, 2, 3}, b3[3] = {4, 6, 3};
  EXPECT_FLOAT_EQ(L2DistanceSquared(a3, b3, 3), 25.0f);
  EXPECT_FLOAT_EQ(CostToDistance(DescriptorNorm::kL2, 25.0f), 5.0f);
  EXPECT_FLOAT_EQ(DistanceToCost(DescriptorNorm::kL2, 5.0f), 25.0f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 100.0f);
  for (int dims : {3, 64, 128, 130}) {
    const DescriptorCostFn fn = SelectCostFunction(DescriptorNorm::kL2, dims * 4);
    cv::Mat a(1, dims, CV_32F), b(1, dims, CV_32F);
    for (int k = 0; k < dims; ++k) {
      a.at<float>(0, k) = u(rng);
      b.at<float>(0, k) = u(rng);
    }
    const double expected = cv::norm(a, b, cv::NORM_L2SQR);
    EXPECT_NEAR(fn(a.ptr(), b.ptr(), dims * 4), expected, 1e-4 * expected) << dims;
    EXPECT_NEAR(L2DistanceSquared(a.ptr<float>(), b.ptr<float>(), dims), expected, 1e-4 * expected);
    EXPECT_EQ(DescriptorView::FromMat(a).norm, DescriptorNorm::kL2);
    EXPECT_EQ(DescriptorView::FromMat(a).dims(), dims);
  }
}

// The gather form (one query against rows picked by slot) gives the per-pair function's values bit
// for bit, and OpenCV's norms, for every supported length (binary 32, AKAZE's 61 padded to 64, 64
// bytes and others; float 64 and 128 dimensions), with repeated and out-of-order slots.
TEST(DescriptorDistanceTest, GatherEqualsPerPairForEveryLength) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const std::vector<int> slots = {5, 0, 12, 12, 3, 19, 7};
  for (const int bytes : {8, 24, 32, 64, 488 / 8 * 8, 64 * 4, 128 * 4}) {
    for (const bool binary : {true, false}) {
      if (!binary && bytes < 64 * 4) continue;
      const DescriptorNorm norm = binary ? DescriptorNorm::kHamming : DescriptorNorm::kL2;
      const int type = binary ? CV_8U : CV_32F;
      const int cols = binary ? bytes : bytes / 4;
      cv::Mat rows(20, cols, type), query(1, cols, type);
      for (cv::Mat* m : {&rows, &query}) {
        for (int r = 0; r < m->rows; ++r) {
          for (int c = 0; c < cols; ++c) {
            if (binary) {
              m->at<uint8_t>(r, c) = static_cast<uint8_t>(byte(rng));
            } else {
              m->at<float>(r, c) = u(rng);
            }
          }
        }
      }
      const DescriptorCostFn pair = SelectCostFunction(norm, bytes);
      const DescriptorCostGatherFn gather = SelectCostGatherFunction(norm, bytes);
      std::vector<float> out(slots.size(), -1.0f);
      gather(query.ptr(), rows.ptr(), slots.data(), static_cast<int>(slots.size()), bytes,
             out.data());
      for (size_t j = 0; j < slots.size(); ++j) {
        const float expected = pair(query.ptr(), rows.ptr(slots[j]), bytes);
        EXPECT_EQ(out[j], expected) << bytes << " bytes, slot " << slots[j];
        const double cv_norm =
            cv::norm(query, rows.row(slots[j]), binary ? cv::NORM_HAMMING : cv::NORM_L2SQR);
        EXPECT_NEAR(out[j], cv_norm, binary ? 0.0 : 1e-4 * cv_norm);
      }
      // No rows: nothing written.
      gather(query.ptr(), rows.ptr(), slots.data(), 0, bytes, out.data());
    }
  }
}

TEST(DescriptorDistanceTest, ViewRejectsBadTypesAndMismatches) {
  EXPECT_THROW(DescriptorView::FromMat(cv::Mat::zeros(2, 12, CV_8U)), InvalidArgument);
  EXPECT_THROW(DescriptorView::FromMat(cv::Mat::zeros(2, 8, CV_64F)), InvalidArgument);
  EXPECT_THROW(DescriptorView::FromMat(cv::Mat::zeros(2, 8, CV_8UC3)), InvalidArgument);
  EXPECT_EQ(DescriptorView::FromMat(cv::Mat()).rows, 0);
  EXPECT_THROW(CheckCompatible(DescriptorView::FromMat(cv::Mat::zeros(2, 32, CV_8U)),
                               DescriptorView::FromMat(cv::Mat::zeros(2, 64, CV_8U))),
               InvalidArgument);
  EXPECT_THROW(CheckCompatible(DescriptorView::FromMat(cv::Mat::zeros(2, 32, CV_8U)),
                               DescriptorView::FromMat(cv::Mat::zeros(2, 8, CV_32F))),
               InvalidArgument);
  // A view of a non-contiguous ROI uses the parent's row step.
  cv::Mat big = cv::Mat::zeros(4, 64, CV_8U);
  big.at<uint8_t>(2, 0) = 0x03;
  const DescriptorView roi = DescriptorView::FromMat(big(cv::Rect(0, 0, 32, 4)));
  EXPECT_EQ(roi.step, 64u);
  EXPECT_EQ(HammingDistance(roi.Row(0), roi.Row(2), 32), 2u);
}

}  // namespace
}  // namespace imumatch
