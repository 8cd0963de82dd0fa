#include "imumatch/matching/neighbour_depth.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "imumatch/core/error.h"

namespace imumatch {

void NeighbourDepthOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(cell_px) && cell_px > 0.0,
                 "neighbour cell_px=" << cell_px << " must be positive");
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
  // A partner beyond the rotation-only point: at infinity within noise, unless the translation's
  // sign is open.
  const bool sign_open = predictor.TranslationSignOpen();
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
    if (std::isfinite(r)) rho[i] = sign_open ? r : std::max(r, 0.0);
  }
  return rho;
}

std::vector<InverseDepthRange> NeighbourInverseDepthRanges(
    const std::vector<KeypointInfo>& keypoints_a, const std::vector<double>& inverse_depths,
    const NeighbourDepthOptions& options) {
  options.Check();
  const size_t n = keypoints_a.size();
  IMUMATCH_CHECK(inverse_depths.size() == n,
                 inverse_depths.size() << " inverse depths for " << n << " keypoints of A");
  std::vector<InverseDepthRange> ranges(n);
  if (!options.enabled || n == 0) return ranges;

  // Per cell of cell_px: how many keypoints have an inverse depth there, and its range. A
  // keypoint's neighbours are then 9 cells' summaries, whatever the keypoints' density (ORB
  // clusters on texture: testing every neighbour within a radius cost 0.5 ms per ORB pair of
  // EuRoC MH_05, more than the second search it shortens).
  float min_x = std::numeric_limits<float>::infinity(), min_y = min_x;
  float max_x = -min_x, max_y = -min_x;
  for (const KeypointInfo& k : keypoints_a) {
    if (!std::isfinite(k.x) || !std::isfinite(k.y)) continue;
    min_x = std::min(min_x, k.x);
    max_x = std::max(max_x, k.x);
    min_y = std::min(min_y, k.y);
    max_y = std::max(max_y, k.y);
  }
  if (!(min_x <= max_x)) return ranges;  // no finite keypoint
  const double cell = options.cell_px;
  const int cols = static_cast<int>((max_x - min_x) / cell) + 1;
  const int rows = static_cast<int>((max_y - min_y) / cell) + 1;
  const auto col_of = [&](const KeypointInfo& k) { return static_cast<int>((k.x - min_x) / cell); };
  const auto row_of = [&](const KeypointInfo& k) { return static_cast<int>((k.y - min_y) / cell); };
  const size_t cells = static_cast<size_t>(cols) * static_cast<size_t>(rows);
  std::vector<int> count(cells, 0);
  std::vector<double> lo(cells, std::numeric_limits<double>::infinity()),
      hi(cells, -std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < n; ++i) {
    const KeypointInfo& k = keypoints_a[i];
    if (!std::isfinite(inverse_depths[i]) || !std::isfinite(k.x) || !std::isfinite(k.y)) continue;
    const size_t c = static_cast<size_t>(row_of(k)) * cols + static_cast<size_t>(col_of(k));
    ++count[c];
    lo[c] = std::min(lo[c], inverse_depths[i]);
    hi[c] = std::max(hi[c], inverse_depths[i]);
  }
  for (size_t i = 0; i < n; ++i) {
    const KeypointInfo& k = keypoints_a[i];
    if (!std::isfinite(k.x) || !std::isfinite(k.y)) continue;
    const int cx = col_of(k), cy = row_of(k);
    int neighbours = 0;
    double range_lo = std::numeric_limits<double>::infinity(), range_hi = -range_lo;
    for (int r = std::max(0, cy - 1); r <= std::min(rows - 1, cy + 1); ++r) {
      for (int c = std::max(0, cx - 1); c <= std::min(cols - 1, cx + 1); ++c) {
        const size_t j = static_cast<size_t>(r) * cols + static_cast<size_t>(c);
        neighbours += count[j];
        range_lo = std::min(range_lo, lo[j]);
        range_hi = std::max(range_hi, hi[j]);
      }
    }
    if (neighbours < options.min_neighbours) continue;
    // Widened away from zero on both sides (a negative end moves further below zero).
    const double f = options.range_factor;
    ranges[i].rho_far = range_lo >= 0.0 ? range_lo / f : range_lo * f;
    ranges[i].rho_near = range_hi >= 0.0 ? range_hi * f : range_hi / f;
  }
  return ranges;
}

int PredictKeypointsNearMatches(const KeypointPredictor& predictor,
                                const std::vector<KeypointInfo>& keypoints_a,
                                const std::vector<float>& depths_m,
                                const std::vector<Match>& matches,
                                const std::vector<KeypointInfo>& keypoints_b,
                                const NeighbourDepthOptions& options,
                                std::vector<KeypointPrediction>* predictions) {
  std::vector<InverseDepthRange> ranges;
  if (options.enabled) {
    ranges = NeighbourInverseDepthRanges(
        keypoints_a, MatchedInverseDepths(predictor, keypoints_a, depths_m, matches, keypoints_b),
        options);
  }
  return PredictKeypointsInRanges(predictor, keypoints_a, depths_m, ranges, predictions);
}

}  // namespace imumatch
