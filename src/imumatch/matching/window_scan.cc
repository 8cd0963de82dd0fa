// Compiled with -ffp-contract=off (CMakeLists.txt): the capsule test must round as written on every
// path (no fused multiply-add), so that the vector paths give the portable path's lists.
#include "imumatch/matching/window_scan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "imumatch/core/error.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define IMUMATCH_WT_X86 1
#else
#define IMUMATCH_WT_X86 0
#endif

namespace imumatch {
namespace {

template <bool kCapsule>
int TestRunPortable(const CandidateTest& t, const CandidateView& b, int begin, int end, float lo_x,
                    float hi_x, float lo_y, float hi_y, int keep_inconsistent, int* consistent_slot,
                    int* num_consistent, int* rival_slot, int* num_rivals) {
  const float len2 = t.dx * t.dx + t.dy * t.dy;
  const float denominator = len2 > 0.0f ? len2 : 1.0f;  // a point segment: dot = 0, s = 0
  const int no_angle_check = !t.check_angle, no_size_check = !t.check_size;
  int nc = *num_consistent, ni = *num_rivals, any = 0;
  for (int k = begin; k < end; ++k) {
    const float x = b.x[k], y = b.y[k];
    int in = (x >= lo_x) & (x <= hi_x) & (y >= lo_y) & (y <= hi_y);
    if constexpr (kCapsule) {
      const float px = x - t.start_x, py = y - t.start_y;
      const float s = std::min(std::max((px * t.dx + py * t.dy) / denominator, 0.0f), 1.0f);
      const float ex = px - s * t.dx, ey = py - s * t.dy;
      in &= static_cast<int>(ex * ex + ey * ey <= t.r2);
    }
    const float a = b.angle_deg[k];
    const float d = std::fabs(a - t.expected_angle);
    const int angle_ok =
        no_angle_check | (a < 0.0f) | static_cast<int>(std::min(d, 360.0f - d) <= t.orient_tol);
    const float size = b.size[k];
    const int size_ok =
        no_size_check | (size <= 0.0f) | ((size >= t.size_lo) & (size <= t.size_hi));
    const int consistent = angle_ok & size_ok;
    any |= in | ((in & angle_ok) << 1);
    consistent_slot[nc] = k;
    rival_slot[ni] = k;
    nc += in & consistent;
    ni += in & (consistent ^ 1) & keep_inconsistent;
  }
  *num_consistent = nc;
  *num_rivals = ni;
  return any;
}

#if IMUMATCH_WT_X86

// Min and max in their zero-masked forms, all lanes on: the plain intrinsics' undefined
// pass-through operand trips GCC 12's -Wmaybe-uninitialized.
constexpr __mmask16 kAll = 0xffff;

template <bool kCapsule>
__attribute__((target("avx512f"))) int TestRunAvx512(const CandidateTest& t, const CandidateView& b,
                                                     int begin, int end, float lo_x, float hi_x,
                                                     float lo_y, float hi_y, int keep_inconsistent,
                                                     int* consistent_slot, int* num_consistent,
                                                     int* rival_slot, int* num_rivals) {
  const float len2 = t.dx * t.dx + t.dy * t.dy;
  const __m512 den = _mm512_set1_ps(len2 > 0.0f ? len2 : 1.0f);
  const __m512 vlo_x = _mm512_set1_ps(lo_x), vhi_x = _mm512_set1_ps(hi_x);
  const __m512 vlo_y = _mm512_set1_ps(lo_y), vhi_y = _mm512_set1_ps(hi_y);
  const __m512 sx = _mm512_set1_ps(t.start_x), sy = _mm512_set1_ps(t.start_y);
  const __m512 dx = _mm512_set1_ps(t.dx), dy = _mm512_set1_ps(t.dy), r2 = _mm512_set1_ps(t.r2);
  const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
  const __m512 full_turn = _mm512_set1_ps(360.0f), expected = _mm512_set1_ps(t.expected_angle);
  const __m512 tol = _mm512_set1_ps(t.orient_tol);
  const __m512 size_lo = _mm512_set1_ps(t.size_lo), size_hi = _mm512_set1_ps(t.size_hi);
  const __mmask16 angle_all = t.check_angle ? 0 : 0xffff, size_all = t.check_size ? 0 : 0xffff;
  const __mmask16 keep = keep_inconsistent ? 0xffff : 0;
  int nc = *num_consistent, ni = *num_rivals;
  __mmask16 any_in = 0, any_angle = 0;
  __m512i slot =
      _mm512_add_epi32(_mm512_set1_epi32(begin),
                       _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
  const __m512i sixteen = _mm512_set1_epi32(16);
  for (int k = begin; k < end; k += 16, slot = _mm512_add_epi32(slot, sixteen)) {
    const int left = end - k;
    const __mmask16 live =
        left >= 16 ? static_cast<__mmask16>(0xffff) : static_cast<__mmask16>((1u << left) - 1u);
    const __m512 x = _mm512_maskz_loadu_ps(live, b.x + k);
    const __m512 y = _mm512_maskz_loadu_ps(live, b.y + k);
    __mmask16 in = _mm512_mask_cmp_ps_mask(live, x, vlo_x, _CMP_GE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, x, vhi_x, _CMP_LE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, y, vlo_y, _CMP_GE_OQ);
    in = _mm512_mask_cmp_ps_mask(in, y, vhi_y, _CMP_LE_OQ);
    if constexpr (kCapsule) {
      const __m512 px = _mm512_sub_ps(x, sx), py = _mm512_sub_ps(y, sy);
      const __m512 dot = _mm512_add_ps(_mm512_mul_ps(px, dx), _mm512_mul_ps(py, dy));
      const __m512 s =
          _mm512_maskz_min_ps(kAll, _mm512_maskz_max_ps(kAll, _mm512_div_ps(dot, den), zero), one);
      const __m512 ex = _mm512_sub_ps(px, _mm512_mul_ps(s, dx));
      const __m512 ey = _mm512_sub_ps(py, _mm512_mul_ps(s, dy));
      const __m512 d2 = _mm512_add_ps(_mm512_mul_ps(ex, ex), _mm512_mul_ps(ey, ey));
      in = _mm512_mask_cmp_ps_mask(in, d2, r2, _CMP_LE_OQ);
    }
    const __m512 a = _mm512_maskz_loadu_ps(live, b.angle_deg + k);
    const __m512 d = _mm512_abs_ps(_mm512_sub_ps(a, expected));
    const __m512 turn = _mm512_maskz_min_ps(kAll, d, _mm512_sub_ps(full_turn, d));
    const __mmask16 angle_ok = angle_all | _mm512_cmp_ps_mask(a, zero, _CMP_LT_OQ) |
                               _mm512_cmp_ps_mask(turn, tol, _CMP_LE_OQ);
    const __m512 size = _mm512_maskz_loadu_ps(live, b.size + k);
    const __mmask16 size_ok = size_all | _mm512_cmp_ps_mask(size, zero, _CMP_LE_OQ) |
                              _mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(size, size_lo, _CMP_GE_OQ),
                                                      size, size_hi, _CMP_LE_OQ);
    const __mmask16 consistent = angle_ok & size_ok;
    any_in |= in;
    any_angle |= in & angle_ok;
    const __mmask16 take = in & consistent, rival = in & static_cast<__mmask16>(~consistent) & keep;
    // Register-to-register compress, then a plain store (the memory form of VPCOMPRESSD is
    // microcoded and slow on AMD Zen 4); the lists have kWindowScanSlack spare entries.
    _mm512_storeu_si512(consistent_slot + nc, _mm512_maskz_compress_epi32(take, slot));
    _mm512_storeu_si512(rival_slot + ni, _mm512_maskz_compress_epi32(rival, slot));
    nc += __builtin_popcount(take);
    ni += __builtin_popcount(rival);
  }
  *num_consistent = nc;
  *num_rivals = ni;
  return (any_in != 0 ? 1 : 0) | (any_angle != 0 ? 2 : 0);
}

// For each 8-bit lane mask, the lanes that are set, in order (the AVX2 compaction's permutation).
const std::array<uint64_t, 256>& CompactionTable() {
  static const std::array<uint64_t, 256> table = [] {
    std::array<uint64_t, 256> t{};
    for (int m = 0; m < 256; ++m) {
      uint64_t packed = 0;
      int n = 0;
      for (int lane = 0; lane < 8; ++lane) {
        if (m & (1 << lane)) packed |= static_cast<uint64_t>(lane) << (8 * n++);
      }
      t[m] = packed;
    }
    return t;
  }();
  return table;
}

__attribute__((target("avx2"))) inline void StoreCompacted(int* out, __m256i slot, int mask,
                                                           const std::array<uint64_t, 256>& table) {
  const __m256i perm = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<int64_t>(table[mask])));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_permutevar8x32_epi32(slot, perm));
}

