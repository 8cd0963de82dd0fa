#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "imumatch/core/error.h"

namespace imumatch {

// The element at index size() / 2 of v once sorted: the median of an odd count, the upper of the
// two middle elements of an even one (always a sample, never an average across a gap). Reorders
// v (std::nth_element, O(n)). Throws InvalidArgument when v is empty.
template <typename T>
T UpperMedianInPlace(std::vector<T>& v) {
  IMUMATCH_CHECK(!v.empty(), "UpperMedianInPlace of an empty vector");
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// The median of v: the middle element of an odd count, the mean of the two middle elements of an
// even one. v is a copy (the caller's order is kept). Throws InvalidArgument when v is empty.
inline double Median(std::vector<double> v) {
  const double hi = UpperMedianInPlace(v);
  if (v.size() % 2 == 1) return hi;
  const double lo =
      *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2));
  return 0.5 * (lo + hi);
}

}  // namespace imumatch
