#pragma once

#include <cstddef>
#include <cstdint>

namespace imumatch {

// Bilinear samples of an 8-bit image, the inner loops of the patch alignment (patch_alignment.h).
// Pixel centres at integer coordinates: (x, y) = (2, 3) is the pixel in column 2, row 3.
enum class SamplerPath { kAuto, kPortable, kAvx2 };
bool SamplerPathSupported(SamplerPath path);

// The w x h grid of unit steps whose first sample is at (x, y), row-major into out, with one set
// of bilinear weights for all samples (they share the fractional part). The grid and its right and
// lower neighbours must lie inside the image: floor(x) >= 0, floor(y) >= 0,
// floor(x) + w < cols, floor(y) + h < rows. Every path gives the portable path's floats bit for
// bit (the same products and sums in the same order, no fused multiply-add).
void SampleGrid(const uint8_t* data, size_t step, float x, float y, int w, int h, float* out,
                SamplerPath path = SamplerPath::kAuto);

// n samples at (xs[i], ys[i]) (each inside [0, cols - 1) x [0, rows - 1) of an image of `rows`
// rows), bilinear, into out. Same floats on every path.
void SamplePoints(const uint8_t* data, size_t step, int rows, const float* xs, const float* ys,
                  int n, float* out, SamplerPath path = SamplerPath::kAuto);

}  // namespace imumatch
