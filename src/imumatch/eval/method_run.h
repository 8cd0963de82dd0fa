#pragma once

#include <cstddef>
#include <vector>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/evaluation_options.h"
#include "imumatch/eval/frame_source.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

// One method on one detector's features of a pair, for EvaluateSource (evaluation.h): the
// brute-force baselines, the guided method with its second pass and sub-pixel refinement, the
// fixed window, the trackers; and the comparison of a guided run with brute force's matches.

namespace imumatch {

// A frame's features for one detector, kept for the next pair (whose frame A it is).
struct CachedFeatures {
  size_t frame = 0;
  DetectorKind kind = DetectorKind::kOrb;
  Features features;
  std::vector<KeypointInfo> ideal;  // the keypoints in ideal pixels (predictor and grid)
  double ms = 0.0;                  // extraction
  double ideal_ms = 0.0;            // mapping to ideal pixels
};

// Runs one method on one detector's features: matches (query: A, train: B) and, for the methods
// that predict, the predictions their search used (the second pass's when it ran).
MethodRun RunMethod(MatchMethod method, const PixelUndistorter& undistorter,
                    const CameraMotion& motion, const CachedFeatures& ca, const CachedFeatures& cb,
                    const FrameImages& image_a, const FrameImages& image_b,
                    const EvaluationOptions& options, std::vector<Match>& matches,
                    std::vector<KeypointPrediction>& predictions);

// For each match of the brute-force run: does the guided search region of its query contain its
// partner (in ideal pixels), and if not, why; and which match of this run has the same query (and
// back), for the fate of brute force's correct matches (ComputeBruteForceFate).
void CompareWithBruteForce(const std::vector<Match>& bf_matches,
                           const std::vector<KeypointPrediction>& predictions,
                           const std::vector<KeypointInfo>& ideal_b,
                           const std::vector<Match>& run_matches, MethodRun& run);

}  // namespace imumatch
