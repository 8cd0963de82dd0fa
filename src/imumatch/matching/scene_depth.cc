#include "imumatch/matching/scene_depth.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "imumatch/core/error.h"

namespace imumatch {

namespace {

// The work of both overloads. candidates_b() gives frame B prepared for the search; it is called
// only when the pilot runs, so that a caller who did not prepare B pays for it only then.
template <typename GetCandidates>
SceneNearDepth PredictInScene(
    const KeypointPredictor& predictor, const std::vector<KeypointInfo>& keypoints_a,
    const std::vector<float>& depths_m, const DescriptorView& descriptors_a,
    const std::vector<KeypointInfo>& keypoints_b, const GetCandidates& candidates_b,
    const GuidedMatcherOptions& matcher_options, std::vector<KeypointPrediction>* predictions,
    GuidedSearchScratch* scratch) {
  IMUMATCH_CHECK(predictions != nullptr && scratch != nullptr,
                 "PredictKeypointsInScene needs predictions and a scratch");
  const PredictionOptions& po = predictor.options();
  const SceneNearDepthOptions& so = po.scene_near;
  so.Check();
  const size_t n = keypoints_a.size();
  IMUMATCH_CHECK(depths_m.empty() || depths_m.size() == n,
                 depths_m.size() << " depths for " << n << " keypoints");
  SceneNearDepth out;
  out.segment_min_depth_m = po.segment_min_depth;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto depth_of = [&](size_t i) { return depths_m.empty() ? nan : depths_m[i]; };
  auto has_depth = [&](size_t i) { return po.IsUsableDepth(depth_of(i)); };
  // The ladder of near ends: segment_min_depth x 2^k up to max_depth (the measurable range) and
  // short of the segments' far end.
  const double top = std::min(po.max_depth, 0.5 * po.segment_max_depth);
  const int levels =
      top > po.segment_min_depth ? static_cast<int>(std::log2(top / po.segment_min_depth)) : 0;
  // The pilot costs about pilot_queries searches along full segments: with fewer than twice as
  // many keypoints without depth it cannot pay for itself.
  size_t count_without_depth = 0;
  for (size_t i = 0; i < n; ++i) count_without_depth += has_depth(i) ? 0 : 1;
  if (!so.enabled || !po.predict_without_depth || levels < 1 ||
      count_without_depth < 2 * static_cast<size_t>(so.pilot_queries)) {
    PredictKeypoints(predictor, keypoints_a, depths_m, predictions);
    return out;
  }

  // The pilot: keypoints spread evenly over A, predicted as configured and matched.
  const float reference = ReferenceKeypointSize(keypoints_a);
  const int pilot = static_cast<int>(std::min<size_t>(n, static_cast<size_t>(so.pilot_queries)));
  predictions->assign(n, KeypointPrediction());  // kInvalid: not in the pilot
  for (int k = 0; k < pilot; ++k) {
    const size_t i =
        static_cast<size_t>((static_cast<int64_t>(2 * k + 1) * static_cast<int64_t>(n)) /
                            (2 * static_cast<int64_t>(pilot)));
    const KeypointInfo& kp = keypoints_a[i];
    (*predictions)[i] = predictor.Predict(Eigen::Vector2d(kp.x, kp.y), depth_of(i),
                                          KeypointSigmaScale(po, kp, reference));
  }
  out.pilot_queries = pilot;
  GuidedMatcherOptions pilot_options = matcher_options;
  pilot_options.ratio = std::min(pilot_options.ratio, so.pilot_ratio);
  const MatchResult pilot_result =
      MatchGuided(*predictions, keypoints_a, descriptors_a, candidates_b(), pilot_options, scratch);

  // Each match's sample: the nearer of (a) the deepest near end on the ladder whose no-depth
  // capsule contains the partner (the capsules shrink as the near end moves away: a binary
  // search), which holds where the partner lies off the given epipolar line, and (b) the depth at
  // which the partner lies along the line (triangulated with the given motion), which holds where
  // the capsule's width alone would cover a point nearer than its near end. A partner outside
  // even the configured capsule (a keypoint with depth matched off its epipolar line) tells
  // nothing.
  std::vector<double> sample_depths;
  const auto level_depth = [&](int level) { return po.segment_min_depth * std::ldexp(1.0, level); };
  std::vector<KeypointPredictor> ladder;  // one predictor per level, made once
  ladder.reserve(static_cast<size_t>(levels) + 1);
  for (int level = 0; level <= levels; ++level) {
    ladder.push_back(predictor.WithSegmentMinDepth(level_depth(level)));
  }
  auto contains = [&](int level, const KeypointInfo& a, double sigma_scale, const KeypointInfo& b) {
    const KeypointPrediction pr =
        ladder[static_cast<size_t>(level)].Predict(Eigen::Vector2d(a.x, a.y), nan, sigma_scale);
    return pr.status == PredictionStatus::kWithoutDepth && pr.Contains(b.x, b.y);
  };
  for (const Match& m : pilot_result.matches) {
    const KeypointInfo& a = keypoints_a[static_cast<size_t>(m.query_idx)];
    const KeypointInfo& b = keypoints_b[static_cast<size_t>(m.train_idx)];
    const double sigma_scale = KeypointSigmaScale(po, a, reference);
    const bool without_depth =
        (*predictions)[static_cast<size_t>(m.query_idx)].status == PredictionStatus::kWithoutDepth;
    if (!without_depth && !contains(0, a, sigma_scale, b)) continue;
    const double rho = predictor.InverseDepthOf({a.x, a.y}, {b.x, b.y});
    const double along_line = rho > 0.0 ? 1.0 / rho : std::numeric_limits<double>::infinity();
    // The sample is min(ladder depth, along_line): only the ladder's levels up to the first one
    // deeper than along_line matter. When that level's capsule holds the partner, so do all
    // shallower ones and the sample is along_line (one prediction instead of a search).
    int deeper = 0;  // the first level deeper than along_line (levels + 1: none)
    while (deeper <= levels && level_depth(deeper) <= along_line) ++deeper;
    if (deeper <= levels && contains(deeper, a, sigma_scale, b)) {
      sample_depths.push_back(along_line);
      continue;
    }
    int lo = 0, hi = deeper;  // contained at lo (level 0, checked above), not at hi
    while (hi - lo > 1) {
      const int mid = (lo + hi) / 2;
      (contains(mid, a, sigma_scale, b) ? lo : hi) = mid;
    }
    sample_depths.push_back(std::min(level_depth(lo), along_line));
  }
  out.pilot_matches = static_cast<int>(sample_depths.size());
  if (out.pilot_matches >= so.min_samples) {
    const size_t q =
        std::min(sample_depths.size() - 1,
                 static_cast<size_t>(so.near_quantile * static_cast<double>(sample_depths.size())));
    std::nth_element(sample_depths.begin(), sample_depths.begin() + static_cast<std::ptrdiff_t>(q),
                     sample_depths.end());
    out.near_depth_m = sample_depths[q];
  }
  const double near = std::isnan(out.near_depth_m) ? 0.0 : so.near_margin * out.near_depth_m;
  if (near > po.segment_min_depth) {
    out.segment_min_depth_m = near;
    out.moved = true;
    PredictKeypoints(predictor.WithSegmentMinDepth(near), keypoints_a, depths_m, predictions);
  } else {
    PredictKeypoints(predictor, keypoints_a, depths_m, predictions);
  }
  return out;
}

}  // namespace

SceneNearDepth PredictKeypointsInScene(
    const KeypointPredictor& predictor, const std::vector<KeypointInfo>& keypoints_a,
    const std::vector<float>& depths_m, const DescriptorView& descriptors_a,
    const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
    const DescriptorView& descriptors_b, const GuidedMatcherOptions& matcher_options,
    std::vector<KeypointPrediction>* predictions, GuidedSearchScratch* scratch) {
  IMUMATCH_CHECK(scratch != nullptr, "PredictKeypointsInScene needs predictions and a scratch");
  const auto prepare = [&]() -> const GuidedCandidates& {
    PrepareGuidedCandidates(keypoints_b, grid_b, descriptors_b, &scratch->candidates);
    return scratch->candidates;
  };
  return PredictInScene(predictor, keypoints_a, depths_m, descriptors_a, keypoints_b, prepare,
                        matcher_options, predictions, scratch);
}

SceneNearDepth PredictKeypointsInScene(
    const KeypointPredictor& predictor, const std::vector<KeypointInfo>& keypoints_a,
    const std::vector<float>& depths_m, const DescriptorView& descriptors_a,
    const std::vector<KeypointInfo>& keypoints_b, const GuidedCandidates& candidates_b,
    const GuidedMatcherOptions& matcher_options, std::vector<KeypointPrediction>* predictions,
    GuidedSearchScratch* scratch) {
  IMUMATCH_CHECK(static_cast<int>(keypoints_b.size()) == candidates_b.count(),
                 keypoints_b.size() << " keypoints in B, " << candidates_b.count() << " prepared");
  const auto prepared = [&]() -> const GuidedCandidates& { return candidates_b; };
  return PredictInScene(predictor, keypoints_a, depths_m, descriptors_a, keypoints_b, prepared,
                        matcher_options, predictions, scratch);
}

}  // namespace imumatch
