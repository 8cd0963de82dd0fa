#include "imumatch/matching/guided_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "imumatch/core/error.h"

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

float SquaredNorm(const uint8_t* row, int bytes) {
  const float* v = reinterpret_cast<const float*>(row);
  float s = 0.0f;
  for (int k = 0; k < bytes / 4; ++k) s += v[k] * v[k];
  return s;
}

// Angle difference wrapped to [-180, 180).
float WrapDegrees(float a) {
  if (a >= 180.0f || a < -180.0f) a -= 360.0f * std::floor((a + 180.0f) / 360.0f);
  return a;
}

}  // namespace

MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a,
                        const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
                        const DescriptorView& descriptors_b, const GuidedMatcherOptions& options) {
  options.Check();
  const int n = static_cast<int>(keypoints_a.size());
  const int m = static_cast<int>(keypoints_b.size());
  IMUMATCH_CHECK(static_cast<int>(predictions.size()) == n,
                 predictions.size() << " predictions for " << n << " keypoints");
  IMUMATCH_CHECK(descriptors_a.rows == n,
                 descriptors_a.rows << " descriptors for " << n << " keypoints in A");
  IMUMATCH_CHECK(descriptors_b.rows == m,
                 descriptors_b.rows << " descriptors for " << m << " keypoints in B");
  IMUMATCH_CHECK(grid_b.size() == m, "grid holds " << grid_b.size() << " points, B has " << m);
  CheckCompatible(descriptors_a, descriptors_b);

  MatchResult result;
  MatchStats& stats = result.stats;
  stats.queries = n;
  result.outcomes.assign(static_cast<size_t>(n), QueryOutcome::kMatched);
  if (n == 0) return result;

  const DescriptorNorm norm = descriptors_a.norm;
  const bool l2 = norm == DescriptorNorm::kL2;
  const int bytes = descriptors_a.bytes;
  const DescriptorCostFn cost_fn = m > 0 ? SelectCostFunction(norm, bytes) : nullptr;
  const float ratio_cost = static_cast<float>(l2 ? options.ratio * options.ratio : options.ratio);
  const bool use_ratio = options.ratio < 1.0;
  const float max_hamming = static_cast<float>(options.max_hamming_fraction * bytes * 8);
  const float max_l2_rel2 = static_cast<float>(options.max_l2_relative * options.max_l2_relative);
  const float orient_tol = static_cast<float>(options.orientation_tolerance_deg);
  const float scale_tol = static_cast<float>(options.scale_tolerance_factor);
  const float inf = std::numeric_limits<float>::infinity();
  const bool rivals_all = options.inconsistent_candidates_in_ratio;

  // B's keypoints and descriptors copied into the grid's cell order: a window's candidates are then
  // read from a few contiguous runs instead of scattered rows (O(m) copy, a few us per 1000).
  std::vector<KeypointInfo> info_b(m);
  std::vector<uint8_t> desc_b(static_cast<size_t>(m) * bytes);
  for (int k = 0; k < m; ++k) {
    const int j = grid_b.slot_index(k);
    info_b[k] = keypoints_b[j];
    std::memcpy(desc_b.data() + static_cast<size_t>(k) * bytes, descriptors_b.Row(j), bytes);
  }
  const bool mutual = options.mutual;
  std::vector<float> reverse_cost;  // by slot
  std::vector<int> reverse_idx;
  if (mutual) {
    reverse_cost.assign(m, inf);
    reverse_idx.assign(m, -1);
  }
  std::vector<int> best_slot(n, -1);  // accepted (before the mutual check) matches, by query
  std::vector<float> best_cost(n), second_cost(n);
  std::vector<int> candidates;
  candidates.reserve(256);
  struct Scored {
    float cost;
    int k;
    bool consistent;
  };
  std::vector<Scored> scored;
  scored.reserve(256);
  const bool dedup = options.duplicate_radius_px > 0.0;
  const float dup_radius = static_cast<float>(options.duplicate_radius_px);
  const float ref_b = ReferenceKeypointSize(keypoints_b);

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
    const KeypointInfo& ka = keypoints_a[i];
    const uint8_t* da = descriptors_a.Row(i);
    const bool check_angle = options.check_orientation && ka.angle_deg >= 0.0f;
    const bool check_size = options.check_scale && ka.size > 0.0f;
    const float expected_angle = ka.angle_deg + p.angle_change_deg;
    const float size_lo = check_size ? ka.size * p.scale_min / scale_tol : 0.0f;
    const float size_hi = check_size ? ka.size * p.scale_max * scale_tol : 0.0f;
    const bool capsule = p.status == PredictionStatus::kWithoutDepth;
    const float r2 = p.radius * p.radius;

    bool any_in_window = false, any_angle_ok = false;
    float best = inf, second = inf, rival = inf;
    int best_k = -1;
    int64_t evaluated = 0;
    scored.clear();
    grid_b.CollectSlotsInBox(p.min_x, p.min_y, p.max_x, p.max_y, &candidates);
    for (const int k : candidates) {
      const KeypointInfo& kb = info_b[k];
      if (capsule && p.SegmentDistanceSquared(kb.x, kb.y) > r2) continue;
      any_in_window = true;
      const bool angle_ok = !(check_angle && kb.angle_deg >= 0.0f &&
                              std::fabs(WrapDegrees(kb.angle_deg - expected_angle)) > orient_tol);
      const bool size_ok =
          !(check_size && kb.size > 0.0f && (kb.size < size_lo || kb.size > size_hi));
      if (angle_ok) any_angle_ok = true;
      const bool consistent = angle_ok && size_ok;
      if (!consistent && !rivals_all) continue;
      // An inconsistent candidate cannot be the match but still competes in the ratio test.
      const float c = cost_fn(da, desc_b.data() + static_cast<size_t>(k) * bytes, bytes);
      ++evaluated;
      if (dedup) scored.push_back({c, k, consistent});
      if (!consistent) {
        if (c < rival) rival = c;
        continue;
      }
      if (c < second) {
        if (c < best) {
          second = best;
          best = c;
          best_k = k;
        } else {
          second = c;
        }
      }
      if (mutual && c < reverse_cost[k]) {
        reverse_cost[k] = c;
        reverse_idx[k] = i;
      }
    }
    if (dedup && best_k >= 0) {
      // Rivals at the best candidate's own place are the same feature detected twice (another
      // pyramid level, another orientation): they do not make the match ambiguous.
      const KeypointInfo& kbest = info_b[best_k];
      const float scale =
          ref_b > 0.0f && kbest.size > 0.0f ? std::max(1.0f, kbest.size / ref_b) : 1.0f;
      const float dup2 = dup_radius * dup_radius * scale * scale;
      second = rival = inf;
      for (const Scored& sc : scored) {
        if (sc.k == best_k) continue;
        const KeypointInfo& kb = info_b[sc.k];
        const float dx = kb.x - kbest.x, dy = kb.y - kbest.y;
        if (dx * dx + dy * dy <= dup2) continue;
        float& target = sc.consistent ? second : rival;
        if (sc.cost < target) target = sc.cost;
      }
    }
    stats.distances_computed += evaluated;
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
      const float na = SquaredNorm(da, bytes);
      const float nb = SquaredNorm(desc_b.data() + static_cast<size_t>(best_k) * bytes, bytes);
      max_cost = max_l2_rel2 * 0.5f * (na + nb);
    }
    if (best > max_cost) {
      ++stats.distance_threshold;
      result.outcomes[i] = QueryOutcome::kDistanceThreshold;
      continue;
    }
    if (use_ratio && !(best < ratio_cost * std::min({second, rival, max_cost}))) {
      ++stats.ratio_test;
      result.outcomes[i] = QueryOutcome::kRatioTest;
      continue;
    }
    best_slot[i] = best_k;
    best_cost[i] = best;
    second_cost[i] = second;
  }

  // The mutual check uses the reverse bests gathered in the same pass.
  for (int i = 0; i < n; ++i) {
    const int k = best_slot[i];
    if (k < 0) continue;
    if (mutual && reverse_idx[k] != i) {
      ++stats.mutual;
      result.outcomes[i] = QueryOutcome::kMutual;
      continue;
    }
    Match match;
    match.query_idx = i;
    match.train_idx = grid_b.slot_index(k);
    match.distance = CostToDistance(norm, best_cost[i]);
    match.second_distance = second_cost[i] < inf ? CostToDistance(norm, second_cost[i]) : inf;
    match.predicted_uv = predictions[i].uv;
    result.matches.push_back(match);
  }
  stats.matched = static_cast<int>(result.matches.size());
  return result;
}

