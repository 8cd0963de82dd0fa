#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/eval/evaluation_options.h"
#include "imumatch/eval/frame_source.h"
#include "imumatch/eval/ground_truth.h"
#include "imumatch/eval/pair_selection.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/imu/time_offset.h"
#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"
#include "imumatch/matching/subpixel_refinement.h"

// The per-pair evaluation pipeline: frames read on a reader thread, features extracted once per
// frame, the motion from the IMU or the ground truth, every method run on the same keypoints and
// judged against the ground truth. Frame sources, pair selection, options, summaries and the
// end-to-end timing have headers of their own beside this one.

namespace imumatch {

// PadBinaryDescriptors (AKAZE's 61-byte rows for DescriptorView): matching/descriptor_distance.h.

enum class SecondPassOutcome {
  kNotTried,      // not the guided method, or --single-pass
  kRan,           // matched again in the fitted motion's windows
  kNoFit,         // no fit (too few matches, residuals beyond the keypoints' noise, no convergence)
  kFitDisagreed,  // the fit strayed beyond the IMU's uncertainty: the first pass stands
  kNotTighter,    // the fitted windows search no less than the first pass's: it stands
};
const char* ToString(SecondPassOutcome outcome);  // "not_tried", "ran", ...

struct MethodRun {
  MatchMethod method = MatchMethod::kBruteForce;
  double predict_ms = 0.0;  // depth lookup + prediction (guided methods only)
  double match_ms = 0.0;    // grid + matching, or brute force
  double refine_ms = 0.0;   // sub-pixel refinement (guided, when enabled)
  // Guided, second pass (EvaluationOptions::second_pass): what happened, the fit, its cost
  // (included in predict_ms), and the search windows' mean half size (px; the capsule's radius
  // without depth) of the first pass and of the final one.
  SecondPassOutcome second_pass = SecondPassOutcome::kNotTried;
  MotionRefit refit;
  double refit_ms = 0.0;
  double first_window_px = 0.0;
  double window_px = 0.0;
  // Of the second pass's segments (keypoints without depth), how many were cut to the inverse
  // depths their matched neighbours show (EvaluationOptions::neighbour_depth).
  int narrowed_segments = 0;
  // The fitted motion against the ground truth (when refit.ok), as the record's motion errors.
  double refit_rotation_error_deg = 0.0;
  double refit_translation_error_m = 0.0;
  // The ground truth's squared Mahalanobis distance from the fitted motion under the fit's
  // covariance (6 dof; median 5.35 and beyond 22.46 one time in a thousand when the covariance
  // holds, ground-truth noise aside). 0 when !refit.ok.
  double refit_truth_mahalanobis2 = 0.0;
  SubpixelStats refine_stats;
  // Guided, second look by the image patch (EvaluationOptions::patch_second_look): what it did,
  // its cost (included in match_ms), and per match 1 when it found the match.
  PatchMatchingStats patch;
  double patch_ms = 0.0;
  std::vector<uint8_t> match_by_patch;
  // Tracking methods: how every track ended; hybrid: how many correspondences each path made.
  TrackStats track_stats;
  int from_tracks = 0;
  int from_descriptors = 0;
  std::vector<MatchResidual> residuals;  // one per match
  MatchStats stats;                      // guided methods: outcome of every query
  SceneNearDepth scene_near;             // guided methods: the segments' near end
  std::vector<QueryOutcome> outcomes;    // guided methods: per query
  // Guided methods, when the record has a brute-force run: for each of its matches, whether this
  // method's search region for the query contained the brute-force partner, and how the query
  // was predicted. The window recall of a threshold is the share of the brute-force matches
  // judged correct there whose partner lay inside (WindowRecall in summary.h).
  std::vector<uint8_t> bf_partner_in_window;
  std::vector<PredictionStatus> bf_partner_prediction;
  // For a partner outside an epipolar capsule: 1 when it lies within the capsule's radius of the
  // segment's line but beyond one of its ends (a depth outside the searched range, or a match on
  // the wrong side of the point at infinity), 0 when it is off the line.
  std::vector<uint8_t> bf_partner_beyond_segment;
  // What became of each brute-force match's query in this run: the index of this run's match of
  // the same query keypoint (-1: none) and the query's outcome; and, per match of this run, the
  // index of the brute-force match of its query (-1: brute force did not match it). Guided
  // methods with a brute-force run in the record (ComputeBruteForceFate in summary.h).
  std::vector<int> bf_query_match;
  std::vector<QueryOutcome> bf_query_outcome;
  std::vector<int> match_bf_match;
};

// One detector on one frame pair.
struct DetectorPairRecord {
  std::string case_name;
  size_t pair_index = 0;  // ordinal in the selected pairs of the case
  size_t frame_a = 0, frame_b = 0;
  int64_t t_a_ns = 0, t_b_ns = 0;
  DetectorKind detector = DetectorKind::kOrb;
  int keypoints_a = 0, keypoints_b = 0;
  int keypoints_a_with_depth = 0;
  double read_ms = 0.0;     // decoding both frames (reader thread), shared by the detectors
  double extract_ms = 0.0;  // detection + description of both frames
  double motion_ms = 0.0;   // IMU integration (shared by the guided methods)
  double motion_rotation_error_deg = 0.0;  // |IMU motion vs ground truth|
  double motion_translation_error_m = 0.0;
  bool has_depth = false;               // frame A had a depth image
  std::vector<GtCandidate> candidates;  // for the possible-correspondence count (recall)
  std::vector<MethodRun> runs;
  int bf_run = -1;  // index in runs of the first brute-force run (-1: none)
};

struct SkippedPair {
  std::string case_name;
  size_t pair_index = 0;
  size_t frame_a = 0, frame_b = 0;
  std::string detector;  // empty: the whole pair was skipped
  std::string reason;
};

// What the match images need.
struct PairVisual {
  std::string case_name;
  size_t pair_index = 0;
  DetectorKind detector = DetectorKind::kOrb;
  cv::Mat image_a, image_b;
  std::vector<cv::KeyPoint> keypoints_a, keypoints_b;
  struct Run {
    MatchMethod method = MatchMethod::kBruteForce;
    std::vector<Match> matches;
    std::vector<MatchResidual> residuals;
    std::vector<KeypointPrediction> predictions;  // guided methods, in ideal pixels
  };
  PinholeCamera camera;  // maps the predictions' ideal pixels to the image (IdealToPixel)
  std::vector<Run> runs;
};

struct EvaluationResult {
  std::vector<DetectorPairRecord> records;
  std::vector<SkippedPair> skipped;
  std::vector<PairVisual> visuals;
  std::vector<std::string> notes;  // e.g. "no depth in this dataset: epipolar judging only"
  // Inputs that look wrong (depth images without any valid depth, ground truth that disagrees with
  // the images or the IMU by far more than their noise, frames dropped by the loader): the
  // figures may be meaningless. Printed by the CLI and recorded in the report.
  std::vector<std::string> warnings;
  // Recorded IMU: per case and detector, the camera's clock offset from the IMU's measured from
  // the guided pairs' fitted rotations (EstimateTimeOffset; also in notes, and in warnings with
  // TimeOffsetAdvice when worth setting).
  struct TimeOffset {
    std::string case_name;
    DetectorKind detector = DetectorKind::kOrb;
    TimeOffsetEstimate estimate;
  };
  std::vector<TimeOffset> time_offsets;
  size_t pairs_total = 0;  // pairs selected
  double wall_s = 0.0;
  void Append(EvaluationResult other);
};

// Sanity checks on the evaluated records: depth images without valid depth, a ground truth that
// places brute-force matches a median over kMaxPlausibleMedianResidualPx away, and (recorded IMU)
// an IMU rotation a median over kMaxPlausibleImuRotationErrorDeg off the ground truth. One
// warning line each; EvaluateSource adds them to the result.
inline constexpr double kMaxPlausibleMedianResidualPx = 8.0;
inline constexpr double kMaxPlausibleImuRotationErrorDeg = 0.5;
std::vector<std::string> CheckInputsLookRight(const std::vector<DetectorPairRecord>& records,
                                              bool recorded_imu);

// Evaluates every selected pair of the source. case_name labels the records (default: the
// dataset's name). Never throws for per-pair problems (missing depth, too few features, IMU gap,
// unreadable image): they go to result.skipped with a reason.
EvaluationResult EvaluateSource(const EvalSource& source, const std::vector<FramePair>& pairs,
                                const EvaluationOptions& options,
                                const std::string& case_name = "");

}  // namespace imumatch
