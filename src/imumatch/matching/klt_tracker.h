#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

// Lucas-Kanade tracking of frame A's keypoints into frame B.
//
// A track is a Match with train_idx = -1 (no keypoint of B) whose refined_uv_b is the tracked
// position in B (image pixels), predicted_uv the seed (image pixels, NaN for the unseeded
// tracker) and distance 1 - the zero-normalised cross-correlation of the two patches.

// Image pyramid for tracking: level 0 the 8-bit gray image, each next level cv::pyrDown of the
// previous (a point x at level 0 is x / 2^l at level l). Built once per frame.
struct TrackingPyramid {
  std::vector<cv::Mat> levels;
  // Throws InvalidArgument for an empty or non-8-bit single-channel image, max_level outside
  // [0, 8].
  static TrackingPyramid Build(const cv::Mat& gray, int max_level);
};

struct KltOptions {
  // Patch of (2 half_size + 1)^2 samples at every level.
  int half_size = 7;
  // Coarsest pyramid level. The seeded tracker starts each track at the level where its
  // prediction's uncertainty (the window's half size, or the segment's perpendicular radius)
  // fits inside the patch's reach (half_size px): ceil(log2(radius / half_size)), at most this.
  int max_level = 3;
  // Per level; the coarse levels (and the backward check) stop at 10 iterations or 0.05 px.
  int max_iterations = 30;
  double convergence_px = 0.03;
  double min_texture = 0.02;  // see SubpixelOptions::min_texture
  // Forward-backward check (VINS-Fusion: 0.5 px): B's patch tracked back into A must land within
  // this distance of A's keypoint.
  double max_forward_backward_px = 0.5;
  // A track whose patches correlate less than this (zero-normalised cross-correlation) is
  // rejected as a photometric mismatch (-1: no check).
  double min_correlation = 0.8;
  // Seeded tracker: warp A's patch by the prediction's local affine map (the IMU's in-plane
  // rotation and scale change); false tracks an axis-aligned patch.
  bool warp_patch = true;
  // Seeded tracker: reject a track that leaves its prediction's search region.
  bool gate_by_window = true;
  // Keypoints without depth: seeds along the epipolar segment 2 px apart at the level where they
  // are compared (the starting level, or coarser while there would be more than
  // max_segment_seeds); the max_segment_starts best-correlating local maxima each start a
  // coarse-to-fine track, and the best final correlation wins.
  int max_segment_seeds = 32;
  // With more than one start, a second converged position (more than 1 px away) whose
  // correlation is within ambiguity_margin of the best makes the track ambiguous (a repeated
  // texture along the line): rejected. Measured on EuRoC MH_05 (ORB-1000, mostly without depth):
  // 3 starts tracked 0.7 % more keypoints at the same precision for 1.8x the tracking time, so
  // one start is the default; the forward-backward and correlation checks still apply.
  int max_segment_starts = 1;
  double ambiguity_margin = 0.05;
  void Check() const;  // throws InvalidArgument
};

enum class TrackOutcome : uint8_t {
  kTracked,
  kNoPrediction,     // no usable prediction (seeded tracker only)
  kBorder,           // the patch left an image
  kTexture,          // A's patch has no texture in both directions
  kNoConvergence,    // Lucas-Kanade did not converge
  kForwardBackward,  // tracked back, it missed A's keypoint by more than the limit
  kLowCorrelation,   // the patches do not correlate
  kOutsideWindow,    // the track left its prediction's search region (seeded tracker only)
  kAmbiguous,        // two positions along the epipolar segment correlate about as well
};
const char* ToString(TrackOutcome outcome);

struct TrackStats {
  int queries = 0;
  int tracked = 0;
  int no_prediction = 0;
  int border = 0;
  int texture = 0;
  int no_convergence = 0;
  int forward_backward = 0;
  int low_correlation = 0;
  int outside_window = 0;
  int ambiguous = 0;
  int64_t iterations = 0;
  void Count(TrackOutcome outcome);
  int OutcomeSum() const;
  std::string ToString() const;
};

struct TrackResult {
  std::vector<Match> tracks;           // the accepted tracks, by query index
  std::vector<TrackOutcome> outcomes;  // one per keypoint of A
  std::vector<float> correlation;      // one per keypoint of A (-2 when not computed)
  TrackStats stats;
};

// The IMU-seeded tracker: each keypoint of A (image pixels) starts at its prediction (ideal
// pixels, one per keypoint; see KeypointPredictor), mapped into B's image pixels: with depth at
// the predicted position, without depth at the best-correlating point of the epipolar segment.
// Zero-mean, unit-variance patches (gain and bias of the exposure cancel), warped by the
// predicted rotation and scale when options.warp_patch. Coarse to fine from the level the
// prediction's uncertainty needs; forward-backward and correlation checks; then the window gate.
TrackResult TrackSeeded(const TrackingPyramid& a, const TrackingPyramid& b,
                        const std::vector<cv::KeyPoint>& keypoints_a,
                        const std::vector<KeypointPrediction>& predictions,
                        const PixelUndistorter& undistorter, const KltOptions& options);

// The unseeded VINS-Fusion-style baseline on OpenCV's cv::calcOpticalFlowPyrLK: every keypoint
// starts at its own position in B; window (2 half_size + 1)^2 (VINS: 21 x 21, half_size 10),
// max_level pyramid levels, 30 iterations or 0.01 px; forward-backward check seeded at A's
// keypoint; the correlation check as above.
TrackResult TrackOpenCvLk(const cv::Mat& gray_a, const cv::Mat& gray_b,
                          const std::vector<cv::KeyPoint>& keypoints_a, const KltOptions& options);

// The hybrid's fallback: the predictions with every tracked keypoint's marked kInvalid, so that
// guided matching only looks for the keypoints whose track failed.
std::vector<KeypointPrediction> PredictionsOfFailedTracks(
    const std::vector<KeypointPrediction>& predictions, const TrackResult& tracks);

}  // namespace imumatch
