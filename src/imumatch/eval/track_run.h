#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/frame_source.h"
#include "imumatch/eval/ground_truth.h"
#include "imumatch/eval/trajectory_error.h"
#include "imumatch/frontend/front_end.h"

namespace imumatch {

// `imumatch track`: a dataset's frames and IMU fed to a FrontEnd in time order, no ground truth
// given to it. When the dataset has ground truth, every frame's matches (both passes) are judged
// afterwards at fixed thresholds and the estimated trajectory's relative pose error is computed.
struct TrackRunOptions {
  FrontEndOptions front_end;
  // The front end is given no depth images (a monocular camera's run); they still judge.
  bool monocular = false;
  size_t first_frame = 0;
  size_t max_frames = 0;  // 0 = all
  std::vector<double> thresholds_px = {1.0, 3.0, 8.0};
  GroundTruthOptions ground_truth;
  int keep_visuals = 0;  // match images of the first N matched frames (judged runs only)
  std::function<void(size_t, size_t)> progress;
  void Check() const;
};

struct TrackFrameRecord {
  size_t frame = 0;   // index in the dataset
  std::string error;  // the frame could not be read: skipped (the run goes on)
  FrontEndResult result;
  double read_ms = 0.0;
  bool judged = false;  // ground truth for this frame and the previous one
  // Per threshold: the final pass's and the first pass's matches judged.
  std::vector<JudgedCounts> final_counts, pass1_counts;
  double rpe_translation_m = -1.0, rpe_rotation_deg = -1.0;  // to the previous frame (-1: none)
};

struct TrackRunResult {
  std::string dataset_name;
  std::vector<TrackFrameRecord> frames;
  std::vector<std::string> notes;
  bool has_truth = false;
  // The gyro bias (rad/s, IMU frame) the front end learnt from its fits, when it learnt one.
  std::optional<Eigen::Vector3d> learnt_gyro_bias;
  // The camera's clock offset from the IMU's, measured from the front end's fitted rotations
  // (a recorded IMU with fits), and the advice to set it when it is worth it (warnings).
  std::optional<TimeOffsetEstimate> time_offset;
  // The offset the front end read the IMU with at the end (FrontEndOptions::estimate_time_offset;
  // else 0).
  double imu_time_offset_s = 0.0;
  std::vector<std::string> warnings;
  RelativePoseError rpe;
  std::vector<PairVisual> visuals;
  double wall_s = 0.0;
  int FallbackCount() const;  // frames matched by brute force
};

// Throws InputError when the dataset has no IMU; reading errors of single frames are recorded.
TrackRunResult RunTrack(const EvalSource& source, const TrackRunOptions& options);

// report.md: configuration, events, per-pass precision, RPE, timing.
std::string TrackReportMarkdown(const TrackRunResult& result, const TrackRunOptions& options,
                                const std::vector<std::pair<std::string, std::string>>& config);
// Writes frames.csv, trajectory.txt (TUM format: t tx ty tz qx qy qz qw, world_from_cam),
// report.md and the match images; returns the file names.
std::vector<std::string> WriteTrackOutputs(const std::string& dir, const TrackRunResult& result,
                                           const TrackRunOptions& options,
                                           const std::string& report_markdown);

}  // namespace imumatch
