#include "imumatch/matching/neighbour_depth.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "imumatch/core/error.h"

namespace imumatch {

void NeighbourDepthOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(radius_px) && radius_px > 0.0,
                 "neighbour radius_px=" << radius_px << " must be positive");
  IMUMATCH_CHECK(min_neighbours >= 1, "min_neighbours=" << min_neighbours << " must be >= 1");
  IMUMATCH_CHECK(std::isfinite(range_factor) && range_factor >= 1.0,
                 "range_factor=" << range_factor << " must be >= 1");
}

std::vector<double> MatchedInverseDepths(const KeypointPredictor& predictor,
                                         const std::vector<KeypointInfo>& keypoints_a,
                                         const std::vector<float>& depths_m,
                                         const std::vector<Match>& matches,
                                         const std::vector<KeypointInfo>& keypoints_b) {
  const size_t n = keypoints_a.size();
  IMUMATCH_CHECK(depths_m.empty() || depths_m.size() == n,
                 depths_m.size() << " depths for " << n << " keypoints of A");
  std::vector<double> rho(n, std::numeric_limits<double>::quiet_NaN());
  for (const Match& m : matches) {
    IMUMATCH_CHECK(m.query_idx >= 0 && static_cast<size_t>(m.query_idx) < n,
                   "match query " << m.query_idx << " outside the " << n << " keypoints of A");
    IMUMATCH_CHECK(m.train_idx < static_cast<int>(keypoints_b.size()),
                   "match train " << m.train_idx << " outside the " << keypoints_b.size()
                                  << " keypoints of B");
    const size_t i = static_cast<size_t>(m.query_idx);
    if (!depths_m.empty() && predictor.options().IsUsableDepth(depths_m[i])) {
      rho[i] = 1.0 / depths_m[i];
      continue;
    }
    if (m.train_idx < 0) continue;
    const KeypointInfo& a = keypoints_a[i];
    const KeypointInfo& b = keypoints_b[static_cast<size_t>(m.train_idx)];
    const double r = predictor.InverseDepthOf({a.x, a.y}, {b.x, b.y});
    if (std::isfinite(r)) rho[i] = std::max(r, 0.0);
  }
  return rho;
}

int NarrowSegmentsToNeighbours(const KeypointPredictor& predictor,
                               const std::vector<KeypointInfo>& keypoints_a,
                               const std::vector<double>& inverse_depths,
                               const NeighbourDepthOptions& options,
                               std::vector<KeypointPrediction>* predictions) {
  options.Check();
  IMUMATCH_CHECK(predictions != nullptr, "NarrowSegmentsToNeighbours needs predictions");
  const size_t n = keypoints_a.size();
  IMUMATCH_CHECK(inverse_depths.size() == n && predictions->size() == n,
                 inverse_depths.size() << " inverse depths and " << predictions->size()
                                       << " predictions for " << n << " keypoints of A");
  if (!options.enabled || n == 0) return 0;

  // The keypoints with an inverse depth, bucketed in cells of radius_px (a counting sort): a
  // keypoint's neighbours lie in its cell and the 8 around it.
  std::vector<int> measured;
  float min_x = std::numeric_limits<float>::infinity(), min_y = min_x;
  float max_x = -min_x, max_y = -min_x;
  for (size_t i = 0; i < n; ++i) {
    const KeypointInfo& k = keypoints_a[i];
    if (!std::isfinite(inverse_depths[i]) || !std::isfinite(k.x) || !std::isfinite(k.y)) continue;
    measured.push_back(static_cast<int>(i));
    min_x = std::min(min_x, k.x);
    max_x = std::max(max_x, k.x);
    min_y = std::min(min_y, k.y);
    max_y = std::max(max_y, k.y);
  }
  if (static_cast<int>(measured.size()) < options.min_neighbours) return 0;
  const double cell = options.radius_px;
  const int cols = static_cast<int>((max_x - min_x) / cell) + 1;
  const int rows = static_cast<int>((max_y - min_y) / cell) + 1;
  const auto col_of = [&](float x) { return static_cast<int>((x - min_x) / cell); };
  const auto row_of = [&](float y) { return static_cast<int>((y - min_y) / cell); };
  std::vector<int> start(static_cast<size_t>(cols) * rows + 1, 0), slot(measured.size());
  for (int i : measured) {
    ++start[static_cast<size_t>(row_of(keypoints_a[i].y)) * cols + col_of(keypoints_a[i].x) + 1];
  }
  for (size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (int i : measured) {
      slot[next[static_cast<size_t>(row_of(keypoints_a[i].y)) * cols +
                col_of(keypoints_a[i].x)]++] = i;
    }
  }

  const float reference = ReferenceKeypointSize(keypoints_a);
  const double r2 = options.radius_px * options.radius_px;
  int narrowed = 0;
  for (size_t i = 0; i < n; ++i) {
    KeypointPrediction& p = (*predictions)[i];
    if (p.status != PredictionStatus::kWithoutDepth) continue;
    const KeypointInfo& k = keypoints_a[i];
    if (!std::isfinite(k.x) || !std::isfinite(k.y)) continue;
    // Cells around the keypoint, clamped to the grid (a keypoint outside the measured ones'
    // bounding box reaches only the cells within radius_px of it).
    const int c0 = std::max(0, static_cast<int>(std::floor((k.x - min_x - cell) / cell)));
    const int c1 = std::min(cols - 1, static_cast<int>(std::floor((k.x - min_x + cell) / cell)));
    const int r0 = std::max(0, static_cast<int>(std::floor((k.y - min_y - cell) / cell)));
    const int r1 = std::min(rows - 1, static_cast<int>(std::floor((k.y - min_y + cell) / cell)));
    int count = 0;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const size_t cell_index = static_cast<size_t>(r) * cols + c;
        for (int s = start[cell_index]; s < start[cell_index + 1]; ++s) {
          const KeypointInfo& o = keypoints_a[static_cast<size_t>(slot[s])];
          const double dx = o.x - k.x, dy = o.y - k.y;
          if (dx * dx + dy * dy > r2) continue;
          const double rho = inverse_depths[static_cast<size_t>(slot[s])];
          lo = std::min(lo, rho);
          hi = std::max(hi, rho);
          ++count;
        }
      }
    }
    if (count < options.min_neighbours) continue;
    const KeypointPrediction q = predictor.PredictInInverseDepthRange(
        {k.x, k.y}, lo / options.range_factor, hi * options.range_factor,
        KeypointSigmaScale(predictor.options(), k, reference));
    if (q.status != PredictionStatus::kWithoutDepth) continue;
    p = q;
    ++narrowed;
  }
  return narrowed;
}

}  // namespace imumatch
