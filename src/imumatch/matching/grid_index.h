#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "imumatch/matching/match_types.h"

namespace imumatch {

// A uniform grid over one frame's keypoints for window queries. Build is O(n + cells) with a
// counting sort into flat arrays (no per-cell containers); the points of a cell are stored
// contiguously with their coordinates, so a query reads only the cells its box touches. Points
// outside [0, width) x [0, height) are kept in the border cells (a query still finds them by their
// exact coordinates). Build() reuses the arrays' capacity, so rebuilding per frame does not
// allocate once warmed up.
class GridIndex {
 public:
  GridIndex() = default;

  // xs/ys: n coordinates. cell_size in pixels (> 0), width/height > 0. Throws InvalidArgument.
  void Build(const float* xs, const float* ys, int n, int width, int height, float cell_size);
  void Build(const std::vector<KeypointInfo>& keypoints, int width, int height, float cell_size);

  int size() const { return static_cast<int>(index_.size()); }
  int cols() const { return cols_; }
  int rows() const { return rows_; }
  float cell_size() const { return cell_size_; }

  // Calls f(index, x, y) for every point with min_x <= x <= max_x and min_y <= y <= max_y
  // (closed box). index is the point's position in the arrays given to Build.
  template <typename F>
  void ForEachInBox(float min_x, float min_y, float max_x, float max_y, F&& f) const {
    // The box test is branch-free: slots are appended to a small buffer and the buffer is handed to
    // f afterwards (about half the scanned points fail the test, a branch would mispredict a lot).
    constexpr int kBuffer = 64;
    int hits[kBuffer];
    int count = 0;
    const auto flush = [&] {
      for (int h = 0; h < count; ++h) f(index_[hits[h]], xy_[2 * hits[h]], xy_[2 * hits[h] + 1]);
      count = 0;
    };
    ForEachRunInBox(
        min_x, min_y, max_x, max_y, [&](int begin, int end, float, float, float, float) {
          for (int k = begin; k < end; ++k) {
            const float x = xy_[2 * k], y = xy_[2 * k + 1];
            hits[count] = k;
            count += static_cast<int>((x >= min_x) & (x <= max_x) & (y >= min_y) & (y <= max_y));
            if (count == kBuffer) flush();
          }
        });
    flush();
  }

