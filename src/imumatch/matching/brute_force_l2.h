#pragma once

#include "imumatch/matching/brute_force_kernels.h"
#include "imumatch/matching/descriptor_distance.h"

// The squared-L2 paths of NearestTwo (brute_force_kernels.h) and what all its paths share
// (the x86 switch, the nearest-two update, the merge of a vector kernel's lanes), internal to the
// matching library. Every L2 path sums in one order (L2Canonical's), so that all give the same
// bits.

#include <algorithm>
#include <limits>

#if defined(__x86_64__) || defined(__i386__)
#define IMUMATCH_BF_X86 1
#else
#define IMUMATCH_BF_X86 0
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

// Query i's nearest two from the lanes of a vector kernel, each lane's (best, second, index) over
// its own train rows: the best lane's best, ties to the earliest index, and the least of the
// other lanes' bests and all lanes' seconds. A lane whose best is not below far kept no row. What
// one pass over the train rows in order gives (UpdateNearest2).
template <typename Cost, typename Index>
void MergeLaneNearest2(const Cost* best, const Cost* second, const Index* idx, int lanes, Cost far,
                       int i, Nearest2& out) {
  int star = -1;
  for (int l = 0; l < lanes; ++l) {
    if (best[l] >= far) continue;
    if (star < 0 || best[l] < best[star] || (best[l] == best[star] && idx[l] < idx[star])) {
      star = l;
    }
  }
  if (star < 0) return;
  Cost sec = far;
  for (int l = 0; l < lanes; ++l) {
    sec = std::min(sec, second[l]);
    if (l != star) sec = std::min(sec, best[l]);
  }
  out.best[i] = static_cast<float>(best[star]);
  out.best_idx[i] = static_cast<int>(idx[star]);
  out.second[i] = sec < far ? static_cast<float>(sec) : std::numeric_limits<float>::infinity();
}

// Squared L2 distance of two rows of dims floats: element k into partial sum k mod 16 in
// increasing k (a multiply, then an add: never fused), the 16 partials added as the fixed tree
// (((p0 + p8) + (p4 + p12)) + ((p2 + p10) + (p6 + p14))) +
// (((p1 + p9) + (p5 + p13)) + ((p3 + p11) + (p7 + p15))). The reference of every path.
float L2Canonical(const float* a, const float* b, int dims);

// Nearest two of every row of a among the rows of b (out reset by the caller), ties to the lowest
// index: portable C++, and on x86 AVX2 and AVX-512F (the caller checks that the CPU has them).
void NearestTwoL2Scalar(const DescriptorView& a, const DescriptorView& b, Nearest2& out);
#if IMUMATCH_BF_X86
void NearestTwoL2Avx2(const DescriptorView& a, const DescriptorView& b, Nearest2& out);
void NearestTwoL2Avx512(const DescriptorView& a, const DescriptorView& b, Nearest2& out);
#endif

}  // namespace imumatch