const PixelUndistorter& GuidedMatcherWorkspace::UndistorterFor(const PinholeCamera& camera) {
  const PinholeCamera& c = undistorter_.camera();
  const bool same = has_undistorter_ && c.width == camera.width && c.height == camera.height &&
                    c.fx == camera.fx && c.fy == camera.fy && c.cx == camera.cx &&
                    c.cy == camera.cy && c.distortion == camera.distortion;
  if (!same) {
    undistorter_ = PixelUndistorter(camera);
    has_undistorter_ = true;
  }
  return undistorter_;
}

MatchResult GuidedMatcherWorkspace::Match(const PinholeCamera& camera, const CameraMotion& motion,
                                          const std::vector<cv::KeyPoint>& keypoints_a,
                                          const cv::Mat& descriptors_a, const cv::Mat& depth_a,
                                          const std::vector<cv::KeyPoint>& keypoints_b,
                                          const cv::Mat& descriptors_b,
                                          const PredictionOptions& prediction_options,
                                          const GuidedMatcherOptions& matcher_options) {
  matcher_options.Check();
  const PixelUndistorter& undistorter = UndistorterFor(camera);
  const KeypointPredictor predictor(undistorter, motion, prediction_options);
  const size_t n = keypoints_a.size();
  // Depth is registered to the (distorted) image: sampled at the image positions. No depth image:
  // no depths (every keypoint is predicted along its epipolar segment).
  depths_.clear();
  if (!depth_a.empty()) {
    depths_ =
        SampleDepths(depth_a, camera.depth_scale, keypoints_a, prediction_options.depth_sampling);
  }
  // A stream passes each frame twice, as B and then as A: its keypoints were mapped to ideal
  // pixels in the previous call. Reused when the positions are the very same (a cheap compare).
  bool reuse = !undistorter.identity() && keypoints_a.size() == last_b_.size();
  for (size_t i = 0; reuse && i < n; ++i) {
    reuse = keypoints_a[i].pt == last_b_[i];
  }
  if (reuse) {
    info_a_.swap(info_b_);
    for (size_t i = 0; i < n; ++i) {
      info_a_[i].angle_deg = keypoints_a[i].angle;
      info_a_[i].size = keypoints_a[i].size;
      info_a_[i].octave = keypoints_a[i].octave;
    }
  } else {
    ToIdealKeypointInfos(keypoints_a, undistorter, &info_a_);
  }
  PredictKeypoints(predictor, info_a_, depths_, &predictions_);
  ToIdealKeypointInfos(keypoints_b, undistorter, &info_b_);
  last_b_.resize(keypoints_b.size());
  for (size_t j = 0; j < keypoints_b.size(); ++j) last_b_[j] = keypoints_b[j].pt;
  grid_.Build(info_b_, camera.width, camera.height,
              static_cast<float>(matcher_options.grid_cell_size));
  return MatchGuided(predictions_, info_a_, DescriptorView::FromMat(descriptors_a), info_b_, grid_,
                     DescriptorView::FromMat(descriptors_b), matcher_options);
}

MatchResult MatchFramesGuided(const PinholeCamera& camera, const CameraMotion& motion,
                              const std::vector<cv::KeyPoint>& keypoints_a,
                              const cv::Mat& descriptors_a, const cv::Mat& depth_a,
                              const std::vector<cv::KeyPoint>& keypoints_b,
                              const cv::Mat& descriptors_b,
                              const PredictionOptions& prediction_options,
                              const GuidedMatcherOptions& matcher_options) {
  GuidedMatcherWorkspace workspace;
  return workspace.Match(camera, motion, keypoints_a, descriptors_a, depth_a, keypoints_b,
                         descriptors_b, prediction_options, matcher_options);
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
