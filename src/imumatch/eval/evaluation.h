#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/core/time.h"
#include "imumatch/eval/ground_truth.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/io/dataset.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch {

// ---------------------------------------------------------------------------------------------
// Frame sources

// The decoded images of one frame. image: 8-bit gray or BGR; depth: CV_16U raw or empty.
struct FrameImages {
  cv::Mat image;
  cv::Mat depth;
};

// Reads frame `index` of a dataset (with its depth image when with_depth is set and the frame has
// one). Throws InputError for unreadable files.
using FrameReader = std::function<FrameImages(size_t index, bool with_depth)>;

// A dataset plus the way to read its images, and whether its ground truth is exact (synthetic) or
// measured (real: motion capture + Kinect depth).
struct EvalSource {
  Dataset dataset;
  FrameReader reader;
  bool exact_ground_truth = false;
};

// Reads FrameRecord::image_path / depth_path with io's LoadImage / LoadDepth (gray images).
FrameReader MakeDiskFrameReader(const Dataset& dataset);
// The dataset as LoadDataset returns it, read from disk. Ground truth is exact for kSynthetic.
EvalSource MakeDiskSource(Dataset dataset);
// An in-memory synthetic sequence (no files): the frames are PNG-encoded once here so that the
// "read" stage decodes a PNG, like reading a file would. case_name names the dataset.
EvalSource MakeSyntheticSource(const SyntheticSequence& sequence, const std::string& case_name);

// ---------------------------------------------------------------------------------------------
// Frame pairs

struct FramePair {
  size_t a = 0;
  size_t b = 0;
};

struct PairSelection {
  // Exactly one mode: explicit pairs (non-empty), an interval in seconds (> 0: b is the frame
  // nearest to t_a + interval, the next a is that b), or a step in frames (a, a + step), a
  // advancing by step. Default: consecutive frames (step 1).
  std::vector<FramePair> explicit_pairs;
  double interval_s = 0.0;
  int step = 1;
  size_t max_pairs = 0;  // 0 = all
  void Check() const;
};

// Adapter: matching's DescriptorView needs binary descriptors whose row length is a multiple of 8
// bytes, but AKAZE's MLDB has 61. Pads CV_8U rows with zero bytes up to the next multiple of 8
// (Hamming distances are unchanged); other matrices are returned as they are.
cv::Mat PadBinaryDescriptors(const cv::Mat& descriptors);

// Throws InvalidArgument for explicit pairs outside the frame list or with a >= b.
std::vector<FramePair> SelectFramePairs(const std::vector<FrameRecord>& frames,
                                        const PairSelection& selection);

// ---------------------------------------------------------------------------------------------
// Methods and options

enum class MatchMethod {
  kBruteForce,     // OpenCV BFMatcher::knnMatch(k=2) + ratio test: the baseline
  kGuided,         // IMU prediction + uncertainty windows + guided matcher
  kFixedWindow,    // IMU prediction + the paper's fixed +-10 px window
  kOwnBruteForce,  // imumatch's exhaustive matcher + ratio test
};
std::string ToString(MatchMethod method);     // "bf", "guided", "fixed10", "bf_own"
std::string DisplayName(MatchMethod method);  // "BF knn+ratio", "IMU-guided", ...
MatchMethod ParseMatchMethod(std::string_view name);
bool UsesPrediction(MatchMethod method);

enum class MotionSource {
  kImu,          // integrate the dataset's IMU samples (recorded or simulated)
  kGroundTruth,  // the exact ground-truth relative pose (an ideal IMU + VIO)
};
MotionSource ParseMotionSource(std::string_view name);  // "imu" | "gt"
const char* ToString(MotionSource source);

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

  PredictionOptions prediction;
  GuidedMatcherOptions guided;
  GroundTruthOptions ground_truth;

  // Keep the images, keypoints, matches and predictions of the first `keep_visuals` pairs of the
  // source (for match images).
  int keep_visuals = 0;
  // Reader thread: frame pairs decoded ahead of processing (bounded queue). 0 = read inline.
  int queue_capacity = 2;
  // Called after every processed pair with (done, total).
  std::function<void(size_t, size_t)> progress;
  void Check() const;
};

// ---------------------------------------------------------------------------------------------
// Results

