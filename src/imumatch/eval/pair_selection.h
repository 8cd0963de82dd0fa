#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "imumatch/io/dataset.h"

namespace imumatch {

struct FramePair {
  size_t a = 0;
  size_t b = 0;
};

struct PairSelection {
  // Exactly one mode: explicit pairs (non-empty), an interval in seconds (> 0: b is the frame
  // nearest to t_a + interval, the next a is that b), or a step in frames (a, a + step), a
  // advancing by step. Default: consecutive frames (step 1).
  std::vector<FramePair> explicit_pairs;
  double interval_s = 0.0;
  int step = 1;
  size_t max_pairs = 0;  // 0 = all
  void Check() const;
};

// Throws InvalidArgument for explicit pairs outside the frame list or with a >= b.
std::vector<FramePair> SelectFramePairs(const std::vector<FrameRecord>& frames,
                                        const PairSelection& selection);

// Why SelectFramePairs found no pair, for an error message: the frame count and span, and which
// rule left none ("40 frames over 1.3 s, none with a partner 100 s later (--interval)").
std::string WhyNoFramePairs(const std::vector<FrameRecord>& frames, const PairSelection& selection);

}  // namespace imumatch
