#include "imumatch/matching/baseline_matchers.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

#include "imumatch/core/error.h"
#include "imumatch/matching/descriptor_distance.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define IMUMATCH_BF_X86 1
#else
#define IMUMATCH_BF_X86 0
#endif

namespace imumatch {

void BruteForceOptions::Check() const {
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio=" << ratio << " must be in (0, 1]");
  IMUMATCH_CHECK(max_distance >= 0.0, "max_distance=" << max_distance);
}

void FlannLshOptions::Check() const {
  IMUMATCH_CHECK(table_number >= 1, "table_number=" << table_number);
  IMUMATCH_CHECK(key_size >= 1 && key_size <= 32, "key_size=" << key_size);
  IMUMATCH_CHECK(multi_probe_level >= 0, "multi_probe_level=" << multi_probe_level);
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio=" << ratio);
}

namespace {

constexpr int kQueryBlock = 4;
constexpr int kTrainChunk = 256;

// Best and second-best cost per query (Hamming bits or squared L2), and the best index.
struct Nearest2 {
  std::vector<float> best, second;
  std::vector<int> best_idx;
  void Reset(int n) {
    best.assign(n, std::numeric_limits<float>::infinity());
    second.assign(n, std::numeric_limits<float>::infinity());
    best_idx.assign(n, -1);
  }
};

__attribute__((always_inline)) inline void Update(float d, int j, float& best, float& second,
                                                  int& best_idx) {
  if (d < second) {
    if (d < best) {
      second = best;
      best = d;
      best_idx = j;
    } else {
      second = d;
    }
  }
}

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
          Update(static_cast<float>(d), j, best[u], second[u], idx[u]);
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
        Update(d, j, out.best[i], out.second[i], out.best_idx[i]);
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
        Update(fn(a.Row(i), b.Row(j), a.bytes), j, out.best[i], out.second[i], out.best_idx[i]);
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
        Update(static_cast<float>(e0), j, best0, sec0, idx0);
        Update(static_cast<float>(e1), j, best1, sec1, idx1);
        Update(static_cast<float>(e2), j, best2, sec2, idx2);
        Update(static_cast<float>(e3), j, best3, sec3, idx3);
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
        Update(static_cast<float>(e), j, out.best[i], out.second[i], out.best_idx[i]);
      }
    }
  }
}

void HammingPopcnt(const DescriptorView& a, const DescriptorView& b, Nearest2& out) {
  if (a.bytes == 32) return Hamming32Popcnt(a, b, out);
  // Other lengths: one pair at a time through the POPCNT cost function.
  GenericKernel(a, b, out, SelectCostFunction(DescriptorNorm::kHamming, a.bytes));
}

// L2: 4 queries share every 8-float load of the B row; 4 FMA accumulators.
__attribute__((target("avx2,fma"))) void L2Avx2(const DescriptorView& a, const DescriptorView& b,
                                                Nearest2& out) {
  const int n = a.rows, m = b.rows, dims = a.bytes / 4;
  const int vec_dims = dims - dims % 8;
  for (int j0 = 0; j0 < m; j0 += kTrainChunk / 4) {
    const int j1 = std::min(m, j0 + kTrainChunk / 4);
    int i = 0;
    for (; i + kQueryBlock <= n; i += kQueryBlock) {
      const float* q0 = reinterpret_cast<const float*>(a.Row(i));
      const float* q1 = reinterpret_cast<const float*>(a.Row(i + 1));
      const float* q2 = reinterpret_cast<const float*>(a.Row(i + 2));
      const float* q3 = reinterpret_cast<const float*>(a.Row(i + 3));
      for (int j = j0; j < j1; ++j) {
        const float* t = reinterpret_cast<const float*>(b.Row(j));
        __m256 s0 = _mm256_setzero_ps(), s1 = _mm256_setzero_ps(), s2 = _mm256_setzero_ps(),
               s3 = _mm256_setzero_ps();
        for (int k = 0; k < vec_dims; k += 8) {
          const __m256 tv = _mm256_loadu_ps(t + k);
          const __m256 d0 = _mm256_sub_ps(_mm256_loadu_ps(q0 + k), tv);
          const __m256 d1 = _mm256_sub_ps(_mm256_loadu_ps(q1 + k), tv);
          const __m256 d2 = _mm256_sub_ps(_mm256_loadu_ps(q2 + k), tv);
          const __m256 d3 = _mm256_sub_ps(_mm256_loadu_ps(q3 + k), tv);
          s0 = _mm256_fmadd_ps(d0, d0, s0);
          s1 = _mm256_fmadd_ps(d1, d1, s1);
          s2 = _mm256_fmadd_ps(d2, d2, s2);
          s3 = _mm256_fmadd_ps(d3, d3, s3);
        }
        // Horizontal sums of the four accumulators at once.
        const __m256 h01 = _mm256_hadd_ps(s0, s1), h23 = _mm256_hadd_ps(s2, s3);
        const __m256 h = _mm256_hadd_ps(h01, h23);
        const __m128 sum = _mm_add_ps(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
        alignas(16) float d[4];
        _mm_store_ps(d, sum);
        const float* qs[4] = {q0, q1, q2, q3};
        for (int u = 0; u < kQueryBlock; ++u) {
          for (int k = vec_dims; k < dims; ++k) d[u] += (qs[u][k] - t[k]) * (qs[u][k] - t[k]);
          Update(d[u], j, out.best[i + u], out.second[i + u], out.best_idx[i + u]);
        }
      }
    }
    for (; i < n; ++i) {
      for (int j = j0; j < j1; ++j) {
        const float d = L2DistanceSquared(reinterpret_cast<const float*>(a.Row(i)),
                                          reinterpret_cast<const float*>(b.Row(j)), dims);
        Update(d, j, out.best[i], out.second[i], out.best_idx[i]);
      }
    }
  }
}
#endif

void NearestTwo(const DescriptorView& a, const DescriptorView& b, Nearest2& out) {
  out.Reset(a.rows);
  if (a.rows == 0 || b.rows == 0) return;
  if (a.norm == DescriptorNorm::kHamming) {
#if IMUMATCH_BF_X86
    if (__builtin_cpu_supports("popcnt")) return HammingPopcnt(a, b, out);
#endif
    return HammingPortable(a, b, out);
  }
#if IMUMATCH_BF_X86
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return L2Avx2(a, b, out);
#endif
  GenericKernel(a, b, out, SelectCostFunction(DescriptorNorm::kL2, a.bytes));
}

int CvNorm(const cv::Mat& d) { return d.depth() == CV_8U ? cv::NORM_HAMMING : cv::NORM_L2; }

void CheckPair(const cv::Mat& a, const cv::Mat& b) {
  CheckCompatible(DescriptorView::FromMat(a), DescriptorView::FromMat(b));
}

Match FromDMatch(const cv::DMatch& d) {
  Match m;
  m.query_idx = d.queryIdx;
  m.train_idx = d.trainIdx;
  m.distance = d.distance;
  return m;
}

std::vector<Match> KnnToRatioMatches(const std::vector<std::vector<cv::DMatch>>& knn,
                                     double ratio) {
  std::vector<Match> out;
  out.reserve(knn.size());
  for (const auto& nn : knn) {
    if (nn.empty()) continue;
    Match m = FromDMatch(nn[0]);
    if (nn.size() >= 2) {
      m.second_distance = nn[1].distance;
      if (!(nn[0].distance < ratio * nn[1].distance)) continue;
    }
    out.push_back(m);
  }
  return out;
}

}  // namespace

