#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include <opencv2/core.hpp>

namespace imumatch {

// How two descriptors are compared: Hamming (binary descriptors: ORB, BRIEF, BRISK, AKAZE-MLDB,
// stored as CV_8U rows whose byte count is a multiple of 8) or L2 (float descriptors: SIFT, SURF,
// CV_32F rows).
enum class DescriptorNorm { kHamming, kL2 };

// A non-owning view of a descriptor matrix (one descriptor per row). The cv::Mat it was made from
// must outlive the view.
struct DescriptorView {
  const uint8_t* data = nullptr;
  int rows = 0;
  int bytes = 0;    // bytes per descriptor (32 for ORB, 512 for SIFT-128 as float)
  size_t step = 0;  // bytes between rows
  DescriptorNorm norm = DescriptorNorm::kHamming;

  const uint8_t* Row(int i) const { return data + static_cast<size_t>(i) * step; }
  int dims() const { return norm == DescriptorNorm::kHamming ? bytes * 8 : bytes / 4; }

  // CV_8U -> Hamming (the row length must be a multiple of 8 bytes), CV_32F -> L2; single channel.
  // An empty Mat gives an empty view. Throws InvalidArgument for any other type.
  static DescriptorView FromMat(const cv::Mat& descriptors);
};

// Throws InvalidArgument unless both views have the same norm and row length (empty views pass).
void CheckCompatible(const DescriptorView& a, const DescriptorView& b);

// Portable reference implementations (any byte count that is a multiple of 8 / any dimension).
// Hamming: number of differing bits. L2: sum of squared differences.
// always_inline so that callers compiled with target("popcnt") get the POPCNT instruction.
__attribute__((always_inline)) inline uint32_t HammingDistance(const uint8_t* a, const uint8_t* b,
                                                               int bytes) {
  uint32_t sum = 0;
  for (int k = 0; k < bytes; k += 8) {
    uint64_t x, y;
    std::memcpy(&x, a + k, 8);
    std::memcpy(&y, b + k, 8);
    sum += static_cast<uint32_t>(__builtin_popcountll(x ^ y));
  }
  return sum;
}

inline float L2DistanceSquared(const float* a, const float* b, int dims) {
  float sum = 0.0f;
  for (int k = 0; k < dims; ++k) {
    const float d = a[k] - b[k];
    sum += d * d;
  }
  return sum;
}

// The "cost" of a descriptor pair used internally by the matchers: the Hamming distance or the
// SQUARED L2 distance (monotone in the distance, no sqrt in the inner loop). Selected once per
// matcher call: popcnt / AVX2+FMA versions run only when the CPU reports them at run time
// (__builtin_cpu_supports); otherwise portable code runs. Nothing here needs -march flags.
using DescriptorCostFn = float (*)(const uint8_t* a, const uint8_t* b, int bytes);
DescriptorCostFn SelectCostFunction(DescriptorNorm norm, int bytes);
// One query against several rows of a packed array (row s at rows + s * bytes): out[j] = the cost
// of a against row slots[j], for j < count. The guided matcher's window candidates in one call:
// the query is loaded once and no call is made per pair. Same values, bit for bit, as the function
// SelectCostFunction returns for the same norm and length.
using DescriptorCostGatherFn = void (*)(const uint8_t* a, const uint8_t* rows, const int* slots,
                                        int count, int bytes, float* out);
DescriptorCostGatherFn SelectCostGatherFunction(DescriptorNorm norm, int bytes);

// Cost <-> distance as reported (and as OpenCV reports it): identity for Hamming, sqrt for L2.
inline float CostToDistance(DescriptorNorm norm, float cost) {
  return norm == DescriptorNorm::kL2 ? std::sqrt(cost) : cost;
}
inline float DistanceToCost(DescriptorNorm norm, float distance) {
  return norm == DescriptorNorm::kL2 ? distance * distance : distance;
}

// Which of the run-time accelerated kernels this CPU uses ("popcnt", "avx2+fma", "portable"),
// for benchmark reports.
const char* DescriptorKernelName(DescriptorNorm norm);

// Adapter: DescriptorView needs binary descriptors whose row length is a multiple of 8 bytes, but
// AKAZE's MLDB has 61. Pads CV_8U rows with zero bytes up to the next multiple of 8 (Hamming
// distances are unchanged); other matrices are returned as they are.
cv::Mat PadBinaryDescriptors(const cv::Mat& descriptors);

}  // namespace imumatch
