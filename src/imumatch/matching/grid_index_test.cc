#include "imumatch/matching/grid_index.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

TEST(GridIndexTest, QueryBoxEqualsBruteScan) {
  std::mt19937 rng(11);
  // Points mostly inside a 640x480 image, some outside (clamped into border cells).
  std::uniform_real_distribution<float> ux(-20.0f, 660.0f), uy(-20.0f, 500.0f);
  std::vector<KeypointInfo> pts(3000);
  for (auto& p : pts) {
    p.x = ux(rng);
    p.y = uy(rng);
  }
  // A few exact duplicates and points exactly on cell borders.
  pts[0].x = pts[1].x = 48.0f;
  pts[0].y = pts[1].y = 24.0f;
  for (float cell : {7.0f, 16.0f, 24.0f, 100.0f, 1000.0f}) {
    GridIndex grid;
    grid.Build(pts, 640, 480, cell);
    EXPECT_EQ(grid.size(), 3000);
    std::uniform_real_distribution<float> c(-50.0f, 700.0f), half(0.0f, 80.0f);
    for (int q = 0; q < 300; ++q) {
      const float x = c(rng), y = c(rng), hw = half(rng), hh = half(rng);
      std::vector<int> expected;
      for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
        if (pts[i].x >= x - hw && pts[i].x <= x + hw && pts[i].y >= y - hh && pts[i].y <= y + hh) {
          expected.push_back(i);
        }
      }
      ASSERT_EQ(grid.QueryBox(x - hw, y - hh, x + hw, y + hh), expected) << "cell " << cell;
    }
    // Closed box on exact coordinates, and a degenerate (point) box.
    EXPECT_EQ(grid.QueryBox(48.0f, 24.0f, 48.0f, 24.0f), (std::vector<int>{0, 1}));
    EXPECT_TRUE(grid.QueryBox(10.0f, 10.0f, 5.0f, 20.0f).empty());  // min > max
  }
}

// The capsule's row runs hold every point of the capsule (tested against the exact point-segment
// distance over all points), and for a long oblique segment they read a small part of the points
// that its bounding box would read.
TEST(GridIndexTest, CapsuleRunsHoldEveryPointOfTheCapsule) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> ux(-20.0f, 660.0f), uy(-20.0f, 500.0f);
  std::vector<KeypointInfo> pts(4000);
  for (auto& p : pts) {
    p.x = ux(rng);
    p.y = uy(rng);
  }
  const auto distance2 = [](float px, float py, float x0, float y0, float x1, float y1) {
    const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
    double s = len2 > 0.0 ? ((px - x0) * dx + (py - y0) * dy) / len2 : 0.0;
    s = std::clamp(s, 0.0, 1.0);
    const double ex = px - x0 - s * dx, ey = py - y0 - s * dy;
    return ex * ex + ey * ey;
  };
  std::uniform_real_distribution<float> c(-60.0f, 700.0f), ur(0.0f, 25.0f);
  for (float cell : {4.0f, 8.0f, 32.0f}) {
    GridIndex grid;
    grid.Build(pts, 640, 480, cell);
    for (int q = 0; q < 400; ++q) {
      float x0 = c(rng), y0 = c(rng), x1 = c(rng), y1 = c(rng);
      if (q % 10 == 1) y1 = y0;           // horizontal
      if (q % 10 == 2) x1 = x0;           // vertical
      if (q % 10 == 3) x1 = x0, y1 = y0;  // a point
      const float r = ur(rng);
      // A clipping box: the whole plane, or a part of it.
      const float bx0 = q % 2 ? -1e9f : c(rng), by0 = q % 2 ? -1e9f : c(rng);
      const float bx1 = q % 2 ? 1e9f : bx0 + 300.0f, by1 = q % 2 ? 1e9f : by0 + 300.0f;
      std::vector<int> slots;
      grid.CollectSlotsInCapsule(x0, y0, x1, y1, r, bx0, by0, bx1, by1, &slots);
      std::vector<int> got;
      for (int slot : slots) {
        const int i = grid.slot_index(slot);
        // The runs are a superset (boxes per row): keep the points of the exact capsule.
        if (distance2(pts[i].x, pts[i].y, x0, y0, x1, y1) <= static_cast<double>(r) * r) {
          got.push_back(i);
        }
      }
      std::sort(got.begin(), got.end());
      std::vector<int> expected;
      for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
        const bool in_box =
            pts[i].x >= bx0 && pts[i].x <= bx1 && pts[i].y >= by0 && pts[i].y <= by1;
        const double d2 = distance2(pts[i].x, pts[i].y, x0, y0, x1, y1);
        if (in_box && d2 <= static_cast<double>(r) * r) expected.push_back(i);
      }
      ASSERT_EQ(got, expected) << "cell " << cell << " query " << q;
    }
  }
  // Work: a 500 px diagonal with a 3 px radius reads a few percent of its bounding box's points.
  GridIndex grid;
  grid.Build(pts, 640, 480, 8.0f);
  std::vector<int> slots, box;
  const size_t capsule_scanned =
      grid.CollectSlotsInCapsule(50, 50, 450, 350, 3.0f, -1e9f, -1e9f, 1e9f, 1e9f, &slots);
  const size_t box_scanned = grid.CollectSlotsInBox(47, 47, 453, 353, &box);
  EXPECT_LT(capsule_scanned * 8, box_scanned) << capsule_scanned << " vs " << box_scanned;
  // Bad input: NaN ends or a negative radius give nothing.
  EXPECT_EQ(
      grid.CollectSlotsInCapsule(std::nanf(""), 0, 10, 10, 3, -1e9f, -1e9f, 1e9f, 1e9f, &slots),
      0u);
  EXPECT_TRUE(slots.empty());
  EXPECT_EQ(grid.CollectSlotsInCapsule(0, 0, 10, 10, -1, -1e9f, -1e9f, 1e9f, 1e9f, &slots), 0u);
}