std::vector<Match> MatchBruteForce(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                   const BruteForceOptions& options) {
  options.Check();
  const DescriptorView a = DescriptorView::FromMat(descriptors_a);
  const DescriptorView b = DescriptorView::FromMat(descriptors_b);
  CheckCompatible(a, b);
  std::vector<Match> out;
  if (a.rows == 0 || b.rows == 0) return out;
  Nearest2 fwd;
  NearestTwo(a, b, fwd);
  Nearest2 rev;
  if (options.cross_check) NearestTwo(b, a, rev);
  const DescriptorNorm norm = a.norm;
  const float ratio_cost = static_cast<float>(
      norm == DescriptorNorm::kL2 ? options.ratio * options.ratio : options.ratio);
  const float max_cost = std::isinf(options.max_distance)
                             ? std::numeric_limits<float>::infinity()
                             : DistanceToCost(norm, static_cast<float>(options.max_distance));
  const float inf = std::numeric_limits<float>::infinity();
  out.reserve(a.rows);
  for (int i = 0; i < a.rows; ++i) {
    const int j = fwd.best_idx[i];
    if (j < 0 || fwd.best[i] > max_cost) continue;
    if (options.ratio < 1.0 && fwd.second[i] < inf && !(fwd.best[i] < ratio_cost * fwd.second[i])) {
      continue;
    }
    if (options.cross_check && rev.best_idx[j] != i) continue;
    Match m;
    m.query_idx = i;
    m.train_idx = j;
    m.distance = CostToDistance(norm, fwd.best[i]);
    m.second_distance = fwd.second[i] < inf ? CostToDistance(norm, fwd.second[i]) : inf;
    out.push_back(m);
  }
  return out;
}

std::vector<Match> MatchOpenCvBruteForce(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b) {
  CheckPair(descriptors_a, descriptors_b);
  std::vector<Match> out;
  if (descriptors_a.empty() || descriptors_b.empty()) return out;
  cv::BFMatcher matcher(CvNorm(descriptors_a), false);
  std::vector<cv::DMatch> dm;
  matcher.match(descriptors_a, descriptors_b, dm);
  out.reserve(dm.size());
  for (const cv::DMatch& d : dm) out.push_back(FromDMatch(d));
  return out;
}

std::vector<Match> MatchOpenCvKnnRatio(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                       double ratio) {
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio=" << ratio);
  CheckPair(descriptors_a, descriptors_b);
  if (descriptors_a.empty() || descriptors_b.empty()) return {};
  cv::BFMatcher matcher(CvNorm(descriptors_a), false);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(descriptors_a, descriptors_b, knn, 2);
  return KnnToRatioMatches(knn, ratio);
}

std::vector<Match> MatchOpenCvCrossCheck(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b) {
  CheckPair(descriptors_a, descriptors_b);
  std::vector<Match> out;
  if (descriptors_a.empty() || descriptors_b.empty()) return out;
  cv::BFMatcher matcher(CvNorm(descriptors_a), true);
  std::vector<cv::DMatch> dm;
  matcher.match(descriptors_a, descriptors_b, dm);
  for (const cv::DMatch& d : dm) out.push_back(FromDMatch(d));
  return out;
}

std::vector<Match> MatchFlannLsh(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                 const FlannLshOptions& options) {
  options.Check();
  CheckPair(descriptors_a, descriptors_b);
  IMUMATCH_CHECK(descriptors_a.empty() || descriptors_a.depth() == CV_8U,
                 "FLANN LSH needs binary (CV_8U) descriptors");
  if (descriptors_a.empty() || descriptors_b.empty()) return {};
  cv::FlannBasedMatcher matcher(
      cv::makePtr<cv::flann::LshIndexParams>(options.table_number, options.key_size,
                                             options.multi_probe_level),
      cv::makePtr<cv::flann::SearchParams>());
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(descriptors_a, descriptors_b, knn, 2);
  return KnnToRatioMatches(knn, options.ratio);
}

}  // namespace imumatch
