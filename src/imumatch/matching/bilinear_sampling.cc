#include "imumatch/matching/bilinear_sampling.h"

#include <cmath>

#include "imumatch/core/error.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define IMUMATCH_BS_X86 1
#else
#define IMUMATCH_BS_X86 0
#endif

namespace imumatch {
namespace {

inline float SampleOne(const uint8_t* data, size_t step, float x, float y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const uint8_t* r0 = data + static_cast<size_t>(y0) * step + x0;
  const uint8_t* r1 = r0 + step;
  const float top = r0[0] + fx * (static_cast<float>(r0[1]) - r0[0]);
  const float bottom = r1[0] + fx * (static_cast<float>(r1[1]) - r1[0]);
  return top + fy * (bottom - top);
}

struct GridWeights {
  int x0, y0;
  float w00, w01, w10, w11;
};
inline GridWeights WeightsAt(float x, float y) {
  GridWeights g;
  g.x0 = static_cast<int>(std::floor(x));
  g.y0 = static_cast<int>(std::floor(y));
  const float fx = x - static_cast<float>(g.x0), fy = y - static_cast<float>(g.y0);
  g.w00 = (1.0f - fx) * (1.0f - fy);
  g.w01 = fx * (1.0f - fy);
  g.w10 = (1.0f - fx) * fy;
  g.w11 = fx * fy;
  return g;
}

void SampleGridPortable(const uint8_t* data, size_t step, float x, float y, int w, int h,
                        float* out) {
  const GridWeights g = WeightsAt(x, y);
  for (int r = 0; r < h; ++r) {
    const uint8_t* p = data + static_cast<size_t>(g.y0 + r) * step + g.x0;
    const uint8_t* q = p + step;
    float* o = out + static_cast<size_t>(r) * w;
    for (int c = 0; c < w; ++c) {
      o[c] = g.w00 * p[c] + g.w01 * p[c + 1] + g.w10 * q[c] + g.w11 * q[c + 1];
    }
  }
}

void SamplePointsPortable(const uint8_t* data, size_t step, int, const float* xs, const float* ys,
                          int n, float* out) {
  for (int i = 0; i < n; ++i) out[i] = SampleOne(data, step, xs[i], ys[i]);
}

#if IMUMATCH_BS_X86
// Eight samples of a row from bytes p[c .. c + 8] and q[c .. c + 8]: two 8-byte loads per row (no
// byte beyond p[c + 8] is read), widened to floats, then the portable expression's products and
// sums in its order (mul, add; no FMA: the same floats).
__attribute__((target("avx2"))) inline __m256 Widen8(const uint8_t* s) {
  return _mm256_cvtepi32_ps(
      _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(s))));
}
__attribute__((target("avx2"))) inline __m256 GridBlock8(const uint8_t* p, const uint8_t* q,
                                                         __m256 w00, __m256 w01, __m256 w10,
                                                         __m256 w11) {
  __m256 v = _mm256_mul_ps(w00, Widen8(p));
  v = _mm256_add_ps(v, _mm256_mul_ps(w01, Widen8(p + 1)));
  v = _mm256_add_ps(v, _mm256_mul_ps(w10, Widen8(q)));
  return _mm256_add_ps(v, _mm256_mul_ps(w11, Widen8(q + 1)));
}

__attribute__((target("avx2"))) void SampleGridAvx2(const uint8_t* data, size_t step, float x,
                                                    float y, int w, int h, float* out) {
  if (w < 8) {
    SampleGridPortable(data, step, x, y, w, h, out);
    return;
  }
  const GridWeights g = WeightsAt(x, y);
  const __m256 w00 = _mm256_set1_ps(g.w00), w01 = _mm256_set1_ps(g.w01);
  const __m256 w10 = _mm256_set1_ps(g.w10), w11 = _mm256_set1_ps(g.w11);
  for (int r = 0; r < h; ++r) {
    const uint8_t* p = data + static_cast<size_t>(g.y0 + r) * step + g.x0;
    const uint8_t* q = p + step;
    float* o = out + static_cast<size_t>(r) * w;
    int c = 0;
    for (; c + 8 <= w; c += 8)
      _mm256_storeu_ps(o + c, GridBlock8(p + c, q + c, w00, w01, w10, w11));
    // The tail as the last eight samples (recomputes a few: the same values).
    if (c < w) {
      c = w - 8;
      _mm256_storeu_ps(o + c, GridBlock8(p + c, q + c, w00, w01, w10, w11));
    }
  }
}

