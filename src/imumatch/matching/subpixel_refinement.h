#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

// Sub-pixel refinement of matched positions in frame B against frame A's patch.
//
// A detector places a keypoint on its own sampling grid: FAST/ORB corners on whole pixels of the
// pyramid level (1.2^l px at level l), SIFT/AKAZE extrema to about a tenth of a sample. Two
// keypoints of the same physical point are therefore up to a grid step apart, so a correct match
// can be a pixel or two off. Refinement keeps A's keypoint where it is and moves B's position to
// where A's patch (centred on A's keypoint) is seen in B: the correspondence then refers to one
// physical point in both frames.
//
// Per match: A's (2h+1)^2 patch around the keypoint, warped into B by the prediction's local
// affine map (the IMU's in-plane rotation and scale change, lens distortion included; identity
// without a prediction), is aligned by inverse-compositional Lucas-Kanade on the translation, on
// zero-mean unit-variance intensities (gain and bias of the exposure cancel). A patch without
// texture in both directions (the smooth centre of a blob) is tried again at twice the size,
// where the blob's edges are: on EuRoC MH_05 that lifted precision at 1 px by 0.1-1.0 point
// (ORB, SURF, BRISK most) for about a third more refinement time. The match keeps its
// keypoints; Match::refined_uv_b receives the refined position (image pixels). A match whose
// alignment fails (patch leaves an image, no texture, no convergence, or it moves farther than
// max_shift_px) keeps refined_uv_b NaN.
struct SubpixelOptions {
  int half_size = 4;  // 9 x 9 samples
  // Patches are sampled at image resolution whatever the keypoint's scale: measured on the
  // synthetic seed cases, patches spread over 2-4 px steps for coarse keypoints (unblurred) lost
  // 1-6 % of SIFT's correct matches to failed alignments and gained no precision.
  int max_iterations = 10;
  double convergence_px = 0.03;
  // Farthest move (px) of a converged alignment: a correct match is within a few pixels;
  // farther means A's patch was found elsewhere.
  double max_shift_px = 4.0;
  // The patch must have texture in both directions: the smaller eigenvalue of the normalised
  // template's gradient Hessian per sample (a unit-variance patch of pure noise gives about 1).
  double min_texture = 0.02;
  // An alignment that drifts (no convergence, or beyond max_shift_px) is tried again with the
  // patch twice the size, and counts only when that one aligns within max_shift_px with a
  // zero-normalised cross-correlation of at least retry_min_correlation (the KLT tracker's
  // track criterion). On EuRoC MH_05 (all 199 pairs, six detectors) it kept 0.3-1.0 % more
  // correct matches; of the matches it added on the frames with depth, 78-94 % are correct.
  bool retry_drifted_larger = true;
  double retry_min_correlation = 0.8;
  // Drop the matches whose alignment did not converge within max_shift_px: A's patch is
  // not found near B's keypoint, a photometric sign of a false match. Matches left unrefined for
  // lack of texture or at the image border are kept.
  bool drop_unaligned = true;
  void Check() const;
};

struct SubpixelStats {
  int refined = 0;
  int failed_border = 0;
  int failed_texture = 0;
  int failed_convergence = 0;  // no convergence, or shifted too far (dropped: drop_unaligned)
  int recovered_larger = 0;    // drifted at half_size, aligned by the larger patch (in refined)
  int64_t iterations = 0;      // Gauss-Newton steps over all matches
};

// d pixel_b / d pixel_a in image pixels near A's point pa and B's point pb: the prediction's local
// affine map (ideal pixels) conjugated by the lens's local Jacobians, which are taken at the image
// positions instead of the ideal ones (a few per cent off at the corners of a strong lens; no
// iterative undistortion). The identity when the prediction has no window or no finite map.
Eigen::Matrix2f PatchWarpInImage(const KeypointPrediction& prediction, const PinholeCamera& camera,
                                 const Eigen::Vector2f& pa, const Eigen::Vector2f& pb);

// gray_a / gray_b: 8-bit single-channel images of the two frames. keypoints in image pixels as
// the detector gave them. predictions: one per keypoint of A, or empty (identity warp).
// Throws InvalidArgument for empty or non-8-bit images and size mismatches.
SubpixelStats RefineMatches(const cv::Mat& gray_a, const cv::Mat& gray_b,
                            const std::vector<cv::KeyPoint>& keypoints_a,
                            const std::vector<cv::KeyPoint>& keypoints_b,
                            const std::vector<KeypointPrediction>& predictions,
                            const PinholeCamera& camera, const SubpixelOptions& options,
                            std::vector<Match>& matches);

}  // namespace imumatch
