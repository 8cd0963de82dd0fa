#include "imumatch/matching/guided_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "imumatch/core/error.h"
#include "imumatch/matching/window_scan.h"

namespace imumatch {

void GuidedMatcherOptions::Check() const {
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio=" << ratio << " must be in (0, 1]");
  IMUMATCH_CHECK(max_hamming_fraction >= 0.0 && max_hamming_fraction <= 1.0,
                 "max_hamming_fraction=" << max_hamming_fraction);
  IMUMATCH_CHECK(max_l2_relative >= 0.0 && std::isfinite(max_l2_relative),
                 "max_l2_relative=" << max_l2_relative);
  IMUMATCH_CHECK(orientation_tolerance_deg >= 0.0 && orientation_tolerance_deg <= 180.0,
                 "orientation_tolerance_deg=" << orientation_tolerance_deg);
  IMUMATCH_CHECK(scale_tolerance_factor >= 1.0 && std::isfinite(scale_tolerance_factor),
                 "scale_tolerance_factor=" << scale_tolerance_factor);
  IMUMATCH_CHECK(duplicate_radius_px >= 0.0 && std::isfinite(duplicate_radius_px),
                 "duplicate_radius_px=" << duplicate_radius_px);
  IMUMATCH_CHECK(grid_cell_size > 0.0 && std::isfinite(grid_cell_size),
                 "grid_cell_size=" << grid_cell_size);
}

namespace {

// +inf when flag is 1, 0 when it is 0, without a branch (for min-accumulators over costs >= 0).
inline float InfIf(int flag) {
  const uint32_t bits = static_cast<uint32_t>(-flag) & 0x7f800000u;
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

}  // namespace

MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a,
                        const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
                        const DescriptorView& descriptors_b, const GuidedMatcherOptions& options) {
  GuidedSearchScratch scratch;
  return MatchGuided(predictions, keypoints_a, descriptors_a, keypoints_b, grid_b, descriptors_b,
                     options, &scratch);
}

MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a,
                        const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
                        const DescriptorView& descriptors_b, const GuidedMatcherOptions& options,
                        GuidedSearchScratch* scratch) {
  IMUMATCH_CHECK(scratch != nullptr, "MatchGuided needs a scratch");
  PrepareGuidedCandidates(keypoints_b, grid_b, descriptors_b, &scratch->candidates);
  return MatchGuided(predictions, keypoints_a, descriptors_a, scratch->candidates, options,
                     scratch);
}

MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a, const GuidedCandidates& candidates_b,
                        const GuidedMatcherOptions& options, GuidedSearchScratch* scratch) {
  IMUMATCH_CHECK(scratch != nullptr, "MatchGuided needs a scratch");
  IMUMATCH_CHECK(candidates_b.grid != nullptr, "MatchGuided: frame B was not prepared");
  options.Check();
  const GridIndex& grid_b = *candidates_b.grid;
  const int n = static_cast<int>(keypoints_a.size());
  const int m = candidates_b.count();
  IMUMATCH_CHECK(static_cast<int>(predictions.size()) == n,
                 predictions.size() << " predictions for " << n << " keypoints");
  IMUMATCH_CHECK(descriptors_a.rows == n,
                 descriptors_a.rows << " descriptors for " << n << " keypoints in A");
  IMUMATCH_CHECK(grid_b.size() == m,
                 "grid holds " << grid_b.size() << " points, the prepared B has " << m);
  CheckCompatible(descriptors_a, candidates_b.descriptor_view());

  MatchResult result;
  MatchStats& stats = result.stats;
  stats.queries = n;
  result.outcomes.assign(static_cast<size_t>(n), QueryOutcome::kMatched);
  if (n == 0) return result;

  const DescriptorNorm norm = descriptors_a.norm;
  const bool l2 = norm == DescriptorNorm::kL2;
  const int bytes = descriptors_a.bytes;
  const float ratio_cost = static_cast<float>(l2 ? options.ratio * options.ratio : options.ratio);
  const bool use_ratio = options.ratio < 1.0;
  const float max_hamming = static_cast<float>(options.max_hamming_fraction * bytes * 8);
  const float max_l2_rel2 = static_cast<float>(options.max_l2_relative * options.max_l2_relative);
  // The L2 threshold's descriptor norms: the squared L2 distance to a zero row, by the same
  // vectorised kernel as the distances (a running sum was a chain of 128 dependent additions per
  // SIFT descriptor, twice per query: 12 % of the SIFT search).
  const DescriptorCostFn squared_norm = l2 ? SelectCostFunction(norm, bytes) : nullptr;
  const std::vector<uint8_t> zeros(l2 ? static_cast<size_t>(bytes) : 0, 0);
  const float orient_tol = static_cast<float>(options.orientation_tolerance_deg);
  const float scale_tol = static_cast<float>(options.scale_tolerance_factor);
  const float inf = std::numeric_limits<float>::infinity();
  const bool rivals_all = options.inconsistent_candidates_in_ratio;

  // B's keypoints and descriptors in the grid's slot order (PrepareGuidedCandidates): a window's
  // candidates are contiguous runs of slots, tested 16 or 8 at a time (window_scan.h).
  const std::vector<float>&cand_x = candidates_b.x, &cand_y = candidates_b.y,
        &cand_size = candidates_b.size;
  const uint8_t* const desc_b = candidates_b.descriptors.data();
  constexpr int kPrefetchAhead = 8;
  CandidateView view;
  view.x = cand_x.data();
  view.y = cand_y.data();
  view.angle_deg = candidates_b.angle_deg.data();
  view.size = cand_size.data();
  const WindowScanFn box_test = SelectWindowScan(false, options.kernel);
  const WindowScanFn capsule_test = SelectWindowScan(true, options.kernel);
  const bool mutual = options.mutual;
  std::vector<float>& reverse_cost = scratch->reverse_cost;  // by slot
  std::vector<int>& reverse_idx = scratch->reverse_idx;
  if (mutual) {
    reverse_cost.assign(m, inf);
    reverse_idx.assign(m, -1);
  }
  const DescriptorCostGatherFn cost_gather =
      m > 0 ? SelectCostGatherFunction(norm, bytes) : nullptr;
  std::vector<int>&consistent_slot = scratch->consistent_slot, &rival_slot = scratch->rival_slot;
  std::vector<float>&consistent_cost = scratch->consistent_cost, &rival_cost = scratch->rival_cost;
  const int rivals_all_bit = rivals_all ? 1 : 0;
  const bool dedup = options.duplicate_radius_px > 0.0;
  const float dup_radius = static_cast<float>(options.duplicate_radius_px);
  const float ref_b = candidates_b.reference_size;

  // The queries with a window are visited in the grid's cell order of their windows (a counting
  // sort, O(n + cells)): consecutive windows then read neighbouring slots of B, and the per-query
  // results are written in visiting order, so the search touches B's arrays almost as a stream.
  // Only the query's own records (prediction, keypoint, descriptor) are read out of order, and
  // they are prefetched a few queries ahead. In A's order, every window would read a random part
  // of B: a cache miss per candidate once B's arrays outgrow L2 (thousands of keypoints). The
  // result does not depend on the order (the mutual check breaks ties by the lower query index).
  std::vector<int>& order = scratch->order;              // visiting position -> query index
  std::vector<int>& position_of = scratch->position_of;  // query index -> visiting position
  position_of.assign(n, -1);                             // (-1: no window)
  {
    const int cells = grid_b.num_cells();
    std::vector<int>&start = scratch->cell_start, &cell = scratch->cell;
    start.assign(static_cast<size_t>(cells) + 1, 0);
    cell.assign(n, -1);
    for (int i = 0; i < n; ++i) {
      const KeypointPrediction& p = predictions[i];
      switch (p.status) {
        case PredictionStatus::kWithDepth:
          ++stats.predicted_with_depth;
          break;
        case PredictionStatus::kWithoutDepth:
          ++stats.predicted_without_depth;
          break;
        case PredictionStatus::kBehindCamera:
          ++stats.behind_camera;
          result.outcomes[i] = QueryOutcome::kBehindCamera;
          continue;
        case PredictionStatus::kOutsideImage:
          ++stats.outside_image;
          result.outcomes[i] = QueryOutcome::kOutsideImage;
          continue;
        case PredictionStatus::kInvalid:
          ++stats.no_prediction;
          result.outcomes[i] = QueryOutcome::kNoPrediction;
          continue;
      }
      const float centre_x = 0.5f * (p.min_x + p.max_x), centre_y = 0.5f * (p.min_y + p.max_y);
      IMUMATCH_CHECK(std::isfinite(centre_x) && std::isfinite(centre_y),
                     "prediction " << i << " has a window that is not finite: x [" << p.min_x
                                   << ", " << p.max_x << "], y [" << p.min_y << ", " << p.max_y
                                   << "]");
      cell[i] = grid_b.CellOf(centre_x, centre_y);
      ++start[cell[i] + 1];
    }
    for (int c = 0; c < cells; ++c) start[c + 1] += start[c];
    order.resize(start[cells]);
    for (int i = 0; i < n; ++i) {
      if (cell[i] < 0) continue;
      position_of[i] = start[cell[i]]++;
      order[position_of[i]] = i;
    }
  }
  const int visited = static_cast<int>(order.size());
  // Per visiting position: the accepted candidate's slot (-1: none), its cost, the runner-up's.
  std::vector<int>& accepted_slot = scratch->accepted_slot;
  std::vector<float>&accepted_cost = scratch->accepted_cost,
  &accepted_second = scratch->accepted_second;
  accepted_slot.assign(visited, -1);
  accepted_cost.resize(visited);
  accepted_second.resize(visited);

  for (int q = 0; q < visited; ++q) {
    if (q + kPrefetchAhead < visited) {
      const int ahead = order[q + kPrefetchAhead];
      const char* pa = reinterpret_cast<const char*>(&predictions[ahead]);
      __builtin_prefetch(pa);
      __builtin_prefetch(pa + sizeof(KeypointPrediction) - 1);
      __builtin_prefetch(&keypoints_a[ahead]);
      const uint8_t* row = descriptors_a.Row(ahead);
      for (int b = 0; b < bytes; b += 64) __builtin_prefetch(row + b);
    }
    const int i = order[q];
    const KeypointPrediction& p = predictions[i];
    const KeypointInfo& ka = keypoints_a[i];
    const uint8_t* da = descriptors_a.Row(i);
    const bool capsule = p.status == PredictionStatus::kWithoutDepth;
    const float expected_raw = ka.angle_deg + p.angle_change_deg;
    const bool check_angle =
        options.check_orientation && ka.angle_deg >= 0.0f && std::isfinite(expected_raw);
    const bool check_size = options.check_scale && ka.size > 0.0f;
    const float expected_angle = NormalizeDegrees(expected_raw);
    const float size_lo = check_size ? ka.size * p.scale_min / scale_tol : 0.0f;
    const float size_hi = check_size ? ka.size * p.scale_max * scale_tol : 0.0f;
    const float r2 = p.radius * p.radius;

    // Pass 1: the candidates inside the window, split by their consistency with the predicted
    // rotation and scale into consistent_slot and rival_slot, each in grid order (each run of
    // slots the window spans in a cell row, tested without a branch per candidate).
    bool any_in_window = false, any_angle_ok = false;
    int nc = 0, ni = 0;
    const CandidateTest test{expected_angle,
                             orient_tol,
                             size_lo,
                             size_hi,
                             check_angle,
                             check_size,
                             p.segment_start.x(),
                             p.segment_start.y(),
                             p.segment_end.x() - p.segment_start.x(),
                             p.segment_end.y() - p.segment_start.y(),
                             r2};
    const auto run = [&](int begin, int end, float lo_x, float hi_x, float lo_y, float hi_y) {
      const int len = end - begin;
      stats.points_scanned += len;
      if (consistent_slot.size() < static_cast<size_t>(std::max(nc, ni) + len + kWindowScanSlack)) {
        const size_t size = 2 * static_cast<size_t>(std::max(nc, ni) + len + kWindowScanSlack);
        consistent_slot.resize(size);
        rival_slot.resize(size);
        consistent_cost.resize(size);
        rival_cost.resize(size);
      }
      const int any = (capsule ? capsule_test : box_test)(
          test, view, begin, end, lo_x, hi_x, lo_y, hi_y, rivals_all_bit, consistent_slot.data(),
          &nc, rival_slot.data(), &ni);
      any_in_window |= (any & 1) != 0;
      any_angle_ok |= (any & 2) != 0;
    };
    if (capsule) {
      grid_b.ForEachRunInCapsule(p.segment_start.x(), p.segment_start.y(), p.segment_end.x(),
                                 p.segment_end.y(), p.radius, p.min_x, p.min_y, p.max_x, p.max_y,
                                 run);
    } else {
      grid_b.ForEachRunInBox(p.min_x, p.min_y, p.max_x, p.max_y, run);
    }
    // Pass 2: the consistent candidates' costs in one call, the best of them (the first of equal
    // costs, in grid order), and the reverse bests of the mutual check.
    if (nc > 0) {
      cost_gather(da, desc_b, consistent_slot.data(), nc, bytes, consistent_cost.data());
    }
    stats.distances_computed += nc;
    float best = inf;
    int best_j = -1;
    for (int j = 0; j < nc; ++j) {
      const float c = consistent_cost[j];
      best_j = c < best ? j : best_j;
      best = std::min(best, c);
    }
    if (mutual) {
      for (int j = 0; j < nc; ++j) {
        const int k = consistent_slot[j];
        const float c = consistent_cost[j];
        if (c < reverse_cost[k] || (c == reverse_cost[k] && i < reverse_idx[k])) {
          reverse_cost[k] = c;
          reverse_idx[k] = i;
        }
      }
    }
    const int best_k = best_j >= 0 ? consistent_slot[best_j] : -1;
    // Pass 3: the runner-up among the consistent candidates other than the best. Candidates at
    // the best candidate's own place are the same feature detected twice (another pyramid level,
    // another orientation): they do not make the match ambiguous.
    float second = inf, dup2 = -1.0f, bx = 0.0f, by = 0.0f;  // dup2 < 0: no duplicates
    if (best_j >= 0) {
      const float best_size = cand_size[best_k];
      if (dedup) {
        const float scale =
            ref_b > 0.0f && best_size > 0.0f ? std::max(1.0f, best_size / ref_b) : 1.0f;
        dup2 = dup_radius * dup_radius * scale * scale;
      }
      bx = cand_x[best_k];
      by = cand_y[best_k];
      // Without a branch per candidate (their outcomes are data, and mispredicted branches here
      // cost more than the arithmetic once windows hold a dozen candidates): a skipped
      // candidate's cost becomes +inf.
      for (int j = 0; j < nc; ++j) {
        const float dx = cand_x[consistent_slot[j]] - bx, dy = cand_y[consistent_slot[j]] - by;
        const int skip = (j == best_j) | static_cast<int>(dx * dx + dy * dy <= dup2);
        second = std::min(second, consistent_cost[j] + InfIf(skip));
      }
    }
    if (!any_in_window) {
      ++stats.no_candidate_in_window;
      result.outcomes[i] = QueryOutcome::kNoCandidateInWindow;
      continue;
    }
    if (!any_angle_ok) {
      ++stats.orientation;
      result.outcomes[i] = QueryOutcome::kOrientation;
      continue;
    }
    if (best_k < 0) {
      ++stats.scale;
      result.outcomes[i] = QueryOutcome::kScale;
      continue;
    }
    // The acceptance threshold acts as a virtual second-best: a lone candidate (or one whose
    // rival lies beyond the threshold) must still be distinctive by the ratio.
    float max_cost = max_hamming;
    if (l2) {
      const float na = squared_norm(da, zeros.data(), bytes);
      const float nb =
          squared_norm(desc_b + static_cast<size_t>(best_k) * bytes, zeros.data(), bytes);
      max_cost = max_l2_rel2 * 0.5f * (na + nb);
    }
    if (best > max_cost) {
      ++stats.distance_threshold;
      result.outcomes[i] = QueryOutcome::kDistanceThreshold;
      continue;
    }
    if (use_ratio) {
      // The inconsistent candidates (other than the best one's duplicates) are rivals too, as
      // every keypoint is in a brute-force ratio test. Their costs are computed only when they
      // decide: when the best passes the ratio against the runner-up and the threshold. The
      // outcome is that of best < ratio * min(second, rival, threshold) either way.
      bool distinctive = best < ratio_cost * std::min(second, max_cost);
      if (distinctive && ni > 0) {
        int nr = 0;
        for (int j = 0; j < ni; ++j) {
          const int k = rival_slot[j];
          const float dx = cand_x[k] - bx, dy = cand_y[k] - by;
          rival_slot[nr] = k;
          nr += static_cast<int>(dx * dx + dy * dy > dup2);
        }
        if (nr > 0) {
          cost_gather(da, desc_b, rival_slot.data(), nr, bytes, rival_cost.data());
          stats.distances_computed += nr;
          float rival = inf;
          for (int j = 0; j < nr; ++j) rival = std::min(rival, rival_cost[j]);
          distinctive = best < ratio_cost * std::min({second, rival, max_cost});
        }
      }
      if (!distinctive) {
        ++stats.ratio_test;
        result.outcomes[i] = QueryOutcome::kRatioTest;
        continue;
      }
    }
    accepted_slot[q] = best_k;
    accepted_cost[q] = best;
    accepted_second[q] = second;
  }

  // The mutual check uses the reverse bests gathered in the same pass. Matches in A's order.
  int accepted = 0;
  for (int q = 0; q < visited; ++q) accepted += accepted_slot[q] >= 0;
  result.matches.reserve(accepted);
  for (int i = 0; i < n; ++i) {
    const int q = position_of[i];
    if (q < 0) continue;
    const int k = accepted_slot[q];
    if (k < 0) continue;
    if (mutual && reverse_idx[k] != i) {
      ++stats.mutual;
      result.outcomes[i] = QueryOutcome::kMutual;
      continue;
    }
    Match match;
    match.query_idx = i;
    match.train_idx = grid_b.slot_index(k);
    match.distance = CostToDistance(norm, accepted_cost[q]);
    match.second_distance =
        accepted_second[q] < inf ? CostToDistance(norm, accepted_second[q]) : inf;
    match.predicted_uv = predictions[i].uv;
    result.matches.push_back(match);
  }
  stats.matched = static_cast<int>(result.matches.size());
  return result;
}

MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a,
                        const std::vector<KeypointInfo>& keypoints_b,
                        const DescriptorView& descriptors_b, int width, int height,
                        const GuidedMatcherOptions& options) {
  GridIndex grid;
  grid.Build(keypoints_b, width, height, static_cast<float>(options.grid_cell_size));
  return MatchGuided(predictions, keypoints_a, descriptors_a, keypoints_b, grid, descriptors_b,
                     options);
}

}  // namespace imumatch
