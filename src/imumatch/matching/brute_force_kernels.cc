#include "imumatch/matching/brute_force_kernels.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "imumatch/core/error.h"
#include "imumatch/matching/brute_force_l2.h"

#if IMUMATCH_BF_X86
#include <immintrin.h>
#endif

namespace imumatch {

const char* ToString(BruteForceKernel kernel) {
  switch (kernel) {
    case BruteForceKernel::kAuto:
      return "auto";
    case BruteForceKernel::kScalar:
      return "scalar";
    case BruteForceKernel::kPopcnt:
      return "popcnt";
    case BruteForceKernel::kAvx2:
      return "avx2";
    case BruteForceKernel::kAvx512:
      return "avx512";
  }
  return "?";
}

std::string CpuFeaturesString() {
  std::string s;
#if IMUMATCH_BF_X86
  __builtin_cpu_init();
  auto add = [&](const char* name, bool has) {
    if (has) s += (s.empty() ? "" : " ") + std::string(name);
  };
  add("popcnt", __builtin_cpu_supports("popcnt"));
  add("avx2", __builtin_cpu_supports("avx2"));
  add("fma", __builtin_cpu_supports("fma"));
  add("avx512f", __builtin_cpu_supports("avx512f"));
  add("avx512vpopcntdq", __builtin_cpu_supports("avx512vpopcntdq"));
#endif
  return s.empty() ? "none" : s;
}

void Nearest2::Reset(int n) {
  best.assign(n, std::numeric_limits<float>::infinity());
  second.assign(n, std::numeric_limits<float>::infinity());
  best_idx.assign(n, -1);
}

namespace {

constexpr int kQueryBlock = 4;
constexpr int kTrainChunk = 256;

__attribute__((always_inline)) inline uint64_t Load64(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

// Hamming kernel over W 64-bit words. Blocks of 4 queries keep their 4*W words in registers while
// a chunk of B streams past. Compiled twice: with and without the POPCNT instruction.
// always_inline: the kernel must be compiled inside its target("popcnt") caller, otherwise GCC
// emits calls to the portable __popcountdi2.
template <int W>
__attribute__((always_inline)) inline void HammingBlockKernel(const DescriptorView& a,
                                                              const DescriptorView& b,
                                                              Nearest2& out) {
  const int n = a.rows, m = b.rows;
  for (int j0 = 0; j0 < m; j0 += kTrainChunk) {
    const int j1 = std::min(m, j0 + kTrainChunk);
    int i = 0;
    for (; i + kQueryBlock <= n; i += kQueryBlock) {
      uint64_t q[kQueryBlock][W];
#pragma GCC unroll 4
      for (int u = 0; u < kQueryBlock; ++u) {
#pragma GCC unroll 8
        for (int w = 0; w < W; ++w) q[u][w] = Load64(a.Row(i + u) + 8 * w);
      }
      float best[kQueryBlock], second[kQueryBlock];
      int idx[kQueryBlock];
      for (int u = 0; u < kQueryBlock; ++u) {
        best[u] = out.best[i + u];
        second[u] = out.second[i + u];
        idx[u] = out.best_idx[i + u];
      }
      for (int j = j0; j < j1; ++j) {
        const uint8_t* row = b.Row(j);
        uint64_t t[W];
#pragma GCC unroll 8
        for (int w = 0; w < W; ++w) t[w] = Load64(row + 8 * w);
#pragma GCC unroll 4
        for (int u = 0; u < kQueryBlock; ++u) {
          int d = 0;
#pragma GCC unroll 8
          for (int w = 0; w < W; ++w) d += __builtin_popcountll(q[u][w] ^ t[w]);
          UpdateNearest2(static_cast<float>(d), j, best[u], second[u], idx[u]);
        }
      }
      for (int u = 0; u < kQueryBlock; ++u) {
        out.best[i + u] = best[u];
        out.second[i + u] = second[u];
        out.best_idx[i + u] = idx[u];
      }
    }
    for (; i < n; ++i) {
      for (int j = j0; j < j1; ++j) {
        const float d = static_cast<float>(HammingDistance(a.Row(i), b.Row(j), W * 8));
        UpdateNearest2(d, j, out.best[i], out.second[i], out.best_idx[i]);
      }
    }
  }
}

// Any multiple of 8 bytes: one pair at a time.
__attribute__((always_inline)) inline void GenericKernel(const DescriptorView& a,
                                                         const DescriptorView& b, Nearest2& out,
                                                         DescriptorCostFn fn) {
  for (int j0 = 0; j0 < b.rows; j0 += kTrainChunk) {
    const int j1 = std::min(b.rows, j0 + kTrainChunk);
    for (int i = 0; i < a.rows; ++i) {
      for (int j = j0; j < j1; ++j) {
        UpdateNearest2(fn(a.Row(i), b.Row(j), a.bytes), j, out.best[i], out.second[i],
                       out.best_idx[i]);
      }
    }
  }
}

void HammingPortable(const DescriptorView& a, const DescriptorView& b, Nearest2& out) {
  if (a.bytes == 32) return HammingBlockKernel<4>(a, b, out);
  if (a.bytes == 64) return HammingBlockKernel<8>(a, b, out);
  GenericKernel(a, b, out, SelectCostFunction(DescriptorNorm::kHamming, a.bytes));
}

#if IMUMATCH_BF_X86
// 32-byte descriptors (ORB, BRIEF-32, AKAZE-MLDB-32), written out by hand so the 16 query words
// stay in registers and every distance is 4 POPCNTs (a templated loop version got vectorised by
// GCC into an emulated popcount).
__attribute__((target("popcnt"))) void Hamming32Popcnt(const DescriptorView& a,
                                                       const DescriptorView& b, Nearest2& out) {
  const int n = a.rows, m = b.rows;
  for (int j0 = 0; j0 < m; j0 += kTrainChunk) {
    const int j1 = std::min(m, j0 + kTrainChunk);
    int i = 0;
    for (; i + 4 <= n; i += 4) {
      const uint8_t* r0 = a.Row(i);
      const uint8_t* r1 = a.Row(i + 1);
      const uint8_t* r2 = a.Row(i + 2);
      const uint8_t* r3 = a.Row(i + 3);
      const uint64_t a0 = Load64(r0), a1 = Load64(r0 + 8), a2 = Load64(r0 + 16),
                     a3 = Load64(r0 + 24);
      const uint64_t b0 = Load64(r1), b1 = Load64(r1 + 8), b2 = Load64(r1 + 16),
                     b3 = Load64(r1 + 24);
      const uint64_t c0 = Load64(r2), c1 = Load64(r2 + 8), c2 = Load64(r2 + 16),
                     c3 = Load64(r2 + 24);
      const uint64_t d0 = Load64(r3), d1 = Load64(r3 + 8), d2 = Load64(r3 + 16),
                     d3 = Load64(r3 + 24);
      float best0 = out.best[i], best1 = out.best[i + 1], best2 = out.best[i + 2],
            best3 = out.best[i + 3];
      float sec0 = out.second[i], sec1 = out.second[i + 1], sec2 = out.second[i + 2],
            sec3 = out.second[i + 3];
      int idx0 = out.best_idx[i], idx1 = out.best_idx[i + 1], idx2 = out.best_idx[i + 2],
          idx3 = out.best_idx[i + 3];
      for (int j = j0; j < j1; ++j) {
        const uint8_t* row = b.Row(j);
        const uint64_t t0 = Load64(row), t1 = Load64(row + 8), t2 = Load64(row + 16),
                       t3 = Load64(row + 24);
        const int e0 = __builtin_popcountll(a0 ^ t0) + __builtin_popcountll(a1 ^ t1) +
                       __builtin_popcountll(a2 ^ t2) + __builtin_popcountll(a3 ^ t3);
        const int e1 = __builtin_popcountll(b0 ^ t0) + __builtin_popcountll(b1 ^ t1) +
                       __builtin_popcountll(b2 ^ t2) + __builtin_popcountll(b3 ^ t3);
        const int e2 = __builtin_popcountll(c0 ^ t0) + __builtin_popcountll(c1 ^ t1) +
                       __builtin_popcountll(c2 ^ t2) + __builtin_popcountll(c3 ^ t3);
        const int e3 = __builtin_popcountll(d0 ^ t0) + __builtin_popcountll(d1 ^ t1) +
                       __builtin_popcountll(d2 ^ t2) + __builtin_popcountll(d3 ^ t3);
        UpdateNearest2(static_cast<float>(e0), j, best0, sec0, idx0);
        UpdateNearest2(static_cast<float>(e1), j, best1, sec1, idx1);
        UpdateNearest2(static_cast<float>(e2), j, best2, sec2, idx2);
        UpdateNearest2(static_cast<float>(e3), j, best3, sec3, idx3);
      }
      out.best[i] = best0, out.best[i + 1] = best1, out.best[i + 2] = best2,
      out.best[i + 3] = best3;
      out.second[i] = sec0, out.second[i + 1] = sec1, out.second[i + 2] = sec2,
      out.second[i + 3] = sec3;
      out.best_idx[i] = idx0, out.best_idx[i + 1] = idx1, out.best_idx[i + 2] = idx2,
      out.best_idx[i + 3] = idx3;
    }
    for (; i < n; ++i) {
      const uint8_t* q = a.Row(i);
      const uint64_t a0 = Load64(q), a1 = Load64(q + 8), a2 = Load64(q + 16), a3 = Load64(q + 24);
      for (int j = j0; j < j1; ++j) {
        const uint8_t* row = b.Row(j);
        const int e = __builtin_popcountll(a0 ^ Load64(row)) +
                      __builtin_popcountll(a1 ^ Load64(row + 8)) +
                      __builtin_popcountll(a2 ^ Load64(row + 16)) +
                      __builtin_popcountll(a3 ^ Load64(row + 24));
        UpdateNearest2(static_cast<float>(e), j, out.best[i], out.second[i], out.best_idx[i]);
      }
    }
  }
}

void HammingPopcnt(const DescriptorView& a, const DescriptorView& b, Nearest2& out) {
  if (a.bytes == 32) return Hamming32Popcnt(a, b, out);
  // Other lengths: one pair at a time through the POPCNT cost function.
  GenericKernel(a, b, out, SelectCostFunction(DescriptorNorm::kHamming, a.bytes));
}

// ---- Wide kernels ----------------------------------------------------------------------------
// Hamming: B is transposed into blocks of L rows, word-major (block k, word w holds word w of rows
// kL .. kL+L-1), so one vector register holds the same word of L train descriptors and a query word
// is broadcast against it. Each lane keeps its own best / second / index (ties: earliest index);
// the lanes are merged at the end, ties again to the earliest index, which is exactly what the
// scalar loop over j gives.
constexpr uint64_t kFar = uint64_t{1} << 40;  // farther than any Hamming distance

std::vector<uint64_t> TransposeWords(const DescriptorView& b, int lanes) {
  const int words = b.bytes / 8, blocks = (b.rows + lanes - 1) / lanes;
  std::vector<uint64_t> t(static_cast<size_t>(blocks) * words * lanes, 0);
  for (int j = 0; j < b.rows; ++j) {
    const int blk = j / lanes, lane = j % lanes;
    for (int w = 0; w < words; ++w) {
      t[(static_cast<size_t>(blk) * words + w) * lanes + lane] = Load64(b.Row(j) + 8 * w);
    }
  }
  return t;
}

// AVX-512: distances of one query to 8 train rows (block col), the W words' counts summed as a
// tree; then the lanes' nearest two and index kept.
template <int W>
__attribute__((target("avx512f,avx512vpopcntdq"), always_inline)) inline __m512i Distances512(
    const __m512i* q, const uint64_t* col) {
  __m512i count[W];
#pragma GCC unroll 8
  for (int w = 0; w < W; ++w) {
    count[w] = _mm512_popcnt_epi64(_mm512_xor_si512(q[w], _mm512_loadu_si512(col + w * 8)));
  }
#pragma GCC unroll 8
  for (int s = 1; s < W; s *= 2) {
#pragma GCC unroll 8
    for (int w = 0; w + s < W; w += 2 * s) count[w] = _mm512_add_epi64(count[w], count[w + s]);
  }
  return count[0];
}

struct Lanes512 {
  __m512i best, second, idx;
};

__attribute__((target("avx512f"), always_inline)) inline void Keep512(__m512i d, __m512i jv,
                                                                      Lanes512& k) {
  const __mmask8 lt = _mm512_cmplt_epu64_mask(d, k.best);
  // (Masked forms with an explicit source: GCC 12 warns that the unmasked ones read an undefined
  // register.)
  const __m512i d_max = _mm512_mask_max_epu64(d, 0xFF, d, k.best);
  k.second = _mm512_mask_min_epu64(k.second, 0xFF, k.second, d_max);
  k.best = _mm512_mask_min_epu64(k.best, 0xFF, k.best, d);
  k.idx = _mm512_mask_mov_epi64(k.idx, lt, jv);
}

__attribute__((target("avx512f"))) void MergeLanes512(const Lanes512& k, int i, Nearest2& out) {
  alignas(64) uint64_t best_l[8], second_l[8];
  alignas(64) int64_t idx_l[8];
  _mm512_store_si512(best_l, k.best);
  _mm512_store_si512(second_l, k.second);
  _mm512_store_si512(idx_l, k.idx);
  MergeLaneNearest2(best_l, second_l, idx_l, 8, kFar, i, out);
}

// Q queries (1 or 2) against all of B: the train block's words are loaded once for both queries.
// Two queries per pass took 0.67-0.93x the time of one (32 and 64 bytes, 1000 and 4000 rows;
// three or four per pass were no faster), measured in one program on an AMD EPYC family 26; with
// one query the template word count alone changed nothing there (0.98-1.04x the run-time loop).
template <int W, int Q>
__attribute__((target("avx512f,avx512vpopcntdq"), always_inline)) inline void HammingAvx512Pass(
    const DescriptorView& a, int i, const std::vector<uint64_t>& bt, int m, Nearest2& out) {
  constexpr int L = 8;
  const int blocks = (m + L - 1) / L;
  const __mmask8 last =
      m % L == 0 ? static_cast<__mmask8>(0xFF) : static_cast<__mmask8>((1u << (m % L)) - 1u);
  const __m512i far = _mm512_set1_epi64(static_cast<long long>(kFar));
  const __m512i step = _mm512_set1_epi64(L);
  __m512i q0[W], q1[W];
  Lanes512 k0{far, far, _mm512_set1_epi64(-1)}, k1 = k0;
#pragma GCC unroll 8
  for (int w = 0; w < W; ++w) {
    q0[w] = _mm512_set1_epi64(static_cast<long long>(Load64(a.Row(i) + 8 * w)));
    if constexpr (Q == 2)
      q1[w] = _mm512_set1_epi64(static_cast<long long>(Load64(a.Row(i + 1) + 8 * w)));
  }
  __m512i jv = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
  const uint64_t* col = bt.data();
  for (int blk = 0; blk + 1 < blocks; ++blk, col += W * L) {
    Keep512(Distances512<W>(q0, col), jv, k0);
    if constexpr (Q == 2) Keep512(Distances512<W>(q1, col), jv, k1);
    jv = _mm512_add_epi64(jv, step);
  }
  // The last block: lanes past row m - 1 held zeros, read as far away.
  Keep512(_mm512_mask_mov_epi64(far, last, Distances512<W>(q0, col)), jv, k0);
  MergeLanes512(k0, i, out);
  if constexpr (Q == 2) {
    Keep512(_mm512_mask_mov_epi64(far, last, Distances512<W>(q1, col)), jv, k1);
    MergeLanes512(k1, i + 1, out);
  }
}

template <int W>
__attribute__((target("avx512f,avx512vpopcntdq"))) void HammingAvx512Words(const DescriptorView& a,
                                                                           const DescriptorView& b,
                                                                           Nearest2& out) {
  const std::vector<uint64_t> bt = TransposeWords(b, 8);
  int i = 0;
  for (; i + 2 <= a.rows; i += 2) HammingAvx512Pass<W, 2>(a, i, bt, b.rows, out);
  if (i < a.rows) HammingAvx512Pass<W, 1>(a, i, bt, b.rows, out);
}

void HammingAvx512(const DescriptorView& a, const DescriptorView& b, Nearest2& out) {
  using Kernel = void (*)(const DescriptorView&, const DescriptorView&, Nearest2&);
  static constexpr Kernel kByWords[] = {
      HammingAvx512Words<1>, HammingAvx512Words<2>, HammingAvx512Words<3>, HammingAvx512Words<4>,
      HammingAvx512Words<5>, HammingAvx512Words<6>, HammingAvx512Words<7>, HammingAvx512Words<8>};
  kByWords[std::clamp(a.bytes / 8, 1, 8) - 1](a, b, out);
}

// W (the descriptor's 64-bit words) is a template argument: with the words' loop unrolled, their
// byte counts are summed as a tree (two chains of W / 2 additions instead of one of 2 W) and the
// query words stay in registers (a run-time word count had GCC reload them and chain every
// addition: that kernel took 1.13-1.15x as long for 32-byte descriptors, 1.06x for 64, measured
// against this one in one program on an AVX2-only AMD EPYC).
template <int W>
__attribute__((target("avx2"))) void HammingAvx2Words(const DescriptorView& a,
                                                      const DescriptorView& b, Nearest2& out) {
  constexpr int L = 4;
  const int m = b.rows, blocks = (m + L - 1) / L;
  const std::vector<uint64_t> bt = TransposeWords(b, L);
  const __m256i lut = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2,
                                       1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i nibble = _mm256_set1_epi8(0x0F), zero = _mm256_setzero_si256();
  const __m256i far = _mm256_set1_epi64x(static_cast<long long>(kFar));
  const __m256i step = _mm256_set1_epi64x(L);
  alignas(32) int64_t lane_valid[L];
  for (int l = 0; l < L; ++l) lane_valid[l] = (blocks - 1) * L + l < m ? -1 : 0;
  const __m256i last_valid = _mm256_load_si256(reinterpret_cast<const __m256i*>(lane_valid));
  alignas(32) uint64_t best_l[L], second_l[L];
  alignas(32) int64_t idx_l[L];
  __m256i q[W];
  for (int i = 0; i < a.rows; ++i) {
#pragma GCC unroll 8
    for (int w = 0; w < W; ++w) {
      q[w] = _mm256_set1_epi64x(static_cast<long long>(Load64(a.Row(i) + 8 * w)));
    }
    __m256i best = far, second = far, idx = _mm256_set1_epi64x(-1);
    __m256i jv = _mm256_setr_epi64x(0, 1, 2, 3);
    const uint64_t* col = bt.data();
    for (int blk = 0; blk < blocks; ++blk, col += static_cast<size_t>(W) * L) {
      // Byte counts per word (at most 8 per byte), summed over the words as a tree (at most 64),
      // then over the 8 bytes of each 64-bit lane.
      __m256i count[W];
#pragma GCC unroll 8
      for (int w = 0; w < W; ++w) {
        const __m256i x = _mm256_xor_si256(
            q[w], _mm256_loadu_si256(reinterpret_cast<const __m256i*>(col + w * L)));
        const __m256i lo = _mm256_and_si256(x, nibble);
        const __m256i hi = _mm256_and_si256(_mm256_srli_epi16(x, 4), nibble);
        count[w] = _mm256_add_epi8(_mm256_shuffle_epi8(lut, lo), _mm256_shuffle_epi8(lut, hi));
      }
#pragma GCC unroll 8
      for (int s = 1; s < W; s *= 2) {
#pragma GCC unroll 8
        for (int w = 0; w + s < W; w += 2 * s) count[w] = _mm256_add_epi8(count[w], count[w + s]);
      }
      __m256i d = _mm256_sad_epu8(count[0], zero);
      if (blk == blocks - 1) d = _mm256_blendv_epi8(far, d, last_valid);
      // Distances are < 2^41: signed 64-bit compares are exact.
      const __m256i lt = _mm256_cmpgt_epi64(best, d);         // d < best
      const __m256i d_max = _mm256_blendv_epi8(d, best, lt);  // max(d, best)
      second = _mm256_blendv_epi8(second, d_max, _mm256_cmpgt_epi64(second, d_max));
      best = _mm256_blendv_epi8(best, d, lt);
      idx = _mm256_blendv_epi8(idx, jv, lt);
      jv = _mm256_add_epi64(jv, step);
    }
    _mm256_store_si256(reinterpret_cast<__m256i*>(best_l), best);
    _mm256_store_si256(reinterpret_cast<__m256i*>(second_l), second);
    _mm256_store_si256(reinterpret_cast<__m256i*>(idx_l), idx);
    MergeLaneNearest2(best_l, second_l, idx_l, L, kFar, i, out);
  }
}

void HammingAvx2(const DescriptorView& a, const DescriptorView& b, Nearest2& out) {
  using Kernel = void (*)(const DescriptorView&, const DescriptorView&, Nearest2&);
  static constexpr Kernel kByWords[] = {
      HammingAvx2Words<1>, HammingAvx2Words<2>, HammingAvx2Words<3>, HammingAvx2Words<4>,
      HammingAvx2Words<5>, HammingAvx2Words<6>, HammingAvx2Words<7>, HammingAvx2Words<8>};
  kByWords[std::clamp(a.bytes / 8, 1, 8) - 1](a, b, out);
}

#endif

bool CpuHas(BruteForceKernel k) {
#if IMUMATCH_BF_X86
  switch (k) {
    case BruteForceKernel::kAuto:
    case BruteForceKernel::kScalar:
      return true;
    case BruteForceKernel::kPopcnt:
      return __builtin_cpu_supports("popcnt");
    case BruteForceKernel::kAvx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case BruteForceKernel::kAvx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq");
  }
  return false;
#else
  return k == BruteForceKernel::kAuto || k == BruteForceKernel::kScalar;
#endif
}

}  // namespace

void NearestTwo(const DescriptorView& a, const DescriptorView& b, BruteForceKernel kernel,
                Nearest2& out) {
  out.Reset(a.rows);
  if (a.rows == 0 || b.rows == 0) return;
  if (kernel == BruteForceKernel::kAuto) {
    static const BruteForceKernel fastest = AvailableBruteForceKernels().back();  // CPU: fixed
    kernel = fastest;
  }
  IMUMATCH_CHECK(CpuHas(kernel),
                 "this CPU cannot run the " << ToString(kernel) << " brute-force path");
  if (a.norm == DescriptorNorm::kHamming) {
#if IMUMATCH_BF_X86
    switch (kernel) {
      case BruteForceKernel::kAvx512:
        if (a.bytes <= 64) return HammingAvx512(a, b, out);
        break;
      case BruteForceKernel::kAvx2:
        if (a.bytes <= 64) return HammingAvx2(a, b, out);
        break;
      default:
        break;
    }
    if (kernel != BruteForceKernel::kScalar) return HammingPopcnt(a, b, out);
#endif
    return HammingPortable(a, b, out);
  }
#if IMUMATCH_BF_X86
  if (kernel == BruteForceKernel::kAvx512) return NearestTwoL2Avx512(a, b, out);
  if (kernel == BruteForceKernel::kAvx2) return NearestTwoL2Avx2(a, b, out);
#endif
  NearestTwoL2Scalar(a, b, out);
}

std::vector<BruteForceKernel> AvailableBruteForceKernels() {
  std::vector<BruteForceKernel> out;
  for (BruteForceKernel k : {BruteForceKernel::kScalar, BruteForceKernel::kPopcnt,
                             BruteForceKernel::kAvx2, BruteForceKernel::kAvx512}) {
    if (CpuHas(k)) out.push_back(k);
  }
  return out;
}

}  // namespace imumatch
