#pragma once

#include <limits>
#include <vector>

#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/grid_index.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

// PredictKeypoints (into *predictions, its capacity reused) with the near end of the epipolar
// segments taken from the scene when predictor.options().scene_near.enabled (see
// SceneNearDepthOptions): a pilot of A's keypoints is predicted and matched with MatchGuided and
// the configured segments; each match gives a depth sample (the nearer of its depth along the
// epipolar line and the deepest near end whose no-depth capsule still contains its partner); the
// segments of every keypoint without depth then start at
// near_margin x the samples' near_quantile (never nearer than segment_min_depth). Nothing is
// learned (plain PredictKeypoints) when fewer than 2 x pilot_queries keypoints lack depth (the
// pilot, about pilot_queries full-segment searches, would cost more than it saves) or when the
// pilot matches fewer than min_samples. Keypoints and the grid in
// ideal pixels, as MatchGuided takes them; depths_m as PredictKeypoints takes them.
SceneNearDepth PredictKeypointsInScene(
    const KeypointPredictor& predictor, const std::vector<KeypointInfo>& keypoints_a,
    const std::vector<float>& depths_m, const DescriptorView& descriptors_a,
    const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
    const DescriptorView& descriptors_b, const GuidedMatcherOptions& matcher_options,
    std::vector<KeypointPrediction>* predictions, GuidedSearchScratch* scratch);
// The same against a frame B prepared once (PrepareGuidedCandidates over keypoints_b), which the
// caller's own searches against B then reuse.
SceneNearDepth PredictKeypointsInScene(
    const KeypointPredictor& predictor, const std::vector<KeypointInfo>& keypoints_a,
    const std::vector<float>& depths_m, const DescriptorView& descriptors_a,
    const std::vector<KeypointInfo>& keypoints_b, const GuidedCandidates& candidates_b,
    const GuidedMatcherOptions& matcher_options, std::vector<KeypointPrediction>* predictions,
    GuidedSearchScratch* scratch);

}  // namespace imumatch