struct MethodRun {
  MatchMethod method = MatchMethod::kBruteForce;
  double predict_ms = 0.0;               // depth lookup + prediction (guided methods only)
  double match_ms = 0.0;                 // grid + matching, or brute force
  std::vector<MatchResidual> residuals;  // one per match
  MatchStats stats;                      // guided methods: outcome of every query
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
  std::vector<GtCandidate> candidates;  // for the possible-correspondence count (recall)
  std::vector<MethodRun> runs;
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
    std::vector<KeypointPrediction> predictions;  // guided methods
  };
  std::vector<Run> runs;
};

struct EvaluationResult {
  std::vector<DetectorPairRecord> records;
  std::vector<SkippedPair> skipped;
  std::vector<PairVisual> visuals;
  std::vector<std::string> notes;  // e.g. "no depth in this dataset: epipolar judging only"
  size_t pairs_total = 0;          // pairs selected
  double wall_s = 0.0;
  void Append(EvaluationResult other);
};

// Evaluates every selected pair of the source. case_name labels the records (default: the
// dataset's name). Never throws for per-pair problems (missing depth, too few features, IMU gap,
// unreadable image): they go to result.skipped with a reason.
EvaluationResult EvaluateSource(const EvalSource& source, const std::vector<FramePair>& pairs,
                                const EvaluationOptions& options,
                                const std::string& case_name = "");

// The threshold used to call a match correct.
struct ThresholdChoice {
  double threshold_px = 1.5;
  std::string description;
  std::optional<AutoThreshold> automatic;
};
// Fixed (explicit_px given), 1.5 px for exact ground truth, otherwise ComputeAutoThreshold on
// the depth residuals of the brute-force matches of all records.
ThresholdChoice ChooseThreshold(const EvaluationResult& result, bool exact_ground_truth,
                                std::optional<double> explicit_px);

// ---------------------------------------------------------------------------------------------
// Summaries

struct StageStats {
  double mean = 0.0, p50 = 0.0, p90 = 0.0, p99 = 0.0;
  int count = 0;
};
StageStats ComputeStageStats(std::vector<double> values);  // nearest-rank percentiles

// One (case, detector, method) row, judged at one threshold.
struct MethodSummary {
  std::string case_name;
  DetectorKind detector = DetectorKind::kOrb;
  MatchMethod method = MatchMethod::kBruteForce;
  int pairs = 0;
  double keypoints = 0.0;  // mean over both frames
  StageStats read_ms, extract_ms, predict_ms, match_ms,
      total_ms;                                      // total: extract+motion+predict+match
  double matches = 0.0, correct = 0.0, wrong = 0.0;  // means per pair
  double possible = 0.0;                             // mean GT-possible correspondences
  double precision = 0.0;                            // pooled: sum correct / sum matches
  double recall = 0.0;             // pooled: sum correct (depth-judged) / sum possible
  double epipolar_fraction = 0.0;  // share of matches judged without depth
};

// Per-pair counts of one run at a threshold.
struct RunCounts {
  JudgedCounts counts;
  int possible = 0;
  double precision = 0.0;
  double recall = 0.0;
};
RunCounts CountRun(const DetectorPairRecord& record, const MethodRun& run, double threshold_px);

// Rows ordered by case (first appearance), detector, method.
std::vector<MethodSummary> Summarize(const std::vector<DetectorPairRecord>& records,
                                     double threshold_px);

// ---------------------------------------------------------------------------------------------
// End-to-end timing: a stream of consecutive frames, each read, described with ORB and matched
// with the previous frame.
//   - sequential OpenCV: imread (gray), cv::ORB (max_keypoints), BFMatcher knnMatch + ratio 0.8;
//   - imumatch pipelined: a reader thread decodes the next frame (image + depth) while the current
//     one is processed: ORB, IMU camera motion, prediction, guided matching.
struct EndToEndOptions {
  size_t first_frame = 0;
  size_t max_frames = 30;
  int max_keypoints = 1000;
  void Check() const;
};
struct EndToEndTiming {
  int frames = 0;
  int width = 0, height = 0;
  double sequential_ms_per_frame = 0.0;
  double pipelined_ms_per_frame = 0.0;
  int sequential_matches = 0;  // totals over the stream, for a sanity check
  int pipelined_matches = 0;
  int motion_failures = 0;  // frames without a motion (IMU gap / no GT): matched by brute force
  std::string Describe() const;
};
EndToEndTiming MeasureEndToEnd(const EvalSource& source, const EvaluationOptions& options,
                               const EndToEndOptions& e2e);

}  // namespace imumatch