__attribute__((target("avx2"))) inline int Bits(__m256 compare) {
  return _mm256_movemask_ps(compare);
}

template <bool kCapsule>
__attribute__((target("avx2"))) int TestRunAvx2(const CandidateTest& t, const CandidateView& b,
                                                int begin, int end, float lo_x, float hi_x,
                                                float lo_y, float hi_y, int keep_inconsistent,
                                                int* consistent_slot, int* num_consistent,
                                                int* rival_slot, int* num_rivals) {
  const std::array<uint64_t, 256>& table = CompactionTable();
  const float len2 = t.dx * t.dx + t.dy * t.dy;
  const __m256 den = _mm256_set1_ps(len2 > 0.0f ? len2 : 1.0f);
  const __m256 vlo_x = _mm256_set1_ps(lo_x), vhi_x = _mm256_set1_ps(hi_x);
  const __m256 vlo_y = _mm256_set1_ps(lo_y), vhi_y = _mm256_set1_ps(hi_y);
  const __m256 sx = _mm256_set1_ps(t.start_x), sy = _mm256_set1_ps(t.start_y);
  const __m256 dx = _mm256_set1_ps(t.dx), dy = _mm256_set1_ps(t.dy), r2 = _mm256_set1_ps(t.r2);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 full_turn = _mm256_set1_ps(360.0f), expected = _mm256_set1_ps(t.expected_angle);
  const __m256 tol = _mm256_set1_ps(t.orient_tol);
  const __m256 size_lo = _mm256_set1_ps(t.size_lo), size_hi = _mm256_set1_ps(t.size_hi);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const int angle_all = t.check_angle ? 0 : 0xff, size_all = t.check_size ? 0 : 0xff;
  const int keep = keep_inconsistent ? 0xff : 0;
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  int nc = *num_consistent, ni = *num_rivals, any_in = 0, any_angle = 0;
  for (int k = begin; k < end; k += 8) {
    const int left = end - k;
    const __m256i slot = _mm256_add_epi32(_mm256_set1_epi32(k), lanes);
    const __m256i load = _mm256_cmpgt_epi32(_mm256_set1_epi32(left), lanes);
    const int live = left >= 8 ? 0xff : (1 << left) - 1;
    const __m256 x = _mm256_maskload_ps(b.x + k, load);
    const __m256 y = _mm256_maskload_ps(b.y + k, load);
    int in = live & Bits(_mm256_cmp_ps(x, vlo_x, _CMP_GE_OQ)) &
             Bits(_mm256_cmp_ps(x, vhi_x, _CMP_LE_OQ)) & Bits(_mm256_cmp_ps(y, vlo_y, _CMP_GE_OQ)) &
             Bits(_mm256_cmp_ps(y, vhi_y, _CMP_LE_OQ));
    if constexpr (kCapsule) {
      const __m256 px = _mm256_sub_ps(x, sx), py = _mm256_sub_ps(y, sy);
      const __m256 dot = _mm256_add_ps(_mm256_mul_ps(px, dx), _mm256_mul_ps(py, dy));
      const __m256 s = _mm256_min_ps(_mm256_max_ps(_mm256_div_ps(dot, den), zero), one);
      const __m256 ex = _mm256_sub_ps(px, _mm256_mul_ps(s, dx));
      const __m256 ey = _mm256_sub_ps(py, _mm256_mul_ps(s, dy));
      const __m256 d2 = _mm256_add_ps(_mm256_mul_ps(ex, ex), _mm256_mul_ps(ey, ey));
      in &= Bits(_mm256_cmp_ps(d2, r2, _CMP_LE_OQ));
    }
    const __m256 a = _mm256_maskload_ps(b.angle_deg + k, load);
    const __m256 d = _mm256_and_ps(_mm256_sub_ps(a, expected), abs_mask);
    const __m256 turn = _mm256_min_ps(d, _mm256_sub_ps(full_turn, d));
    const int angle_ok = angle_all | Bits(_mm256_cmp_ps(a, zero, _CMP_LT_OQ)) |
                         Bits(_mm256_cmp_ps(turn, tol, _CMP_LE_OQ));
    const __m256 size = _mm256_maskload_ps(b.size + k, load);
    const int size_ok = size_all | Bits(_mm256_cmp_ps(size, zero, _CMP_LE_OQ)) |
                        (Bits(_mm256_cmp_ps(size, size_lo, _CMP_GE_OQ)) &
                         Bits(_mm256_cmp_ps(size, size_hi, _CMP_LE_OQ)));
    const int consistent = angle_ok & size_ok;
    any_in |= in;
    any_angle |= in & angle_ok;
    const int take = in & consistent, rival = in & ~consistent & keep;
    StoreCompacted(consistent_slot + nc, slot, take, table);
    StoreCompacted(rival_slot + ni, slot, rival, table);
    nc += __builtin_popcount(static_cast<unsigned>(take));
    ni += __builtin_popcount(static_cast<unsigned>(rival));
  }
  *num_consistent = nc;
  *num_rivals = ni;
  return (any_in != 0 ? 1 : 0) | (any_angle != 0 ? 2 : 0);
}

#endif  // IMUMATCH_WT_X86

bool Available(BruteForceKernel k) {
  static const std::vector<BruteForceKernel> kernels = AvailableBruteForceKernels();
  return std::find(kernels.begin(), kernels.end(), k) != kernels.end();
}

}  // namespace

WindowScanFn SelectWindowScan(bool capsule, BruteForceKernel kernel) {
  if (kernel == BruteForceKernel::kAuto) {
    kernel = Available(BruteForceKernel::kAvx512) ? BruteForceKernel::kAvx512
             : Available(BruteForceKernel::kAvx2) ? BruteForceKernel::kAvx2
                                                  : BruteForceKernel::kScalar;
  }
  IMUMATCH_CHECK(Available(kernel),
                 "this CPU cannot run the " << ToString(kernel) << " window test");
#if IMUMATCH_WT_X86
  if (kernel == BruteForceKernel::kAvx512) {
    return capsule ? &TestRunAvx512<true> : &TestRunAvx512<false>;
  }
  if (kernel == BruteForceKernel::kAvx2) {
    return capsule ? &TestRunAvx2<true> : &TestRunAvx2<false>;
  }
#endif
  return capsule ? &TestRunPortable<true> : &TestRunPortable<false>;
}

}  // namespace imumatch
