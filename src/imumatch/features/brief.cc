#include "imumatch/features/brief.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/features/image_util.h"

namespace imumatch {
namespace {

// Standard normal samples by Box-Muller from std::mt19937, whose output sequence is fixed by the
// C++ standard (std::normal_distribution is not).
class NormalSource {
 public:
  explicit NormalSource(uint32_t seed) : engine_(seed) {}
  double Next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    // Uniforms in (0, 1): never 0, so the logarithm is finite.
    const double u1 = (static_cast<double>(engine_()) + 0.5) / 4294967296.0;
    const double u2 = (static_cast<double>(engine_()) + 0.5) / 4294967296.0;
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double phase = 2.0 * kPi * u2;
    spare_ = radius * std::sin(phase);
    has_spare_ = true;
    return radius * std::cos(phase);
  }

 private:
  std::mt19937 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace

const std::array<BriefTest, 256>& BriefPattern() {
  static const std::array<BriefTest, 256> pattern = [] {
    std::array<BriefTest, 256> tests{};
    NormalSource normal(20100905u);
    const double sigma = Brief::kPatchSize / 5.0;  // sigma^2 = S^2 / 25
    const int limit = Brief::kPatchSize / 2 - 1;   // 23
    const auto draw = [&]() {
      const long v = std::lround(normal.Next() * sigma);
      return static_cast<int8_t>(std::clamp<long>(v, -limit, limit));
    };
    for (BriefTest& t : tests) {
      t.x1 = draw();
      t.y1 = draw();
      t.x2 = draw();
      t.y2 = draw();
    }
    return tests;
  }();
  return pattern;
}

cv::Ptr<Brief> Brief::Create() { return cv::makePtr<Brief>(); }

void Brief::detectAndCompute(cv::InputArray image, cv::InputArray /*mask*/,
                             std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                             bool useProvidedKeypoints) {
  if (!useProvidedKeypoints) {
    throw InvalidArgument(
        "Brief is a descriptor extractor only: use compute() with keypoints from a detector");
  }
  const cv::Mat gray = ToGray8(image.getMat(), "Brief");
  cv::KeyPointsFilter::runByImageBorder(keypoints, gray.size(), kBorder);
  // (Non-finite positions are removed too: Rect::contains is false for NaN.)
  const int n = static_cast<int>(keypoints.size());
  if (!descriptors.needed()) return;
  if (n == 0) {
    descriptors.release();
    return;
  }
  cv::Mat sum;
  // Entries may wrap around for huge images; box sums are taken modulo 2^32, which is exact.
  cv::integral(gray, sum, CV_32S);
  descriptors.create(n, 32, CV_8U);
  cv::Mat desc = descriptors.getMat();
  const std::array<BriefTest, 256>& pattern = BriefPattern();
  constexpr int kHalf = kKernelSize / 2;
  const auto smoothed = [&sum](int x, int y) {
    const uint32_t* r0 = sum.ptr<uint32_t>(y - kHalf);
    const uint32_t* r1 = sum.ptr<uint32_t>(y + kHalf + 1);
    return r1[x + kHalf + 1] - r1[x - kHalf] - r0[x + kHalf + 1] + r0[x - kHalf];
  };
  for (int k = 0; k < n; ++k) {
    const int x = cvRound(keypoints[k].pt.x);
    const int y = cvRound(keypoints[k].pt.y);
    uint8_t* out = desc.ptr<uint8_t>(k);
    for (int byte = 0; byte < 32; ++byte) {
      uint8_t value = 0;
      for (int bit = 0; bit < 8; ++bit) {
        const BriefTest& t = pattern[byte * 8 + bit];
        if (smoothed(x + t.x1, y + t.y1) < smoothed(x + t.x2, y + t.y2)) {
          value |= static_cast<uint8_t>(1u << bit);
        }
      }
      out[byte] = value;
    }
  }
}

}  // namespace imumatch
