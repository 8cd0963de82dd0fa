#pragma once

#include <string>
#include <vector>

#include "imumatch/matching/descriptor_distance.h"

namespace imumatch {

// The exhaustive nearest + second-nearest search under every brute-force baseline of our own
// (MatchBruteForce in baseline_matchers.h), with one kernel per instruction set.

// The instruction-set paths of the exhaustive matcher. kAuto picks the fastest the CPU has (checked
// at run time: one binary runs everywhere); the others force a path, for tests and benchmarks, and
// throw InvalidArgument when the CPU lacks it. Every path gives the same matches bit for bit.
enum class BruteForceKernel {
  kAuto,
  kScalar,  // portable C++ (no POPCNT instruction)
  kPopcnt,  // 64-bit POPCNT, 4 queries per pass; L2: the portable path (Hamming only differs)
  kAvx2,    // Hamming: nibble-table popcount (PSHUFB) over 4 descriptors per register; L2: AVX2,
            // 8 train rows per pass
  kAvx512,  // Hamming: VPOPCNTQ over 8 descriptors per register, 2 queries per pass; L2:
            // AVX-512F, 16 train rows per pass
};
const char* ToString(BruteForceKernel kernel);
// The paths this CPU can run, kScalar first, the fastest last (what kAuto uses).
std::vector<BruteForceKernel> AvailableBruteForceKernels();
// The CPU features the fast paths look for, e.g. "popcnt avx2 fma avx512f avx512vpopcntdq".
std::string CpuFeaturesString();

// Best and second-best cost per query (Hamming bits or squared L2, see descriptor_distance.h)
// and the best's index in B (-1: none; ties go to the lowest index on every path).
struct Nearest2 {
  std::vector<float> best, second;
  std::vector<int> best_idx;
  void Reset(int n);
};

// Every query row of a against every row of b. Hamming: AVX-512 VPOPCNTQ or AVX2 nibble-table
// popcount over B transposed into blocks of train rows (each lane keeps its own nearest two), or
// 64-bit POPCNT blocked over 4 queries x 256-row chunks of b (a chunk stays in L1). L2: AVX-512F
// or AVX2 over blocks of 16 / 8 train rows that stay in L1 while every query passes over them,
// in one fixed summation order without fused multiply-adds (brute_force_l2.h), so that every
// path gives the same bits as the portable one. kAuto: the fastest path the CPU has; a forced
// path the CPU lacks throws InvalidArgument.
void NearestTwo(const DescriptorView& a, const DescriptorView& b, BruteForceKernel kernel,
                Nearest2& out);

}  // namespace imumatch
