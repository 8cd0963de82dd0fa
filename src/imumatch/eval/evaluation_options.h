#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "imumatch/eval/ground_truth.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/frontend/motion_refit.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/imu/gyro_bias_filter.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/klt_tracker.h"
#include "imumatch/matching/neighbour_depth.h"
#include "imumatch/matching/patch_matching.h"
#include "imumatch/matching/predictor.h"
#include "imumatch/matching/subpixel_refinement.h"

namespace imumatch {

enum class MatchMethod {
  kBruteForce,     // OpenCV BFMatcher::knnMatch(k=2) + ratio test: the baseline
  kGuided,         // IMU prediction + uncertainty windows + guided matcher
  kFixedWindow,    // IMU prediction + the paper's fixed +-10 px window
  kOwnBruteForce,  // imumatch's exhaustive matcher + ratio test
  // Tracking: correspondences from A's keypoints to tracked positions in B (no keypoint of B).
  kKltUnseeded,  // VINS-style pyramidal LK from each keypoint's own position (OpenCV)
  kKlt,          // LK seeded at the IMU prediction, gated by its window (TrackSeeded)
  kHybrid,       // kKlt, and guided matching for the keypoints whose track failed
};
// "bf", "guided", "fixed10", "bf_own", "klt0", "klt", "hybrid"
std::string ToString(MatchMethod method);
std::string DisplayName(MatchMethod method);  // "BF knn+ratio", "IMU-guided", ...
MatchMethod ParseMatchMethod(std::string_view name);
bool UsesPrediction(MatchMethod method);  // guided, fixed10, klt, hybrid
bool IsBruteForce(MatchMethod method);    // bf, bf_own
bool IsTracking(MatchMethod method);      // klt0, klt, hybrid

enum class MotionSource {
  kImu,          // integrate the dataset's IMU samples (recorded or simulated)
  kGroundTruth,  // the exact ground-truth relative pose (an ideal IMU + VIO)
};
MotionSource ParseMotionSource(std::string_view name);  // "imu" | "gt"
const char* ToString(MotionSource source);

// The unseeded baseline's settings (VINS-Fusion's feature tracker): 21 x 21 window, pyramid
// levels 0-3, forward-backward check 0.5 px.
KltOptions VinsKltOptions();

struct EvaluationOptions {
  std::vector<DetectorKind> detectors = {DetectorKind::kSift,  DetectorKind::kSurf,
                                         DetectorKind::kOrb,   DetectorKind::kFastBrief,
                                         DetectorKind::kAkaze, DetectorKind::kBrisk};
  FeatureOptions features;  // kind is replaced per detector; max_keypoints = 1000
  std::vector<MatchMethod> methods = {MatchMethod::kBruteForce, MatchMethod::kGuided,
                                      MatchMethod::kFixedWindow};
  double ratio = 0.8;  // Lowe's ratio for the brute-force methods (the guided one: guided.ratio)

  MotionSource motion_source = MotionSource::kImu;
  CameraMotionOptions motion;  // mode (so3 | paper) and the sigmas the predictor is told
  // The IMU state at frame A comes from the ground truth (what a VIO back-end would supply),
  // perturbed by these 1-sigma errors (negative: use motion.velocity_sigma / attitude_sigma):
  // velocity per axis (m/s), roll and pitch (rad). Seeded with seed + pair index.
  double velocity_perturbation_sigma = -1.0;
  double attitude_perturbation_sigma = -1.0;
  uint64_t seed = 1;
  // Gyro bias from the first still_init_s seconds of a recorded IMU log (see EstimateImuBias);
  // 0 integrates without a bias estimate.
  double still_init_s = 1.0;
  // Recorded IMU: each detector keeps a gyro bias filter (GyroBiasFilter), started from the still
  // start's estimate (or from zero with gyro_bias_filter.unknown_bias_sigma when the log does not
  // start still) and fed with the rotation each guided pair's fitted motion measures
  // (ImuRotationFromFit), as a visual-inertial estimator keeps its bias; the next pair's IMU
  // motion removes that bias and is told its sigma. false: the still start's bias throughout.
  bool gyro_bias_from_matches = true;
  GyroBiasFilterOptions gyro_bias_filter;

  PredictionOptions prediction;
  // Predict as a camera without depth would (every keypoint along its epipolar segment), also
  // where frame A has a depth image: that image then only judges the matches. Measures the
  // monocular path against the exact judge of depth.
  bool monocular = false;
  GuidedMatcherOptions guided;
  // Guided methods: refine each match's position in B to sub-pixel accuracy against A's patch
  // warped by the IMU's prediction (RefineMatches); the judge then judges the refined position.
  bool refine_subpixel = true;
  SubpixelOptions subpixel;
  // Guided method: fit the motion to the first pass's matches (RefitMotion) and match again with
  // the windows of the fitted motion's covariance; the first pass stands when the fit fails or
  // disagrees with the IMU.
  bool second_pass = true;
  MotionRefitOptions refit;
  // Second pass: the segments of keypoints without depth cut to the inverse depths their matched
  // neighbours show (NeighbourInverseDepthRanges, PredictKeypointsInRanges).
  NeighbourDepthOptions neighbour_depth;
  // Guided method: the queries still unmatched are looked at again by the image patch (A's patch
  // warped by the prediction, aligned at each candidate: MatchByPatch); charged to matching.
  bool patch_second_look = true;
  PatchMatchingOptions patch;
  GroundTruthOptions ground_truth;
  // Tracking methods: the seeded tracker (klt, hybrid) and the unseeded baseline (klt0, with
  // VINS-Fusion's settings: 21 x 21 window, 3 levels, forward-backward <= 0.5 px).
  KltOptions klt;
  KltOptions klt_unseeded = VinsKltOptions();
  // Exposure change: frame B of every pair is multiplied by this gain (saturated to 8 bits)
  // before features are extracted and matched; 1 leaves the images as read.
  double gain_b = 1.0;

  // Keep the images, keypoints, matches and predictions of the first `keep_visuals` pairs of the
  // source (for match images).
  int keep_visuals = 0;
  // Reader thread: frame pairs decoded ahead of processing (bounded queue). 0 = read inline.
  int queue_capacity = 2;
  // Called after every processed pair with (done, total).
  std::function<void(size_t, size_t)> progress;
  void Check() const;
};

}  // namespace imumatch
