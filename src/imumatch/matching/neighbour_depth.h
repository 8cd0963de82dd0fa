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
  // Neighbours: matched keypoints of A within radius_px (ideal pixels) of the keypoint, itself
  // included when it was matched; fewer than min_neighbours of them: the segment is kept.
  double radius_px = 40.0;
  int min_neighbours = 3;
  // The range [rho_min / range_factor, rho_max * range_factor] of the neighbours' inverse depths
  // (depth from half the nearest one's to twice the farthest one's for range_factor 2).
  double range_factor = 2.0;
  void Check() const;  // throws InvalidArgument
};

// The inverse depths (1/m) that matches measure for their keypoints of A: 1 / depth where
// depths_m (one per keypoint of A, or empty) holds a usable depth (predictor.options()), else
// predictor.InverseDepthOf the keypoint and its partner (negative values, at infinity within noise,
// as 0). NaN for the keypoints without a match or whose partner is not a keypoint of B (a track:
// train_idx < 0). Keypoints in ideal pixels; the predictor holds the motion the matches fit.
std::vector<double> MatchedInverseDepths(const KeypointPredictor& predictor,
                                         const std::vector<KeypointInfo>& keypoints_a,
                                         const std::vector<float>& depths_m,
                                         const std::vector<Match>& matches,
                                         const std::vector<KeypointInfo>& keypoints_b);

// Replaces each prediction without depth (kWithoutDepth) by the prediction along its neighbours'
// inverse-depth range (KeypointPredictor::PredictInInverseDepthRange with predictor) when it has
// at least min_neighbours neighbours with an inverse depth (inverse_depths: per keypoint of A, NaN
// = none) and that prediction still has a window. Returns how many were replaced. predictions: one
// per keypoint of A, as PredictKeypoints makes them with predictor. Throws InvalidArgument on size
// mismatches.
int NarrowSegmentsToNeighbours(const KeypointPredictor& predictor,
                               const std::vector<KeypointInfo>& keypoints_a,
                               const std::vector<double>& inverse_depths,
                               const NeighbourDepthOptions& options,
                               std::vector<KeypointPrediction>* predictions);

}  // namespace imumatch
