#pragma once

#include <vector>

#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

// A keypoint of A without depth is searched along its whole epipolar segment, from the near end
// (segment_min_depth or the scene's, PredictKeypointsInScene) to infinity: hundreds of pixels when
// the camera has moved a few centimetres and the near end is 0.1 m. Once a first pass has matched,
// its matches measure the inverse depth of their keypoints (from the depth image, or from where the
// partner lies along its epipolar line), and surfaces are mostly continuous: a keypoint lies at an
// inverse depth near those of the matched keypoints around it. Its second search can then run
// along the part of the segment that the neighbours' range spans, widened by range_factor on each
// side, and the capsule's width (the keypoint noise and the motion's uncertainty) still surrounds
// it. A shorter segment holds fewer look-alikes: fewer false matches and fewer rivals in the
// ratio test. A keypoint at a depth edge has neighbours on both sides and keeps both in its range;
// one on a small near object surrounded by far ones is the case this narrowing can lose, hence
// the widening and the minimum count of neighbours.
struct NeighbourDepthOptions {
  bool enabled = true;
  // Neighbours: the keypoints of A with an inverse depth in the 3 x 3 cells of cell_px (ideal
  // pixels, a grid over A's keypoints) around the keypoint's own cell, itself included when it has
  // one: 24-48 px away on each side (a 72 px square, about the area of a 40 px radius); fewer than
  // min_neighbours of them: no range.
  double cell_px = 24.0;
  int min_neighbours = 3;
  // The range [rho_min / range_factor, rho_max * range_factor] of the neighbours' inverse depths
  // (depth from half the nearest one's to twice the farthest one's for range_factor 2); a
  // negative end (see MatchedInverseDepths) is moved away from zero as well (times range_factor).
  double range_factor = 2.0;
  void Check() const;  // throws InvalidArgument
};

// The inverse depths (1/m) that matches measure for their keypoints of A: 1 / depth where
// depths_m (one per keypoint of A, or empty) holds a usable depth (predictor.options()), else
// predictor.InverseDepthOf the keypoint and its partner, in the units of the predictor's
// translation: where the partner lies along its epipolar line. That value is negative when the
// partner lies beyond the rotation-only point: at infinity within the keypoints' noise (then 0),
// or, when predictor.TranslationSignOpen() (epipolar distances observe neither the translation's
// length nor, when it is within its uncertainty of zero, its sign: hovering, a slow take-off),
// because the translation points the other way: then it is kept, so that the range of such
// neighbours still holds the partners. NaN for the keypoints without a match or whose partner is
// not a keypoint of B (a track: train_idx < 0). Keypoints in ideal pixels; the predictor holds the
// motion the matches fit.
std::vector<double> MatchedInverseDepths(const KeypointPredictor& predictor,
                                         const std::vector<KeypointInfo>& keypoints_a,
                                         const std::vector<float>& depths_m,
                                         const std::vector<Match>& matches,
                                         const std::vector<KeypointInfo>& keypoints_b);

// Per keypoint of A, the widened range of its neighbours' inverse depths (inverse_depths: per
// keypoint of A, NaN = none; see NeighbourDepthOptions); none where it has fewer than
// min_neighbours or options.enabled is false. O(keypoints + cells). Throws InvalidArgument on a
// size mismatch or bad options.
std::vector<InverseDepthRange> NeighbourInverseDepthRanges(
    const std::vector<KeypointInfo>& keypoints_a, const std::vector<double>& inverse_depths,
    const NeighbourDepthOptions& options);

// The second pass's predictions in one call: PredictKeypointsInRanges with the ranges that
// NeighbourInverseDepthRanges finds around the inverse depths MatchedInverseDepths measures
// (PredictKeypoints when options.enabled is false). Returns how many keypoints were predicted
// along their range.
int PredictKeypointsNearMatches(const KeypointPredictor& predictor,
                                const std::vector<KeypointInfo>& keypoints_a,
                                const std::vector<float>& depths_m,
                                const std::vector<Match>& matches,
                                const std::vector<KeypointInfo>& keypoints_b,
                                const NeighbourDepthOptions& options,
                                std::vector<KeypointPrediction>* predictions);

}  // namespace imumatch
