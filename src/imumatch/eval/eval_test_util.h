#pragma once

// Test-only helpers shared by the evaluation tests (not installed).

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/eval/summary.h"

namespace imumatch {

// The summary row of one case, detector and method; a test failure (and an empty row) if absent.
inline const MethodSummary& Row(const std::vector<MethodSummary>& rows, const std::string& c,
                                DetectorKind d, MatchMethod m) {
  for (const auto& r : rows) {
    if (r.case_name == c && r.detector == d && r.method == m) return r;
  }
  ADD_FAILURE() << "no row " << c << " " << ToString(d) << " " << ToString(m);
  static const MethodSummary empty;
  return empty;
}

}  // namespace imumatch
