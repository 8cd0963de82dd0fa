#include "imumatch/matching/bilinear_sampling.h"

#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace imumatch {
namespace {

const SamplerPath kPaths[] = {SamplerPath::kAuto, SamplerPath::kPortable, SamplerPath::kAvx2};

// A rows x cols image of random bytes in a buffer of exactly rows * step bytes.
std::vector<uint8_t> RandomImage(int rows, size_t step, std::mt19937* rng) {
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<uint8_t> img(static_cast<size_t>(rows) * step);
  for (uint8_t& b : img) b = static_cast<uint8_t>(byte(*rng));
  return img;
}

bool SameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(BilinearSamplingTest, HandComputedValues) {
  // 3 x 4 image, step 4: row r holds 10 r + c... with one bright pixel.
  const uint8_t img[] = {0,  10, 20,  30,   //
                         40, 50, 60,  200,  //
                         80, 90, 100, 110};
  for (SamplerPath path : kPaths) {
    if (!SamplerPathSupported(path)) continue;
    float out[3];
    // (1.25, 0.5): top 10 + 0.25 * 10 = 12.5, bottom 50 + 0.25 * 10 = 52.5, mean 32.5.
    const float xs[] = {1.25f, 2.5f, 0.0f}, ys[] = {0.5f, 1.0f, 1.75f};
    SamplePoints(img, 4, 3, xs, ys, 3, out, path);
    EXPECT_FLOAT_EQ(out[0], 32.5f);
    EXPECT_FLOAT_EQ(out[1], 130.0f);  // 60 + 0.5 * 140 on row 1 (weight 0 on row 2)
    EXPECT_FLOAT_EQ(out[2], 70.0f);   // 40 + 0.75 * 40
    // A 2 x 1 grid from (1.5, 1.0): 55 and 130.
    float grid[2];
    SampleGrid(img, 4, 1.5f, 1.0f, 2, 1, grid, path);
    EXPECT_FLOAT_EQ(grid[0], 55.0f);
    EXPECT_FLOAT_EQ(grid[1], 130.0f);
  }
}

TEST(BilinearSamplingTest, EveryPathGivesThePortableFloats) {
  std::mt19937 rng(5);
  const int rows = 37, cols = 45;
  for (const size_t step : {static_cast<size_t>(cols), static_cast<size_t>(cols + 19)}) {
    const std::vector<uint8_t> img = RandomImage(rows, step, &rng);
    std::uniform_real_distribution<float> frac(0.0f, 0.999f);
    for (int w : {1, 3, 7, 8, 9, 11, 16, 17, 19}) {
      for (int h : {1, 9, 19}) {
        for (int trial = 0; trial < 20; ++trial) {
          // The grid anywhere it fits, including against the right and lower edges.
          std::uniform_int_distribution<int> x0(0, cols - 1 - w), y0(0, rows - 1 - h);
          const float x = (trial % 4 == 0 ? cols - 1 - w : x0(rng)) + frac(rng);
          const float y = (trial % 4 == 1 ? rows - 1 - h : y0(rng)) + frac(rng);
          std::vector<float> want(static_cast<size_t>(w) * h), got(want.size());
          SampleGrid(img.data(), step, x, y, w, h, want.data(), SamplerPath::kPortable);
          for (SamplerPath path : kPaths) {
            if (!SamplerPathSupported(path)) continue;
            SampleGrid(img.data(), step, x, y, w, h, got.data(), path);
            for (size_t k = 0; k < want.size(); ++k) {
              ASSERT_TRUE(SameBits(got[k], want[k])) << w << "x" << h << " at " << x << "," << y;
            }
          }
        }
      }
    }
    // Points: every count 0..20, anywhere in [0, cols - 1) x [0, rows - 1), many in the last
    // row and column.
    std::uniform_real_distribution<float> px(0.0f, cols - 1.001f), py(0.0f, rows - 1.001f);
    for (int n = 0; n <= 20; ++n) {
      std::vector<float> xs(n), ys(n), want(n), got(n);
      for (int i = 0; i < n; ++i) {
        xs[i] = i % 3 == 0 ? cols - 2 + frac(rng) : px(rng);
        ys[i] = i % 2 == 0 ? rows - 2 + frac(rng) : py(rng);
      }
      SamplePoints(img.data(), step, rows, xs.data(), ys.data(), n, want.data(),
                   SamplerPath::kPortable);
      for (SamplerPath path : kPaths) {
        if (!SamplerPathSupported(path)) continue;
        SamplePoints(img.data(), step, rows, xs.data(), ys.data(), n, got.data(), path);
        for (int i = 0; i < n; ++i) {
          ASSERT_TRUE(SameBits(got[i], want[i])) << xs[i] << "," << ys[i] << " n=" << n;
        }
      }
    }
  }
}

}  // namespace
}  // namespace imumatch
