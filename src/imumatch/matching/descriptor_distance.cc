#include "imumatch/matching/descriptor_distance.h"

#include "imumatch/core/error.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define IMUMATCH_X86 1
#else
#define IMUMATCH_X86 0
#endif

namespace imumatch {

DescriptorView DescriptorView::FromMat(const cv::Mat& descriptors) {
  DescriptorView v;
  if (descriptors.empty()) return v;
  IMUMATCH_CHECK(descriptors.dims == 2 && descriptors.channels() == 1,
                 "descriptors must be a single-channel 2-D matrix");
  if (descriptors.depth() == CV_8U) {
    IMUMATCH_CHECK(descriptors.cols % 8 == 0,
                   "binary descriptors must have a multiple of 8 bytes, got " << descriptors.cols);
    v.norm = DescriptorNorm::kHamming;
    v.bytes = descriptors.cols;
  } else if (descriptors.depth() == CV_32F) {
    v.norm = DescriptorNorm::kL2;
    v.bytes = descriptors.cols * 4;
  } else {
    IMUMATCH_CHECK(false, "descriptors must be CV_8U (binary) or CV_32F (float), got type "
                              << descriptors.type());
  }
  v.data = descriptors.data;
  v.rows = descriptors.rows;
  v.step = descriptors.step[0];
  return v;
}

void CheckCompatible(const DescriptorView& a, const DescriptorView& b) {
  if (a.rows == 0 || b.rows == 0) return;
  IMUMATCH_CHECK(a.norm == b.norm, "descriptor types differ (binary vs float)");
  IMUMATCH_CHECK(a.bytes == b.bytes,
                 "descriptor lengths differ: " << a.bytes << " vs " << b.bytes << " bytes");
}

namespace {

float HammingPortable(const uint8_t* a, const uint8_t* b, int bytes) {
  return static_cast<float>(HammingDistance(a, b, bytes));
}

[[maybe_unused]] float L2Portable(const uint8_t* a, const uint8_t* b, int bytes) {
  return L2DistanceSquared(reinterpret_cast<const float*>(a), reinterpret_cast<const float*>(b),
                           bytes / 4);
}

#if IMUMATCH_X86
// The same code compiled with the popcnt instruction enabled: HammingDistance() inlines here and
// __builtin_popcountll becomes one POPCNT per 64-bit word.
__attribute__((target("popcnt"))) float HammingPopcnt32(const uint8_t* a, const uint8_t* b, int) {
  return static_cast<float>(HammingDistance(a, b, 32));
}
__attribute__((target("popcnt"))) float HammingPopcnt64(const uint8_t* a, const uint8_t* b, int) {
  return static_cast<float>(HammingDistance(a, b, 64));
}
__attribute__((target("popcnt"))) float HammingPopcnt(const uint8_t* a, const uint8_t* b,
                                                      int bytes) {
  return static_cast<float>(HammingDistance(a, b, bytes));
}

// SSE2 is part of x86-64: four independent 4-lane accumulators.
float L2Sse2(const uint8_t* a8, const uint8_t* b8, int bytes) {
  const float* a = reinterpret_cast<const float*>(a8);
  const float* b = reinterpret_cast<const float*>(b8);
  const int n = bytes / 4;
  __m128 s0 = _mm_setzero_ps(), s1 = _mm_setzero_ps();
  int k = 0;
  for (; k + 8 <= n; k += 8) {
    const __m128 d0 = _mm_sub_ps(_mm_loadu_ps(a + k), _mm_loadu_ps(b + k));
    const __m128 d1 = _mm_sub_ps(_mm_loadu_ps(a + k + 4), _mm_loadu_ps(b + k + 4));
    s0 = _mm_add_ps(s0, _mm_mul_ps(d0, d0));
    s1 = _mm_add_ps(s1, _mm_mul_ps(d1, d1));
  }
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, _mm_add_ps(s0, s1));
  float sum = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; k < n; ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
  return sum;
}

__attribute__((target("avx2,fma"))) float L2Avx2(const uint8_t* a8, const uint8_t* b8, int bytes) {
  const float* a = reinterpret_cast<const float*>(a8);
  const float* b = reinterpret_cast<const float*>(b8);
  const int n = bytes / 4;
  __m256 s0 = _mm256_setzero_ps(), s1 = _mm256_setzero_ps();
  int k = 0;
  for (; k + 16 <= n; k += 16) {
    const __m256 d0 = _mm256_sub_ps(_mm256_loadu_ps(a + k), _mm256_loadu_ps(b + k));
    const __m256 d1 = _mm256_sub_ps(_mm256_loadu_ps(a + k + 8), _mm256_loadu_ps(b + k + 8));
    s0 = _mm256_fmadd_ps(d0, d0, s0);
    s1 = _mm256_fmadd_ps(d1, d1, s1);
  }
  const __m256 s = _mm256_add_ps(s0, s1);
  __m128 h = _mm_add_ps(_mm256_castps256_ps128(s), _mm256_extractf128_ps(s, 1));
  h = _mm_add_ps(h, _mm_movehl_ps(h, h));
  h = _mm_add_ss(h, _mm_shuffle_ps(h, h, 1));
  float sum = _mm_cvtss_f32(h);
  for (; k < n; ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
  return sum;
}

// Gather forms: the per-pair code above inlined into a loop over the slots (same target, so the
// same instructions and the same float results).
__attribute__((target("popcnt"))) void HammingPopcnt32Gather(const uint8_t* a, const uint8_t* rows,
                                                             const int* slots, int count, int,
                                                             float* out) {
  uint64_t q[4];
  std::memcpy(q, a, 32);
  for (int j = 0; j < count; ++j) {
    const uint8_t* b = rows + static_cast<size_t>(slots[j]) * 32;
    uint64_t r[4];
    std::memcpy(r, b, 32);
    out[j] =
        static_cast<float>(__builtin_popcountll(q[0] ^ r[0]) + __builtin_popcountll(q[1] ^ r[1]) +
                           __builtin_popcountll(q[2] ^ r[2]) + __builtin_popcountll(q[3] ^ r[3]));
  }
}
__attribute__((target("popcnt"))) void HammingPopcntGather(const uint8_t* a, const uint8_t* rows,
                                                           const int* slots, int count, int bytes,
                                                           float* out) {
  for (int j = 0; j < count; ++j) {
    out[j] =
        static_cast<float>(HammingDistance(a, rows + static_cast<size_t>(slots[j]) * bytes, bytes));
  }
}
void L2Sse2Gather(const uint8_t* a, const uint8_t* rows, const int* slots, int count, int bytes,
                  float* out) {
  for (int j = 0; j < count; ++j) {
    out[j] = L2Sse2(a, rows + static_cast<size_t>(slots[j]) * bytes, bytes);
  }
}
__attribute__((target("avx2,fma"))) void L2Avx2Gather(const uint8_t* a, const uint8_t* rows,
                                                      const int* slots, int count, int bytes,
                                                      float* out) {
  for (int j = 0; j < count; ++j) {
    out[j] = L2Avx2(a, rows + static_cast<size_t>(slots[j]) * bytes, bytes);
  }
}

bool HasPopcnt() { return __builtin_cpu_supports("popcnt"); }
bool HasAvx2Fma() { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"); }
#endif

}  // namespace

namespace {
[[maybe_unused]] void HammingPortableGather(const uint8_t* a, const uint8_t* rows, const int* slots,
                                            int count, int bytes, float* out) {
  for (int j = 0; j < count; ++j) {
    out[j] = HammingPortable(a, rows + static_cast<size_t>(slots[j]) * bytes, bytes);
  }
}
[[maybe_unused]] void L2PortableGather(const uint8_t* a, const uint8_t* rows, const int* slots,
                                       int count, int bytes, float* out) {
  for (int j = 0; j < count; ++j) {
    out[j] = L2Portable(a, rows + static_cast<size_t>(slots[j]) * bytes, bytes);
  }
}
}  // namespace

DescriptorCostGatherFn SelectCostGatherFunction(DescriptorNorm norm, int bytes) {
#if IMUMATCH_X86
  if (norm == DescriptorNorm::kHamming) {
    if (!HasPopcnt()) return &HammingPortableGather;
    if (bytes == 32) return &HammingPopcnt32Gather;
    return &HammingPopcntGather;
  }
  return HasAvx2Fma() ? &L2Avx2Gather : &L2Sse2Gather;
#else
  (void)bytes;
  return norm == DescriptorNorm::kHamming ? &HammingPortableGather : &L2PortableGather;
#endif
}

DescriptorCostFn SelectCostFunction(DescriptorNorm norm, int bytes) {
#if IMUMATCH_X86
  if (norm == DescriptorNorm::kHamming) {
    if (!HasPopcnt()) return &HammingPortable;
    if (bytes == 32) return &HammingPopcnt32;
    if (bytes == 64) return &HammingPopcnt64;
    return &HammingPopcnt;
  }
  return HasAvx2Fma() ? &L2Avx2 : &L2Sse2;
#else
  (void)bytes;
  return norm == DescriptorNorm::kHamming ? &HammingPortable : &L2Portable;
#endif
}

const char* DescriptorKernelName(DescriptorNorm norm) {
#if IMUMATCH_X86
  if (norm == DescriptorNorm::kHamming) return HasPopcnt() ? "popcnt" : "portable";
  return HasAvx2Fma() ? "avx2+fma" : "sse2";
#else
  (void)norm;
  return "portable";
#endif
}

cv::Mat PadBinaryDescriptors(const cv::Mat& descriptors) {
  if (descriptors.empty() || descriptors.type() != CV_8UC1 || descriptors.cols % 8 == 0) {
    return descriptors;
  }
  const int cols = (descriptors.cols + 7) / 8 * 8;
  cv::Mat padded = cv::Mat::zeros(descriptors.rows, cols, CV_8UC1);
  descriptors.copyTo(padded(cv::Rect(0, 0, descriptors.cols, descriptors.rows)));
  return padded;
}

}  // namespace imumatch