TEST(GridIndexTest, PointsWithoutPositionAreHeldButNeverFound) {
  // A keypoint outside a fisheye's field of view has a NaN ideal position: indexed (slot counts
  // stay those of the input) but in no query's answer, and never converted to a cell by a cast.
  const float nan = std::nanf("");
  const std::vector<float> xs = {10.0f, nan, 300.0f, nan, 5.0f};
  const std::vector<float> ys = {10.0f, 20.0f, nan, nan, 470.0f};
  GridIndex grid;
  grid.Build(xs.data(), ys.data(), static_cast<int>(xs.size()), 640, 480, 8.0f);
  EXPECT_EQ(grid.size(), 5);
  EXPECT_EQ(grid.QueryBox(-1e9f, -1e9f, 1e9f, 1e9f), (std::vector<int>{0, 4}));
  std::vector<int> slots;
  grid.CollectSlotsInCapsule(0, 0, 640, 480, 1e4f, -1e9f, -1e9f, 1e9f, 1e9f, &slots);
  std::vector<int> found;
  for (const int s : slots) found.push_back(grid.slot_index(s));
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found, (std::vector<int>{0, 4}));
}

TEST(GridIndexTest, CallbackGivesCoordinatesAndRebuildReplacesContent) {
  GridIndex grid;
  const float xs[3] = {10.5f, 300.0f, 639.0f}, ys[3] = {20.25f, 200.0f, 479.0f};
  grid.Build(xs, ys, 3, 640, 480, 32.0f);
  EXPECT_EQ(grid.cols(), 20);
  EXPECT_EQ(grid.rows(), 15);
  int calls = 0;
  grid.ForEachInBox(0.0f, 0.0f, 20.0f, 30.0f, [&](int i, float x, float y) {
    ++calls;
    EXPECT_EQ(i, 0);
    EXPECT_EQ(x, 10.5f);
    EXPECT_EQ(y, 20.25f);
  });
  EXPECT_EQ(calls, 1);
  const float xs2[1] = {5.0f}, ys2[1] = {5.0f};
  grid.Build(xs2, ys2, 1, 640, 480, 32.0f);
  EXPECT_EQ(grid.QueryBox(0, 0, 1000, 1000), std::vector<int>{0});
  grid.Build(xs2, ys2, 0, 640, 480, 32.0f);
  EXPECT_TRUE(grid.QueryBox(0, 0, 1000, 1000).empty());
  EXPECT_THROW(grid.Build(xs, ys, 3, 640, 480, 0.0f), InvalidArgument);
  EXPECT_THROW(grid.Build(xs, ys, 3, 0, 480, 16.0f), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
