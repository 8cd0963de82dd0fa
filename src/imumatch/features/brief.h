#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "imumatch/features/strict_feature2d.h"

namespace imumatch {

// One BRIEF binary test: compare the smoothed intensities at p = (x1, y1) and q = (x2, y2),
// offsets in pixels from the keypoint (x right, y down).
struct BriefTest {
  int8_t x1, y1, x2, y2;
};

// The fixed sampling pattern of Brief: 256 point pairs, pattern "G II" of Calonder et al. (ECCV
// 2010): every coordinate drawn i.i.d. from an isotropic Gaussian N(0, S^2/25) with patch size
// S = 48 (sigma = 9.6 px), rounded to the nearest integer and clipped to [-23, 23] so both points
// stay inside the 48 x 48 patch. Drawn with std::mt19937 seeded with 20100905 and Box-Muller
// (implemented here, so the pattern does not depend on the standard library's distributions), in
// the order x1, y1, x2, y2 for test 0, 1, ... 255.
const std::array<BriefTest, 256>& BriefPattern();

// BRIEF descriptor (Calonder, Lepetit, Strecha, Fua, "BRIEF: Binary Robust Independent Elementary
// Features", ECCV 2010): 256 tests (32 bytes) on the image smoothed by a 9 x 9 box filter
// (computed from an integral image), bit k = (test k % 8 of byte k / 8) = I(p) < I(q).
// Not rotation or scale invariant: kp.angle and kp.size are ignored.
//
// A descriptor extractor only: detect() (and detectAndCompute without provided keypoints) throws
// InvalidArgument. compute() removes keypoints closer than 28 px (patch half-size 24 + box
// half-size 4) to the image border, exactly like OpenCV's xfeatures2d BriefDescriptorExtractor
// (cv::KeyPointsFilter::runByImageBorder with border 28).
class Brief : public StrictFeature2D {  // detect()/compute() throw on empty images
 public:
  static constexpr int kPatchSize = 48;
  static constexpr int kKernelSize = 9;
  static constexpr int kBorder = kPatchSize / 2 + kKernelSize / 2;  // 28

  static cv::Ptr<Brief> Create();

  void detectAndCompute(cv::InputArray image, cv::InputArray mask,
                        std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                        bool useProvidedKeypoints = false) override;

  int descriptorSize() const override { return 32; }
  int descriptorType() const override { return CV_8U; }
  int defaultNorm() const override { return cv::NORM_HAMMING; }
  cv::String getDefaultName() const override { return "imumatch.BRIEF"; }
};

}  // namespace imumatch
