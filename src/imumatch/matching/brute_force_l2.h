#pragma once

#include "imumatch/matching/brute_force_kernels.h"
#include "imumatch/matching/descriptor_distance.h"

// The squared-L2 paths of NearestTwo (brute_force_kernels.h) and the nearest-two update that all
// its paths share, internal to the matching library. Every L2 path sums in one order
// (L2Canonical's), so that all give the same bits.

#if defined(__x86_64__) || defined(__i386__)
#define IMUMATCH_BF_L2_X86 1
#else
#define IMUMATCH_BF_L2_X86 0
#endif

namespace imumatch {

// One train row's cost d (index j) into a query's nearest two: what every path keeps, ties to the
// earliest index.
__attribute__((always_inline)) inline void UpdateNearest2(float d, int j, float& best,
                                                          float& second, int& best_idx) {
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

// Squared L2 distance of two rows of dims floats: element k into partial sum k mod 16 in
// increasing k (a multiply, then an add: never fused), the 16 partials added as the fixed tree
// (((p0 + p8) + (p4 + p12)) + ((p2 + p10) + (p6 + p14))) +
// (((p1 + p9) + (p5 + p13)) + ((p3 + p11) + (p7 + p15))). The reference of every path.
float L2Canonical(const float* a, const float* b, int dims);

// Nearest two of every row of a among the rows of b (out reset by the caller), ties to the lowest
// index: portable C++, and on x86 AVX2 and AVX-512F (the caller checks that the CPU has them).
void NearestTwoL2Scalar(const DescriptorView& a, const DescriptorView& b, Nearest2& out);
#if IMUMATCH_BF_L2_X86
void NearestTwoL2Avx2(const DescriptorView& a, const DescriptorView& b, Nearest2& out);
void NearestTwoL2Avx512(const DescriptorView& a, const DescriptorView& b, Nearest2& out);
#endif

}  // namespace imumatch
