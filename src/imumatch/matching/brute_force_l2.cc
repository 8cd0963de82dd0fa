// Compiled with -ffp-contract=off (CMakeLists.txt): the bit-for-bit agreement of the paths needs
// every multiply and add as written, never fused.
#include "imumatch/matching/brute_force_l2.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#if IMUMATCH_BF_X86
#include <immintrin.h>
#endif

namespace imumatch {
namespace {

// L2Canonical's tree (brute_force_l2.h). AVX-512 holds the 16 partials in one register, AVX2 in
// two, the scalar path in an array.
inline float ReducePartials(const float* p) {
  float h[8];
  for (int l = 0; l < 8; ++l) h[l] = p[l] + p[l + 8];
  float g[4];
  for (int l = 0; l < 4; ++l) g[l] = h[l] + h[l + 4];
  return (g[0] + g[2]) + (g[1] + g[3]);
}

}  // namespace

float L2Canonical(const float* a, const float* b, int dims) {
  // Whole chunks of 16 first, as 16 independent sums the compiler vectorises (the same adds in
  // the same order as one loop over k with p[k % 16]: 0.13x its time at -O3, 0.32x at -O2,
  // measured on x86 for 128 floats), then the tail.
  float p[16] = {0};
  int k = 0;
  for (; k + 16 <= dims; k += 16) {
    for (int l = 0; l < 16; ++l) {
      const float d = a[k + l] - b[k + l];
      const float dd = d * d;
      p[l] = p[l] + dd;
    }
  }
  for (; k < dims; ++k) {
    const float d = a[k] - b[k];
    const float dd = d * d;
    p[k % 16] = p[k % 16] + dd;
  }
  return ReducePartials(p);
}

void NearestTwoL2Scalar(const DescriptorView& a, const DescriptorView& b, Nearest2& out) {
  const int dims = a.bytes / 4;
  for (int i = 0; i < a.rows; ++i) {
    const float* q = reinterpret_cast<const float*>(a.Row(i));
    for (int j = 0; j < b.rows; ++j) {
      UpdateNearest2(L2Canonical(q, reinterpret_cast<const float*>(b.Row(j)), dims), j, out.best[i],
                     out.second[i], out.best_idx[i]);
    }
  }
}

#if IMUMATCH_BF_X86
namespace {

// Every query's nearest two from its T lanes (stored query after query), as the Hamming kernels'
// lanes are merged. A lane's best stays +inf until it keeps a row.
void MergeFloatLanes(const std::vector<float>& best_s, const std::vector<float>& second_s,
                     const std::vector<int32_t>& idx_s, int T, Nearest2& out) {
  const int n = static_cast<int>(out.best.size());
  const float far = std::numeric_limits<float>::infinity();
  for (int i = 0; i < n; ++i) {
    const size_t at = static_cast<size_t>(i) * T;
    MergeLaneNearest2(best_s.data() + at, second_s.data() + at, idx_s.data() + at, T, far, i, out);
  }
}

// AVX-512 L2: 16 trains at a time, each (query, train) pair's 16 partials in one register, the 16
// registers reduced together by a transpose that adds the same operands as ReducePartials (float
// addition is commutative, so each sum has the scalar path's bits). The block of 16 trains (8 KB
// for SIFT) stays in L1 while every query passes over it; each query keeps its nearest two per
// lane in memory between blocks, merged at the end as the Hamming kernels' lanes are. Against
// the previous kernel (4 queries x 1 train, the partials reduced one pair at a time in scalar
// code) in one program on an AMD EPYC family 26: 0.58-0.59x the time for 128 floats, 0.43x for 64,
// 0.33x for 70 (1000 x 997 rows; 0.57x at 4000).
__attribute__((target("avx512f"), always_inline)) inline __m512 AddHalves512(__m512 a, __m512 b) {
  // lanes 0-7: a[l] + a[l + 8]; lanes 8-15: b[l] + b[l + 8]
  return _mm512_add_ps(_mm512_mask_shuffle_f32x4(a, 0xFFFF, a, b, 0x44),
                       _mm512_mask_shuffle_f32x4(b, 0xFFFF, a, b, 0xEE));
}
__attribute__((target("avx512f"), always_inline)) inline __m512 AddQuarters512(__m512 a, __m512 b) {
  // per 128-bit unit u of (a.h_lo, a.h_hi, b.h_lo, b.h_hi): h[l] + h[l + 4]
  return _mm512_add_ps(_mm512_mask_shuffle_f32x4(a, 0xFFFF, a, b, 0x88),
                       _mm512_mask_shuffle_f32x4(b, 0xFFFF, a, b, 0xDD));
}
// 16 pairs' partials -> their 16 distances; lane 4 u + k holds pair 4 k + u.
__attribute__((target("avx512f"), always_inline)) inline __m512 Reduce16(const __m512* s) {
  __m512 v[8], w[4];
  for (int r = 0; r < 8; ++r) v[r] = AddHalves512(s[2 * r], s[2 * r + 1]);
  for (int r = 0; r < 4; ++r) w[r] = AddQuarters512(v[2 * r], v[2 * r + 1]);
  const __m512 z1 =
      _mm512_add_ps(_mm512_shuffle_ps(w[0], w[1], 0x44), _mm512_shuffle_ps(w[0], w[1], 0xEE));
  const __m512 z2 =
      _mm512_add_ps(_mm512_shuffle_ps(w[2], w[3], 0x44), _mm512_shuffle_ps(w[2], w[3], 0xEE));
  return _mm512_add_ps(_mm512_shuffle_ps(z1, z2, 0x88), _mm512_shuffle_ps(z1, z2, 0xDD));
}
}  // namespace

__attribute__((target("avx512f"))) void NearestTwoL2Avx512(const DescriptorView& a,
                                                           const DescriptorView& b, Nearest2& out) {
  constexpr int T = 16;
  const int dims = a.bytes / 4, vec = dims - dims % 16, n = a.rows, m = b.rows;
  const __mmask16 tail = static_cast<__mmask16>((1u << (dims - vec)) - 1u);
  std::vector<float> best_s(static_cast<size_t>(n) * T, std::numeric_limits<float>::infinity());
  std::vector<float> second_s = best_s;
  std::vector<int32_t> idx_s(static_cast<size_t>(n) * T, -1);
  // lane 4 u + k <- train 4 k + u of the block
  const __m512i perm = _mm512_setr_epi32(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15);
  const __m512 inf = _mm512_set1_ps(std::numeric_limits<float>::infinity());
  for (int j0 = 0; j0 < m; j0 += T) {
    const float* t[T];
    for (int r = 0; r < T; ++r)
      t[r] = reinterpret_cast<const float*>(b.Row(std::min(j0 + r, m - 1)));
    const __m512i jv = _mm512_add_epi32(perm, _mm512_set1_epi32(j0));
    const __mmask16 valid = _mm512_cmplt_epi32_mask(jv, _mm512_set1_epi32(m));
    for (int i = 0; i < n; ++i) {
      const float* q = reinterpret_cast<const float*>(a.Row(i));
      __m512 s[T];
      for (int r = 0; r < T; ++r) s[r] = _mm512_setzero_ps();
      for (int k = 0; k < vec; k += 16) {
        const __m512 qv = _mm512_loadu_ps(q + k);
#pragma GCC unroll 16
        for (int r = 0; r < T; ++r) {
          const __m512 d = _mm512_sub_ps(qv, _mm512_loadu_ps(t[r] + k));
          s[r] = _mm512_add_ps(s[r], _mm512_mul_ps(d, d));
        }
      }
      if (tail) {
        const __m512 qv = _mm512_maskz_loadu_ps(tail, q + vec);
#pragma GCC unroll 16
        for (int r = 0; r < T; ++r) {
          const __m512 d = _mm512_sub_ps(qv, _mm512_maskz_loadu_ps(tail, t[r] + vec));
          s[r] = _mm512_add_ps(s[r], _mm512_mul_ps(d, d));
        }
      }
      // Lanes past the last row, and NaN distances (a NaN in a descriptor), read as +inf: never
      // kept, as the scalar update skips them (a NaN would reach second through max / min).
      const __m512 d = Reduce16(s);
      const __m512 dist =
          _mm512_mask_mov_ps(inf, _mm512_mask_cmp_ps_mask(valid, d, d, _CMP_ORD_Q), d);
      float* bp = best_s.data() + static_cast<size_t>(i) * T;
      float* sp = second_s.data() + static_cast<size_t>(i) * T;
      int32_t* ip = idx_s.data() + static_cast<size_t>(i) * T;
      const __m512 best = _mm512_loadu_ps(bp), second = _mm512_loadu_ps(sp);
      const __mmask16 lt = _mm512_cmp_ps_mask(dist, best, _CMP_LT_OQ);
      _mm512_storeu_ps(sp, _mm512_mask_min_ps(second, 0xFFFF, second,
                                              _mm512_mask_max_ps(dist, 0xFFFF, dist, best)));
      _mm512_storeu_ps(bp, _mm512_mask_min_ps(best, 0xFFFF, best, dist));
      _mm512_storeu_si512(ip, _mm512_mask_mov_epi32(_mm512_loadu_si512(ip), lt, jv));
    }
  }
  MergeFloatLanes(best_s, second_s, idx_s, T, out);
}

namespace {

// AVX2 L2: 8 trains at a time, each pair's partials in two registers (0-7, 8-15), the 8 trains in
// two halves of 4 (the 16 registers would not leave room for the query); the 8 pairs reduced
// together as ReducePartials adds (lo + hi = h, then the transposes). Against the previous kernel
// (4 queries x 1 train, reduced one pair at a time in scalar code) in one program on an AMD EPYC
// family 26: 0.51-0.52x the time for 128 floats, 0.36x for 64, 0.31x for 70 (1000 and 4000 rows).
__attribute__((target("avx2"), always_inline)) inline void PartialsAvx2(const float* q,
                                                                        const float* const* t,
                                                                        int vec, int tail,
                                                                        __m256* w_out) {
  __m256 lo[4], hi[4];
  for (int r = 0; r < 4; ++r) lo[r] = hi[r] = _mm256_setzero_ps();
  for (int k = 0; k < vec; k += 16) {
    const __m256 ql = _mm256_loadu_ps(q + k), qh = _mm256_loadu_ps(q + k + 8);
#pragma GCC unroll 4
    for (int r = 0; r < 4; ++r) {
      const __m256 dl = _mm256_sub_ps(ql, _mm256_loadu_ps(t[r] + k));
      const __m256 dh = _mm256_sub_ps(qh, _mm256_loadu_ps(t[r] + k + 8));
      lo[r] = _mm256_add_ps(lo[r], _mm256_mul_ps(dl, dl));
      hi[r] = _mm256_add_ps(hi[r], _mm256_mul_ps(dh, dh));
    }
  }
  if (tail > 0) {
    // Elements vec .. vec + tail - 1 into partials 0 .. tail - 1; masked lanes add 0.
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i ml = _mm256_cmpgt_epi32(_mm256_set1_epi32(tail), lane);
    const __m256i mh = _mm256_cmpgt_epi32(_mm256_set1_epi32(tail - 8), lane);
    const __m256 ql = _mm256_maskload_ps(q + vec, ml), qh = _mm256_maskload_ps(q + vec + 8, mh);
    for (int r = 0; r < 4; ++r) {
      const __m256 dl = _mm256_sub_ps(ql, _mm256_maskload_ps(t[r] + vec, ml));
      const __m256 dh = _mm256_sub_ps(qh, _mm256_maskload_ps(t[r] + vec + 8, mh));
      lo[r] = _mm256_add_ps(lo[r], _mm256_mul_ps(dl, dl));
      hi[r] = _mm256_add_ps(hi[r], _mm256_mul_ps(dh, dh));
    }
  }
  // h[l] = p[l] + p[l + 8]; then per pair of pairs (a, b): [a.h0-3 + a.h4-7, b.h0-3 + b.h4-7].
  __m256 h[4];
  for (int r = 0; r < 4; ++r) h[r] = _mm256_add_ps(lo[r], hi[r]);
  for (int r = 0; r < 2; ++r) {
    w_out[r] = _mm256_add_ps(_mm256_permute2f128_ps(h[2 * r], h[2 * r + 1], 0x20),
                             _mm256_permute2f128_ps(h[2 * r], h[2 * r + 1], 0x31));
  }
}

}  // namespace

__attribute__((target("avx2"))) void NearestTwoL2Avx2(const DescriptorView& a,
                                                      const DescriptorView& b, Nearest2& out) {
  constexpr int T = 8;
  const int dims = a.bytes / 4, vec = dims - dims % 16, tail = dims - vec, n = a.rows, m = b.rows;
  std::vector<float> best_s(static_cast<size_t>(n) * T, std::numeric_limits<float>::infinity());
  std::vector<float> second_s = best_s;
  std::vector<int32_t> idx_s(static_cast<size_t>(n) * T, -1);
  // lane 4 u + k <- train 2 k + u of the block
  const __m256i perm = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  for (int j0 = 0; j0 < m; j0 += T) {
    const float* t[T];
    for (int r = 0; r < T; ++r)
      t[r] = reinterpret_cast<const float*>(b.Row(std::min(j0 + r, m - 1)));
    const __m256i jv = _mm256_add_epi32(perm, _mm256_set1_epi32(j0));
    const __m256 valid = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(m), jv));
    for (int i = 0; i < n; ++i) {
      const float* q = reinterpret_cast<const float*>(a.Row(i));
      __m256 w[4];
      PartialsAvx2(q, t, vec, tail, w);
      PartialsAvx2(q, t + 4, vec, tail, w + 2);
      const __m256 z0 =
          _mm256_add_ps(_mm256_shuffle_ps(w[0], w[1], 0x44), _mm256_shuffle_ps(w[0], w[1], 0xEE));
      const __m256 z1 =
          _mm256_add_ps(_mm256_shuffle_ps(w[2], w[3], 0x44), _mm256_shuffle_ps(w[2], w[3], 0xEE));
      const __m256 d =
          _mm256_add_ps(_mm256_shuffle_ps(z0, z1, 0x88), _mm256_shuffle_ps(z0, z1, 0xDD));
      // As in the AVX-512 kernel: lanes past the last row and NaN distances read as +inf.
      const __m256 dist =
          _mm256_blendv_ps(inf, d, _mm256_and_ps(valid, _mm256_cmp_ps(d, d, _CMP_ORD_Q)));
      float* bp = best_s.data() + static_cast<size_t>(i) * T;
      float* sp = second_s.data() + static_cast<size_t>(i) * T;
      int32_t* ip = idx_s.data() + static_cast<size_t>(i) * T;
      const __m256 best = _mm256_loadu_ps(bp), second = _mm256_loadu_ps(sp);
      const __m256 lt = _mm256_cmp_ps(dist, best, _CMP_LT_OQ);
      _mm256_storeu_ps(sp, _mm256_min_ps(second, _mm256_max_ps(dist, best)));
      _mm256_storeu_ps(bp, _mm256_min_ps(best, dist));
      const __m256i idx = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(ip));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(ip),
                          _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(idx),
                                                               _mm256_castsi256_ps(jv), lt)));
    }
  }
  MergeFloatLanes(best_s, second_s, idx_s, T, out);
}
#endif

}  // namespace imumatch
