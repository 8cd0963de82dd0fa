#include "imumatch/matching/window_scan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

// The window test written out per candidate with branches, from its contract (window_scan.h).
struct Expected {
  std::vector<int> consistent, rivals;
  int flags = 0;
};
Expected Reference(const CandidateTest& t, const CandidateView& b, int begin, int end, float lo_x,
                   float hi_x, float lo_y, float hi_y, bool keep_inconsistent, bool capsule) {
  Expected e;
  const float len2 = t.dx * t.dx + t.dy * t.dy;
  for (int k = begin; k < end; ++k) {
    bool in = b.x[k] >= lo_x && b.x[k] <= hi_x && b.y[k] >= lo_y && b.y[k] <= hi_y;
    if (capsule) {
      const float px = b.x[k] - t.start_x, py = b.y[k] - t.start_y;
      float s = len2 > 0.0f ? (px * t.dx + py * t.dy) / len2 : 0.0f;
      s = s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s);
      const float ex = px - s * t.dx, ey = py - s * t.dy;
      in = in && ex * ex + ey * ey <= t.r2;
    }
    if (!in) continue;
    bool angle_ok = true;
    if (t.check_angle && b.angle_deg[k] >= 0.0f) {
      const float d = std::fabs(b.angle_deg[k] - t.expected_angle);
      angle_ok = (d < 360.0f - d ? d : 360.0f - d) <= t.orient_tol;
    }
    bool size_ok = true;
    if (t.check_size && b.size[k] > 0.0f) {
      size_ok = b.size[k] >= t.size_lo && b.size[k] <= t.size_hi;
    }
    e.flags |= 1 | (angle_ok ? 2 : 0);
    if (angle_ok && size_ok) {
      e.consistent.push_back(k);
    } else if (keep_inconsistent) {
      e.rivals.push_back(k);
    }
  }
  return e;
}

// Every path against the reference: runs of every length 0..40 at every offset modulo 16 (the
// vector tails), points on the box's edges and the capsule's rim, missing angles and sizes,
// checks on and off, rivals kept or not; the lists must be equal entry for entry.
TEST(WindowScanTest, EveryPathEqualsTheReference) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const int m = 400;
  std::vector<float> x(m), y(m), angle(m), size(m);
  for (int k = 0; k < m; ++k) {
    // A 40 x 40 px patch on a 0.5 px lattice (many points exactly on edges), some off-lattice.
    x[k] = k % 3 == 0 ? 100.0f + 40.0f * u(rng) : 100.0f + 0.5f * static_cast<float>(rng() % 81);
    y[k] = k % 3 == 1 ? 200.0f + 40.0f * u(rng) : 200.0f + 0.5f * static_cast<float>(rng() % 81);
    angle[k] = k % 7 == 0   ? -1.0f
               : k % 5 == 0 ? 15.0f * static_cast<float>(rng() % 24)
                            : 360.0f * u(rng);
    if (angle[k] >= 360.0f) angle[k] = 0.0f;
    size[k] = k % 11 == 0  ? 0.0f
              : k % 4 == 0 ? 10.0f * static_cast<float>(1 + rng() % 4)
                           : 5.0f + 40.0f * u(rng);
  }
  CandidateView view;
  view.x = x.data();
  view.y = y.data();
  view.angle_deg = angle.data();
  view.size = size.data();
  int checked = 0, non_empty = 0;
  for (int trial = 0; trial < 60; ++trial) {
    CandidateTest t;
    t.expected_angle = trial % 4 == 0 ? 0.0f : 15.0f * static_cast<float>(trial % 24);
    t.orient_tol = 30.0f;
    t.size_lo = 10.0f;
    t.size_hi = 30.0f;
    t.check_angle = trial % 5 != 0;
    t.check_size = trial % 6 != 0;
    t.start_x = 110.0f + 0.5f * static_cast<float>(trial % 20);
    t.start_y = 210.0f;
    t.dx = trial % 7 == 0 ? 0.0f : 20.0f;  // a point segment, or a diagonal one
    t.dy = trial % 7 == 0 ? 0.0f : 10.0f;
    t.r2 = trial % 3 == 0 ? 25.0f : 6.25f;
    const float lo_x = 100.0f + 0.5f * static_cast<float>(trial % 9), hi_x = lo_x + 20.0f;
    const float lo_y = 200.0f + 0.5f * static_cast<float>(trial % 11), hi_y = lo_y + 15.0f;
    for (int begin = trial % 16; begin + 40 <= m; begin += 97) {
      for (int len = 0; len <= 40; ++len) {
        for (const bool capsule : {false, true}) {
          for (const int keep : {0, 1}) {
            const Expected e =
                Reference(t, view, begin, begin + len, lo_x, hi_x, lo_y, hi_y, keep, capsule);
            non_empty += !e.consistent.empty() && !e.rivals.empty();
            for (const BruteForceKernel kernel : AvailableBruteForceKernels()) {
              std::vector<int> consistent(3 + len + kWindowScanSlack, -7),
                  rivals(2 + len + kWindowScanSlack, -7);
              int nc = 3, ni = 2;  // appended after entries already there
              const int flags = SelectWindowScan(capsule, kernel)(
                  t, view, begin, begin + len, lo_x, hi_x, lo_y, hi_y, keep, consistent.data(), &nc,
                  rivals.data(), &ni);
              const std::vector<int> got_c(consistent.begin() + 3, consistent.begin() + nc);
              const std::vector<int> got_r(rivals.begin() + 2, rivals.begin() + ni);
              ASSERT_EQ(got_c, e.consistent) << ToString(kernel) << " trial " << trial << " begin "
                                             << begin << " len " << len << " capsule " << capsule;
              ASSERT_EQ(got_r, e.rivals) << ToString(kernel) << " trial " << trial;
              ASSERT_EQ(flags, e.flags) << ToString(kernel) << " trial " << trial;
              EXPECT_EQ(consistent[0], -7);  // nothing before the lists' ends is touched
              EXPECT_EQ(rivals[1], -7);
              ++checked;
            }
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 60 * 4 * 41 * 4);
  EXPECT_GT(non_empty, 1000);  // runs with both kinds of candidates, not only empty ones
}

TEST(WindowScanTest, AnyPathTheCpuLacksIsRefused) {
  const std::vector<BruteForceKernel> have = AvailableBruteForceKernels();
  for (const BruteForceKernel k : {BruteForceKernel::kAvx2, BruteForceKernel::kAvx512}) {
    if (std::find(have.begin(), have.end(), k) == have.end()) {
      EXPECT_THROW(SelectWindowScan(false, k), InvalidArgument);
    } else {
      EXPECT_NE(SelectWindowScan(true, k), nullptr);
    }
  }
  EXPECT_NE(SelectWindowScan(false, BruteForceKernel::kAuto), nullptr);
}

}  // namespace
}  // namespace imumatch
