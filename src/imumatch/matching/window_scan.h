#pragma once

#include "imumatch/matching/brute_force_kernels.h"

namespace imumatch {

// The guided search's innermost loop: which keypoints of B in a run of grid slots lie inside one
// query's window, and which of those agree with the predicted rotation and scale. Without a
// branch per candidate (about half of a run fails the box test), on 16 (AVX-512) or 8 (AVX2)
// candidates at a time, or one (portable); every path gives the same lists, in slot order.

// B's keypoints as the tests read them, in the grid's slot order, one array per field. Angles are
// in [0, 360) or -1 (no angle), sizes > 0 or 0 (no size check).
struct CandidateView {
  const float* x = nullptr;
  const float* y = nullptr;
  const float* angle_deg = nullptr;
  const float* size = nullptr;
};

// One query's tests: inside the window (box, and capsule for a prediction without depth: within
// sqrt(r2) of the segment start + s (dx, dy), s in [0, 1]), orientation and size consistent with
// the prediction.
struct CandidateTest {
  float expected_angle, orient_tol, size_lo, size_hi;
  bool check_angle, check_size;
  float start_x, start_y, dx, dy, r2;
};

// Tests slots [begin, end) against the box [lo_x, hi_x] x [lo_y, hi_y] (and the capsule) and
// appends those inside to consistent_slot (consistent with the prediction: possible matches) or,
// when keep_inconsistent is 1, to rival_slot (rivals in the ratio test only), advancing *num_*.
// Each list needs room for (end - begin) + kWindowScanSlack more entries: the vector paths store
// whole registers. Returns flags of the run: bit 0 some candidate inside the window, bit 1 some
// inside with a consistent angle.
constexpr int kWindowScanSlack = 16;
using WindowScanFn = int (*)(const CandidateTest& test, const CandidateView& b, int begin, int end,
                             float lo_x, float hi_x, float lo_y, float hi_y, int keep_inconsistent,
                             int* consistent_slot, int* num_consistent, int* rival_slot,
                             int* num_rivals);

// The test for windows with a capsule (prediction without depth) or a box only, on the given
// path: kAuto = AVX-512F when the CPU has the brute force's AVX-512 path, else AVX2, else portable;
// kPopcnt runs the portable test (it has no vector form). A forced path the CPU lacks throws
// InvalidArgument.
WindowScanFn SelectWindowScan(bool capsule, BruteForceKernel kernel);

}  // namespace imumatch