  // Replaces *out with the slots of the points inside the closed box, in grid order: positions in
  // the grid's cell-sorted order (slot_index(slot) is the point's original index; data copied into
  // slot order is read contiguously by window queries). The buffer's capacity is reused across
  // calls. Returns the number of points read (the points of every cell the box touches).
  size_t CollectSlotsInBox(float min_x, float min_y, float max_x, float max_y,
                           std::vector<int>* out) const;
  // Slots of the points inside the capsule {p : distance(p, segment (x0,y0)-(x1,y1)) <= radius}
  // clipped to the closed box, as a superset: each cell row is scanned only over the x-range the
  // capsule covers within that row's band, so a long oblique segment reads O(length x radius)
  // points instead of its bounding box's (the caller applies the exact capsule test). Returns the
  // number of points read.
  size_t CollectSlotsInCapsule(float x0, float y0, float x1, float y1, float radius, float min_x,
                               float min_y, float max_x, float max_y, std::vector<int>* out) const;
  // The slot runs a window query reads: for each cell row the box (or capsule) touches, calls
  // f(begin, end, min_x, max_x, min_y, max_y) with the contiguous slots [begin, end) of the cells
  // it spans in that row and the closed box that the row's points must lie in (a superset test:
  // the capsule's exact test is the caller's). Callers that keep data in slot order then test the
  // slots of a run in one tight loop.
  template <typename F>
  void ForEachRunInBox(float min_x, float min_y, float max_x, float max_y, F&& f) const {
    if (index_.empty() || !(min_x <= max_x) || !(min_y <= max_y)) return;
    const int c0 = CellCol(min_x), c1 = CellCol(max_x);
    for (int r = CellRow(min_y), r1 = CellRow(max_y); r <= r1; ++r) {
      const int begin = cell_start_[r * cols_ + c0], end = cell_start_[r * cols_ + c1 + 1];
      if (begin < end) f(begin, end, min_x, max_x, min_y, max_y);
    }
  }
  // Each cell row is read only over the x-range the capsule {p : distance(p, segment (x0,y0)-
  // (x1,y1)) <= radius} covers within that row's band (clipped to the box), so a long oblique
  // segment reads O(length x radius) points instead of its bounding box's.
  template <typename F>
  void ForEachRunInCapsule(float x0, float y0, float x1, float y1, float radius, float min_x,
                           float min_y, float max_x, float max_y, F&& f) const {
    if (index_.empty() || !(radius >= 0.0f) || !std::isfinite(x0) || !std::isfinite(y0) ||
        !std::isfinite(x1) || !std::isfinite(y1)) {
      return;
    }
    min_x = std::max(min_x, std::min(x0, x1) - radius);
    max_x = std::min(max_x, std::max(x0, x1) + radius);
    min_y = std::max(min_y, std::min(y0, y1) - radius);
    max_y = std::min(max_y, std::max(y0, y1) + radius);
    if (!(min_x <= max_x) || !(min_y <= max_y)) return;
    const float dx = x1 - x0, dy = y1 - y0;
    const float inf = std::numeric_limits<float>::infinity();
    for (int r = CellRow(min_y), r1 = CellRow(max_y); r <= r1; ++r) {
      // The row's band of y (border rows also hold the points beyond the grid), within the box.
      const float band_lo = std::max(min_y, r == 0 ? -inf : static_cast<float>(r) * cell_size_);
      const float band_hi =
          std::min(max_y, r == rows_ - 1 ? inf : static_cast<float>(r + 1) * cell_size_);
      if (!(band_lo <= band_hi)) continue;
      // Points of the capsule with y in the band lie within radius of segment points with y in
      // [band_lo - radius, band_hi + radius]: the x-range of those, widened by the radius.
      float s_lo = 0.0f, s_hi = 1.0f;
      if (dy != 0.0f) {
        const float a = (band_lo - radius - y0) / dy, b = (band_hi + radius - y0) / dy;
        s_lo = std::max(0.0f, std::min(a, b));
        s_hi = std::min(1.0f, std::max(a, b));
        if (!(s_lo <= s_hi)) continue;
      }
      const float xa = x0 + s_lo * dx, xb = x0 + s_hi * dx;
      const float row_min_x = std::max(min_x, std::min(xa, xb) - radius);
      const float row_max_x = std::min(max_x, std::max(xa, xb) + radius);
      if (!(row_min_x <= row_max_x)) continue;
      const int begin = cell_start_[r * cols_ + CellCol(row_min_x)];
      const int end = cell_start_[r * cols_ + CellCol(row_max_x) + 1];
      if (begin < end) f(begin, end, row_min_x, row_max_x, band_lo, band_hi);
    }
  }
  int slot_index(int slot) const { return index_[slot]; }
  // Row-major cell id of a position (clamped into the grid).
  int CellOf(float x, float y) const { return CellRow(y) * cols_ + CellCol(x); }
  int num_cells() const { return cols_ * rows_; }

  // Convenience for tests and tools: the indices inside the box, ascending.
  std::vector<int> QueryBox(float min_x, float min_y, float max_x, float max_y) const;

 private:
  // Appends to *out the slots of [begin, end) inside the closed box (branch-free).
  void AppendSlotsInBox(int begin, int end, float min_x, float max_x, float min_y, float max_y,
                        std::vector<int>* out) const;

  void BuildStrided(const unsigned char* xs, const unsigned char* ys, size_t stride, int n,
                    int width, int height, float cell_size);
  // Clamped into the grid; NaN gives 0 (never converted: a NaN float to int is undefined).
  int CellCol(float x) const {
    const float c = std::floor(x * inv_cell_);
    return c >= 0.0f ? (c < static_cast<float>(cols_) ? static_cast<int>(c) : cols_ - 1) : 0;
  }
  int CellRow(float y) const {
    const float r = std::floor(y * inv_cell_);
    return r >= 0.0f ? (r < static_cast<float>(rows_) ? static_cast<int>(r) : rows_ - 1) : 0;
  }

  float cell_size_ = 1.0f;
  float inv_cell_ = 1.0f;
  int cols_ = 0;
  int rows_ = 0;
  std::vector<int> cell_start_;  // rows_*cols_ + 1 offsets into the arrays below
  std::vector<int> index_;       // original point index, sorted by cell (row-major)
  std::vector<float> xy_;        // interleaved x, y in the same order
  std::vector<int> cell_of_;     // scratch for Build: each point's cell
  std::vector<int> cursor_;      // scratch for Build: next free slot per cell
};

}  // namespace imumatch
