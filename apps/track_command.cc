// imumatch track: the front end on a recording, no ground truth given to it. Writes the
// per-frame CSV, the trajectory in TUM format, a report and match images; judges the matches and
// the trajectory when the dataset has ground truth.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "commands.h"
#include "imumatch/core/error.h"
#include "imumatch/eval/frame_source.h"
#include "imumatch/eval/track_run.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/output_files.h"
#include "number_checks.h"

namespace imumatch::apps {
namespace {

struct TrackArgs {
  std::string path;
  std::string out = "imumatch-track-out";
  bool overwrite = false;
  std::string detector = "orb";
  int max_keypoints = 1000;
  bool hybrid = false;
  bool no_second_pass = false;
  bool no_neighbour_depth = false;
  bool monocular = false;
  bool fixed_gyro_bias = false;
  bool estimate_time_offset = false;
  bool fixed_segments = false;
  double still_s = 0.5;
  size_t first = 0;
  size_t max_frames = 0;
  int images = 2;
  std::string thresholds = "1,3,8";
  int threads = 0;
  bool progress = false;
  std::string imu_model = "euroc";
  uint64_t seed = 42;
  std::string camera;
  std::optional<double> timeshift;
};

void RunTrackCommand(const TrackArgs& a) {
  TrackRunOptions o;
  o.front_end.features.kind = ParseDetectorKind(a.detector);
  o.front_end.features.max_keypoints = a.max_keypoints;
  o.front_end.hybrid = a.hybrid;
  o.front_end.second_pass = !a.no_second_pass;
  o.front_end.neighbour_depth.enabled = !a.no_neighbour_depth;
  o.monocular = a.monocular;
  o.front_end.learn_gyro_bias = !a.fixed_gyro_bias;
  o.front_end.estimate_time_offset = a.estimate_time_offset;
  o.front_end.prediction.scene_near.enabled = !a.fixed_segments;
  o.front_end.still_s = a.still_s;
  IMUMATCH_REQUIRE(a.max_frames != 1,
                   "--max-frames must be 0 (all) or at least 2: one frame has no pair to track");
  o.first_frame = a.first;
  o.max_frames = a.max_frames;
  o.keep_visuals = a.images;
  // With two or more threads, ORB's pyramid levels are split between two of them (the front
  // end's latency per frame; FeatureOptions::threads).
  o.front_end.features.threads = std::min(2, ApplyThreads(a.threads));
  o.thresholds_px.clear();
  std::stringstream list(a.thresholds);
  for (std::string item; std::getline(list, item, ',');) {
    if (item.empty()) continue;
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    IMUMATCH_REQUIRE(end != item.c_str() && *end == '\0' && std::isfinite(v) && v > 0.0,
                     "--thresholds: '" << item << "' is not a positive number of pixels");
    o.thresholds_px.push_back(v);
  }
  o.Check();
  const OutputFolderCheck check = PrepareOutputFolder(a.out, a.overwrite);
  if (!check.note.empty()) std::cerr << "imumatch: note: " << check.note << "\n";
  DatasetOptions dopts;
  dopts.imu_model = a.imu_model;
  dopts.imu_seed = a.seed;
  // A missing image is a bad frame: skipped with its name when it is read, the run goes on.
  dopts.check_files_exist = false;
  if (!a.camera.empty()) dopts.camera = ReadCameraFile(a.camera);
  dopts.timeshift_cam_imu_s = a.timeshift;
  const EvalSource source = MakeDiskSource(LoadDataset(a.path, dopts));
  std::cerr << "imumatch track: " << source.dataset.name << " (" << source.dataset.frames.size()
            << " frames); IMU: " << source.dataset.imu_source_note << "\n";
  for (const std::string& w : source.dataset.warnings) {
    std::cerr << "imumatch: warning: " << w << "\n";
  }
  const size_t frames = source.dataset.frames.size();
  if (frames < 2) {
    throw InputError(a.path, source.dataset.name + " has " + std::to_string(frames) +
                                 (frames == 1 ? " frame" : " frames") +
                                 ": tracking needs at least two");
  }
  if (a.first > frames - 2) {
    throw InvalidArgument("--first " + std::to_string(a.first) + ": " + source.dataset.name +
                          " has " + std::to_string(frames) +
                          " frames; tracking needs two from the first (at most --first " +
                          std::to_string(frames - 2) + ")");
  }
  const size_t first = a.first;
  const size_t n = a.max_frames > 0 ? std::min(a.max_frames, source.dataset.frames.size() - first)
                                    : source.dataset.frames.size() - first;
  o.progress = MakeProgress(a.progress, n, "track", "frames");
  const TrackRunResult result = RunTrack(source, o);
  const std::string report = TrackReportMarkdown(
      result, o,
      {{"dataset", a.path},
       {"camera", source.dataset.camera.ToString()},
       {"detector", a.detector + ", " + std::to_string(a.max_keypoints) + " keypoints"},
       {"matcher", std::string(a.hybrid ? "hybrid (IMU-seeded KLT + guided)" : "guided") +
                       (a.no_second_pass ? ", one pass" : ", two passes") +
                       (a.fixed_segments ? ", fixed segments" : "") +
                       (a.monocular ? ", monocular (depth images only judge)" : "")},
       {"ground truth",
        result.has_truth ? "judged afterwards, never given to the front end" : "none"}});
  std::cout << report << std::flush;
  for (const std::string& w : result.warnings) std::cerr << "imumatch: warning: " << w << "\n";
  const auto files = WriteTrackOutputs(a.out, result, o, report);
  RecordOutputs(a.out, files);
  std::cout << "\nWrote " << files.size() << " files to " << a.out
            << " (report.md, frames.csv, trajectory.txt, match_*.png)\n";
}

}  // namespace

void AddTrackCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "track",
      "Run the front end on a recording (TUM RGB-D, EuRoC, synthetic folder) with no ground truth "
      "given to it: state from the IMU's still start and the fitted poses, two matching passes, "
      "brute force when lost; judged afterwards when the dataset has ground truth");
  auto a = std::make_shared<TrackArgs>();
  cmd->add_option("DATASET", a->path, "dataset folder")->required();
  cmd->add_option("--out", a->out, "output folder")->capture_default_str();
  cmd->add_flag("--overwrite", a->overwrite,
                "write into an --out folder that holds files imumatch did not write");
  cmd->add_option("--detector", a->detector, "sift, surf, orb, fast, akaze or brisk")
      ->capture_default_str();
  cmd->add_option("--max-keypoints", a->max_keypoints, "keypoints per frame")
      ->capture_default_str()
      ->check(CLI::Range(1, FeatureOptions::kMaxKeypoints));
  cmd->add_flag("--hybrid", a->hybrid,
                "track with the IMU-seeded KLT first, guided matching for the failed tracks");
  cmd->add_flag("--one-pass", a->no_second_pass, "no second matching pass with the fitted pose");
  cmd->add_flag("--no-neighbour-depth", a->no_neighbour_depth,
                "second pass: search keypoints without depth along their whole segment, not along "
                "the inverse depths their matched neighbours show");
  cmd->add_flag(
      "--estimate-time-offset", a->estimate_time_offset,
      "estimate the camera's clock offset from the IMU's from the fitted rotations as the "
      "run goes and read the IMU in the camera's clock (a camera not triggered by the "
      "IMU, its timeshift not calibrated)");
  cmd->add_flag("--fixed-gyro-bias", a->fixed_gyro_bias,
                "without a still start, keep the gyro bias at zero (do not learn it from the "
                "rotations the fitted motions measure; after a still start it is never learnt)");
  cmd->add_flag("--monocular", a->monocular,
                "give the front end no depth images (a monocular camera); where the dataset has "
                "them they only judge the matches");
  cmd->add_flag("--fixed-segments", a->fixed_segments,
                "keypoints without depth: epipolar segments from 0.1 m, not from the nearest "
                "depth a pilot of matches shows");
  cmd->add_option("--still", a->still_s,
                  "seconds of still IMU at the start (gravity and gyro bias)")
      ->capture_default_str()
      ->check(NumberIn(0.0, false, 3600.0, false));
  cmd->add_option("--first", a->first, "first frame")->capture_default_str();
  cmd->add_option("--camera", a->camera, kCameraOptionHelp);
  cmd->add_option("--timeshift-cam-imu", a->timeshift, kTimeshiftOptionHelp)
      ->check(NumberIn(-1.0, false, 1.0, false));
  cmd->add_option("--max-frames", a->max_frames, "frames to run (0 = all)")->capture_default_str();
  cmd->add_option("--images", a->images, "match images of the first N judged frames")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--threads", a->threads,
                  "worker threads of OpenCV (0 = all cores); with 2 or more, ORB's pyramid levels "
                  "are split between two")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--thresholds", a->thresholds,
                  "thresholds (px) at which matches are judged when there is ground truth")
      ->capture_default_str();
  cmd->add_flag("--progress", a->progress, "progress bar on stderr (default: when it is a TTY)");
  cmd->add_option("--imu-model", a->imu_model,
                  "noise model of simulated IMUs: euroc | mems | ideal")
      ->capture_default_str();
  cmd->add_option("--seed", a->seed, "seed of a simulated IMU")->capture_default_str();
  cmd->callback([a] { RunTrackCommand(*a); });
}

}  // namespace imumatch::apps