// Eight arbitrary points per step: the four neighbours by two 32-bit gathers at byte addresses,
// the upper row's at (x0 - 2) so that no gather reads past the sample's own last byte in the
// image's last row (the lower row's reach ends in the following row, which exists).
__attribute__((target("avx2"))) void SamplePointsAvx2(const uint8_t* data, size_t step, int rows,
                                                      const float* xs, const float* ys, int n,
                                                      float* out) {
  int i = 0;
  // Byte offsets must fit an int32 gather index.
  if (static_cast<double>(step) * rows < 2.0e9) {
    const __m256i vstep = _mm256_set1_epi32(static_cast<int>(step));
    const __m256i low_byte = _mm256_set1_epi32(0xff);
    const int* base = reinterpret_cast<const int*>(data);
    for (; i + 8 <= n; i += 8) {
      const __m256 x = _mm256_loadu_ps(xs + i), y = _mm256_loadu_ps(ys + i);
      const __m256i x0 = _mm256_cvttps_epi32(x), y0 = _mm256_cvttps_epi32(y);
      const __m256 fx = _mm256_sub_ps(x, _mm256_cvtepi32_ps(x0));
      const __m256 fy = _mm256_sub_ps(y, _mm256_cvtepi32_ps(y0));
      const __m256i off0 = _mm256_add_epi32(_mm256_mullo_epi32(y0, vstep), x0);
      const __m256i off1 = _mm256_sub_epi32(_mm256_add_epi32(off0, vstep), _mm256_set1_epi32(2));
      const __m256i g0 = _mm256_i32gather_epi32(base, off0, 1);  // bytes x0, x0+1 in bits 0-15
      const __m256i g1 = _mm256_i32gather_epi32(base, off1, 1);  // bytes x0, x0+1 in bits 16-31
      const __m256 a00 = _mm256_cvtepi32_ps(_mm256_and_si256(g0, low_byte));
      const __m256 a01 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(g0, 8), low_byte));
      const __m256 a10 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(g1, 16), low_byte));
      const __m256 a11 = _mm256_cvtepi32_ps(_mm256_srli_epi32(g1, 24));
      // top = r0[0] + fx * (r0[1] - r0[0]) etc., as SampleOne.
      const __m256 top = _mm256_add_ps(a00, _mm256_mul_ps(fx, _mm256_sub_ps(a01, a00)));
      const __m256 bottom = _mm256_add_ps(a10, _mm256_mul_ps(fx, _mm256_sub_ps(a11, a10)));
      _mm256_storeu_ps(out + i, _mm256_add_ps(top, _mm256_mul_ps(fy, _mm256_sub_ps(bottom, top))));
    }
  }
  for (; i < n; ++i) out[i] = SampleOne(data, step, xs[i], ys[i]);
}
#endif

bool CpuHasAvx2() {
#if IMUMATCH_BS_X86
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

SamplerPath Resolve(SamplerPath path) {
  static const SamplerPath best = CpuHasAvx2() ? SamplerPath::kAvx2 : SamplerPath::kPortable;
  if (path == SamplerPath::kAuto) return best;
  IMUMATCH_CHECK(SamplerPathSupported(path), "this CPU lacks the requested sampler path");
  return path;
}

}  // namespace

bool SamplerPathSupported(SamplerPath path) { return path != SamplerPath::kAvx2 || CpuHasAvx2(); }

void SampleGrid(const uint8_t* data, size_t step, float x, float y, int w, int h, float* out,
                SamplerPath path) {
#if IMUMATCH_BS_X86
  if (Resolve(path) == SamplerPath::kAvx2) {
    SampleGridAvx2(data, step, x, y, w, h, out);
    return;
  }
#else
  Resolve(path);
#endif
  SampleGridPortable(data, step, x, y, w, h, out);
}

void SamplePoints(const uint8_t* data, size_t step, int rows, const float* xs, const float* ys,
                  int n, float* out, SamplerPath path) {
#if IMUMATCH_BS_X86
  if (Resolve(path) == SamplerPath::kAvx2) {
    SamplePointsAvx2(data, step, rows, xs, ys, n, out);
    return;
  }
#else
  Resolve(path);
#endif
  SamplePointsPortable(data, step, rows, xs, ys, n, out);
}

}  // namespace imumatch
