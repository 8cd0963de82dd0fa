#include "imumatch/matching/grid_index.h"

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
