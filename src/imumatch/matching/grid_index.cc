#include "imumatch/matching/grid_index.h"

#include <cstddef>
#include <cstring>

#include "imumatch/core/error.h"

namespace imumatch {

void GridIndex::Build(const float* xs, const float* ys, int n, int width, int height,
                      float cell_size) {
  BuildStrided(reinterpret_cast<const unsigned char*>(xs),
               reinterpret_cast<const unsigned char*>(ys), sizeof(float), n, width, height,
               cell_size);
}

void GridIndex::BuildStrided(const unsigned char* xs, const unsigned char* ys, size_t stride, int n,
                             int width, int height, float cell_size) {
  const auto x_at = [xs, stride](int i) {
    float v;
    std::memcpy(&v, xs + static_cast<size_t>(i) * stride, sizeof(float));
    return v;
  };
  const auto y_at = [ys, stride](int i) {
    float v;
    std::memcpy(&v, ys + static_cast<size_t>(i) * stride, sizeof(float));
    return v;
  };
  IMUMATCH_CHECK(n >= 0, "n=" << n);
  IMUMATCH_CHECK(width > 0 && height > 0, "grid size " << width << "x" << height);
  IMUMATCH_CHECK(std::isfinite(cell_size) && cell_size > 0.0f, "cell_size=" << cell_size);
  cell_size_ = cell_size;
  inv_cell_ = 1.0f / cell_size;
  cols_ = std::max(1, static_cast<int>(std::ceil(static_cast<float>(width) * inv_cell_)));
  rows_ = std::max(1, static_cast<int>(std::ceil(static_cast<float>(height) * inv_cell_)));
  const int cells = cols_ * rows_;
  cell_start_.assign(static_cast<size_t>(cells) + 1, 0);
  cell_of_.resize(n);
  index_.resize(n);
  xy_.resize(2 * static_cast<size_t>(n));
  // Counting sort: histogram, exclusive prefix sum, scatter.
  for (int i = 0; i < n; ++i) {
    // NaN coordinates land in cell 0 and never satisfy a box test.
    const int cell = CellRow(y_at(i)) * cols_ + CellCol(x_at(i));
    cell_of_[i] = cell;
    ++cell_start_[cell + 1];
  }
  for (int c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  // cell_start_[c] is now the first slot of cell c; scatter with a moving cursor per cell.
  cursor_.assign(cell_start_.begin(), cell_start_.end() - 1);
  for (int i = 0; i < n; ++i) {
    const int slot = cursor_[cell_of_[i]]++;
    index_[slot] = i;
    xy_[2 * slot] = x_at(i);
    xy_[2 * slot + 1] = y_at(i);
  }
}

void GridIndex::Build(const std::vector<KeypointInfo>& keypoints, int width, int height,
                      float cell_size) {
  const auto* base = reinterpret_cast<const unsigned char*>(keypoints.data());
  BuildStrided(base + offsetof(KeypointInfo, x), base + offsetof(KeypointInfo, y),
               sizeof(KeypointInfo), static_cast<int>(keypoints.size()), width, height, cell_size);
}

void GridIndex::AppendSlotsInBox(int begin, int end, float min_x, float max_x, float min_y,
                                 float max_y, std::vector<int>* out) const {
  const size_t base = out->size();
  out->resize(base + static_cast<size_t>(end - begin));
  int* dst = out->data() + base;
  size_t count = 0;
  for (int k = begin; k < end; ++k) {
    const float x = xy_[2 * k], y = xy_[2 * k + 1];
    dst[count] = k;
    count += static_cast<size_t>((x >= min_x) & (x <= max_x) & (y >= min_y) & (y <= max_y));
  }
  out->resize(base + count);
}

size_t GridIndex::CollectSlotsInBox(float min_x, float min_y, float max_x, float max_y,
                                    std::vector<int>* out) const {
  out->clear();
  size_t scanned = 0;
  ForEachRunInBox(min_x, min_y, max_x, max_y,
                  [&](int begin, int end, float lo_x, float hi_x, float lo_y, float hi_y) {
                    scanned += static_cast<size_t>(end - begin);
                    AppendSlotsInBox(begin, end, lo_x, hi_x, lo_y, hi_y, out);
                  });
  return scanned;
}

size_t GridIndex::CollectSlotsInCapsule(float x0, float y0, float x1, float y1, float radius,
                                        float min_x, float min_y, float max_x, float max_y,
                                        std::vector<int>* out) const {
  out->clear();
  size_t scanned = 0;
  ForEachRunInCapsule(x0, y0, x1, y1, radius, min_x, min_y, max_x, max_y,
                      [&](int begin, int end, float lo_x, float hi_x, float lo_y, float hi_y) {
                        scanned += static_cast<size_t>(end - begin);
                        AppendSlotsInBox(begin, end, lo_x, hi_x, lo_y, hi_y, out);
                      });
  return scanned;
}

std::vector<int> GridIndex::QueryBox(float min_x, float min_y, float max_x, float max_y) const {
  std::vector<int> out;
  ForEachInBox(min_x, min_y, max_x, max_y, [&out](int i, float, float) { out.push_back(i); });
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace imumatch
