#pragma once

#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/matching/match_types.h"

namespace imumatch {

// Unguided baselines on the same descriptors, all returning imumatch::Match (second_distance is
// +inf where the method does not produce one; predicted_uv is NaN).

// The instruction-set paths of the exhaustive matcher. kAuto picks the fastest the CPU has (checked
// at run time: one binary runs everywhere); the others force a path, for tests and benchmarks, and
// throw InvalidArgument when the CPU lacks it. Every path gives the same matches bit for bit.
enum class BruteForceKernel {
  kAuto,
  kScalar,  // portable C++ (no POPCNT instruction)
  kPopcnt,  // 64-bit POPCNT, 4 queries per pass; L2: SSE2 (Hamming only differs from scalar)
  kAvx2,    // Hamming: nibble-table popcount (PSHUFB) over 4 descriptors per register; L2: AVX2+FMA
  kAvx512,  // Hamming: VPOPCNTQ over 8 descriptors per register; L2: AVX-512F FMA
};
const char* ToString(BruteForceKernel kernel);
// The paths this CPU can run, kScalar first, the fastest last (what kAuto uses).
std::vector<BruteForceKernel> AvailableBruteForceKernels();
// The CPU features the fast paths look for, e.g. "popcnt avx2 fma avx512f avx512vpopcntdq".
std::string CpuFeaturesString();

struct BruteForceOptions {
  // Lowe's ratio test on distances: keep best < ratio * second. 1 disables it (every query keeps
  // its nearest neighbour).
  double ratio = 1.0;
  // Drop matches whose distance exceeds this (Hamming bits or L2 distance).
  double max_distance = std::numeric_limits<double>::infinity();
  // Keep i -> j only when i is also j's nearest neighbour in A.
  bool cross_check = false;
  BruteForceKernel kernel = BruteForceKernel::kAuto;
  void Check() const;
};

// Our own exhaustive nearest + second-nearest search: blocked over 4 queries x 256-row chunks of
// B so each B descriptor loaded is compared with 4 queries from registers and a chunk stays in L1;
// POPCNT (Hamming, 32/64-byte specialisations) or AVX2+FMA (L2) kernels when the CPU has them
// (run-time check), portable code otherwise. Single thread.
std::vector<Match> MatchBruteForce(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                   const BruteForceOptions& options);

// cv::BFMatcher(NORM_HAMMING or NORM_L2)::match: nearest neighbour of every query.
std::vector<Match> MatchOpenCvBruteForce(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b);
// cv::BFMatcher::knnMatch(k=2) + ratio test (best < ratio * second; a single neighbour passes).
std::vector<Match> MatchOpenCvKnnRatio(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                       double ratio);
// cv::BFMatcher(norm, crossCheck=true)::match.
std::vector<Match> MatchOpenCvCrossCheck(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b);

struct FlannLshOptions {
  int table_number = 6;
  int key_size = 12;
  int multi_probe_level = 1;
  double ratio = 0.8;
  void Check() const;
};
// cv::FlannBasedMatcher with LshIndexParams (binary descriptors only) + knnMatch(k=2) + ratio.
// Approximate: may miss neighbours. Index build is included (trained on B at each call).
std::vector<Match> MatchFlannLsh(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                 const FlannLshOptions& options);

}  // namespace imumatch
