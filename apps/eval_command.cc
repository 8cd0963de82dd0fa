// imumatch eval / imumatch demo: how much faster and how much more correct is IMU-guided matching
// than brute force, for each detector, on a dataset (eval) or on the built-in synthetic seed cases
// (demo). Prints the two tables of the seed paper as Markdown and writes CSV, JSON and PNGs.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "commands.h"
#include "imumatch/core/error.h"
#include "imumatch/eval/end_to_end.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/outputs.h"
#include "imumatch/eval/report.h"
#include "imumatch/eval/seed_cases.h"
#include "imumatch/eval/summary.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/output_files.h"
#include "imumatch/io/pose_pair.h"
#include "number_checks.h"

namespace imumatch::apps {
namespace {

// Options shared by eval and demo.
struct CommonArgs {
  std::string out;
  std::string detectors = "sift,surf,orb,fast,akaze,brisk";
  std::string methods = "bf,guided,fixed10";
  int max_keypoints = 1000;
  double threshold = 0.0;  // 0: automatic
  std::string imu_mode = "so3";
  std::string motion_source = "imu";
  std::string imu_model = "euroc";
  uint64_t seed = 42;
  int images = 1;
  bool progress = false;
  int e2e_frames = 30;
  // Matching knobs (defaults: the library's option structs).
  double ratio = 0.8;
  bool mutual = false;
  double gate = 0.99;
  double fixed_half = 10.0;
  double z_min = -1.0, z_max = -1.0;  // < 0: PredictionOptions defaults
  bool fixed_segments = false;
  bool no_refine = false;
  bool single_pass = false;
  bool fixed_gyro_bias = false;
  bool no_patch_look = false;
  bool no_neighbour_depth = false;
  bool monocular = false;
  double guided_ratio = -1.0;           // < 0: --ratio
  double orientation_tolerance = -1.0;  // < 0: GuidedMatcherOptions default
  double still_s = 1.0;
  std::string sigma_scaling = "size";
  bool overwrite = false;
  double gain_b = 1.0;
  int threads = 0;
};

void AddCommonOptions(CLI::App* cmd, CommonArgs& a) {
  cmd->add_flag("--overwrite", a.overwrite,
                "write into an --out folder that holds files imumatch did not write");
  cmd->add_option("--detectors", a.detectors, "comma-separated: sift,surf,orb,fast,akaze,brisk")
      ->capture_default_str();
  cmd->add_option("--methods", a.methods,
                  "comma-separated: bf,guided,fixed10,bf_own,klt0,klt,hybrid")
      ->capture_default_str();
  cmd->add_option("--max-keypoints", a.max_keypoints, "keypoints per frame and detector")
      ->capture_default_str()
      ->check(CLI::Range(1, FeatureOptions::kMaxKeypoints));
  cmd->add_option(
         "--threshold", a.threshold,
         "correct-match threshold in px (default: 1.5 on synthetic data, automatic "
         "median + 3 MAD-sigma of brute-force residuals, clamped to [2, 10], on real data)")
      ->check(PositiveFinite());
  cmd->add_option("--imu-mode", a.imu_mode, "IMU integration: so3 | paper")->capture_default_str();
  cmd->add_option("--motion-source", a.motion_source,
                  "imu (integrate the IMU) | gt (exact ground-truth motion)")
      ->capture_default_str();
  cmd->add_option("--imu-model", a.imu_model, "noise model of simulated IMUs: euroc | mems | ideal")
      ->capture_default_str();
  cmd->add_option("--seed", a.seed, "seed of the simulated IMU and the state perturbation")
      ->capture_default_str();
  cmd->add_option("--images", a.images, "match images for the first N pairs of each case")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--e2e-frames", a.e2e_frames, "frames of the end-to-end ORB timing (0 = skip)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--progress", a.progress, "progress bar on stderr (default: when it is a TTY)");
  cmd->add_option("--ratio", a.ratio, "Lowe's ratio for brute force and guided matching")
      ->capture_default_str()
      ->check(NumberIn(0.0, true, 1.0, false));
  cmd->add_flag("--mutual", a.mutual, "guided: keep only mutual best matches");
  cmd->add_option("--gate", a.gate, "guided: chi-square gate probability of the search window")
      ->capture_default_str()
      ->check(NumberIn(0.0, true, 1.0, true));
  cmd->add_option("--fixed-window", a.fixed_half, "fixed10 method: half size of the square (px)")
      ->capture_default_str()
      ->check(PositiveFinite());
  cmd->add_option("--z-min", a.z_min,
                  "no-depth prediction: nearest depth of the segment (m; the scene may move it "
                  "further, see --fixed-segments)")
      ->check(PositiveFinite());
  cmd->add_flag("--fixed-segments", a.fixed_segments,
                "no-depth prediction: segments from --z-min, not from the nearest depth a pilot "
                "of matches shows");
  cmd->add_option("--z-max", a.z_max, "no-depth prediction: farthest depth of the segment (m)")
      ->check(PositiveFinite());
  cmd->add_option("--guided-ratio", a.guided_ratio,
                  "guided: Lowe's ratio inside the search region (default: --ratio)")
      ->check(NumberIn(0.0, true, 1.0, false));
  cmd->add_option("--sigma-scaling", a.sigma_scaling,
                  "keypoint localisation noise: size (grows with the keypoint's size) | none")
      ->capture_default_str();
  cmd->add_option("--orientation-tolerance", a.orientation_tolerance,
                  "guided: largest keypoint angle change off the predicted one (deg; 180 = no "
                  "orientation check)")
      ->check(NumberIn(0.0, false, 180.0, false));
  cmd->add_flag("--no-refine", a.no_refine,
                "guided: do not refine matched positions to sub-pixel accuracy");
  cmd->add_flag("--fixed-gyro-bias", a.fixed_gyro_bias,
                "recorded IMU: keep the still start's gyro bias (do not learn it from the guided "
                "pairs' fitted rotations)");
  cmd->add_flag("--no-patch-look", a.no_patch_look,
                "guided: no second look by the image patch at the queries left unmatched");
  cmd->add_flag("--no-neighbour-depth", a.no_neighbour_depth,
                "guided, second pass: search keypoints without depth along their whole segment, "
                "not along the inverse depths their matched neighbours show");
  cmd->add_flag("--monocular", a.monocular,
                "guided: predict without depth (along epipolar segments) also where frame A has a "
                "depth image, which then only judges the matches");
  cmd->add_flag("--single-pass", a.single_pass,
                "guided: match once with the IMU's windows (no second pass with the motion fitted "
                "to the first pass's matches)");
  cmd->add_option("--threads", a.threads,
                  "worker threads (0 = all cores); 1 also reads frames inline instead of on a "
                  "reader thread")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--gain-b", a.gain_b,
                  "exposure change: multiply frame B of every pair by this gain (1 = off)")
      ->capture_default_str()
      ->check(NumberIn(0.01, false, 100.0, false));
  cmd->add_option("--still", a.still_s,
                  "recorded IMU: seconds of still start used to estimate the gyro bias (0 = none)")
      ->capture_default_str()
      ->check(NonNegativeFinite());
}

std::vector<std::string> SplitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

EvaluationOptions MakeOptions(const CommonArgs& a) {
  EvaluationOptions o;
  o.detectors.clear();
  for (const auto& d : SplitList(a.detectors)) o.detectors.push_back(ParseDetectorKind(d));
  o.methods.clear();
  for (const auto& m : SplitList(a.methods)) o.methods.push_back(ParseMatchMethod(m));
  o.features.max_keypoints = a.max_keypoints;
  o.motion.mode = ParseIntegrationMode(a.imu_mode);
  o.motion_source = ParseMotionSource(a.motion_source);
  o.seed = a.seed;
  o.keep_visuals = a.images;
  IMUMATCH_REQUIRE(std::isfinite(a.threshold) && a.threshold >= 0.0,
                   "--threshold must be a finite number of pixels > 0, got " << a.threshold);
  IMUMATCH_REQUIRE(a.e2e_frames == 0 || a.e2e_frames >= 2, "--e2e-frames must be 0 or >= 2");
  o.ratio = a.ratio;
  o.guided.ratio = a.guided_ratio > 0.0 ? a.guided_ratio : a.ratio;
  o.guided.mutual = a.mutual;
  o.prediction.gate_probability = a.gate;
  o.prediction.fixed_half_size = a.fixed_half;
  if (a.z_min >= 0.0) o.prediction.segment_min_depth = a.z_min;
  if (a.z_max >= 0.0) o.prediction.segment_max_depth = a.z_max;
  IMUMATCH_REQUIRE(o.prediction.segment_max_depth > o.prediction.segment_min_depth,
                   "--z-max (" << o.prediction.segment_max_depth << " m"
                               << (a.z_max < 0.0 ? ", the default" : "")
                               << ") must be farther than --z-min ("
                               << o.prediction.segment_min_depth << " m"
                               << (a.z_min < 0.0 ? ", the default" : "") << ")");
  o.prediction.scene_near.enabled = !a.fixed_segments;
  o.refine_subpixel = !a.no_refine;
  o.second_pass = !a.single_pass;
  o.gyro_bias_from_matches = !a.fixed_gyro_bias;
  o.patch_second_look = !a.no_patch_look;
  o.neighbour_depth.enabled = !a.no_neighbour_depth;
  o.monocular = a.monocular;
  if (a.orientation_tolerance >= 0.0) o.guided.orientation_tolerance_deg = a.orientation_tolerance;
  if (a.sigma_scaling == "none") {
    o.prediction.sigma_scaling = KeypointSigmaScaling::kNone;
  } else if (a.sigma_scaling == "size") {
    o.prediction.sigma_scaling = KeypointSigmaScaling::kSize;
  } else {
    throw InvalidArgument("--sigma-scaling must be size or none, got '" + a.sigma_scaling + "'");
  }
  o.still_init_s = a.still_s;
  o.gain_b = a.gain_b;
  if (ApplyThreads(a.threads) == 1) o.queue_capacity = 0;  // one thread: no reader thread
  o.Check();
  return o;
}

std::string Join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ",") + s;
  return out;
}

void Finish(const EvaluationResult& result, ReportContext& context, const CommonArgs& a,
            const EvaluationOptions& o) {
  std::vector<std::string> detectors, methods;
  for (DetectorKind d : o.detectors) detectors.push_back(ToString(d));
  for (MatchMethod m : o.methods) methods.push_back(ToString(m));
  context.config.insert(context.config.end(), {{"detectors", Join(detectors)},
                                               {"methods", Join(methods)},
                                               {"max keypoints", std::to_string(a.max_keypoints)},
                                               {"motion source", ToString(o.motion_source)},
                                               {"imu mode", ToString(o.motion.mode)},
                                               {"imu model", a.imu_model},
                                               {"seed", std::to_string(a.seed)}});
  context.config.push_back({"second look by the patch", o.patch_second_look ? "on" : "off"});
  context.config.push_back(
      {"segments from the neighbours' depths", o.neighbour_depth.enabled ? "on" : "off"});
  if (o.monocular) {
    context.config.push_back({"prediction", "monocular (depth images only judge the matches)"});
  }
  for (const std::string& w : result.warnings) std::cerr << "imumatch: warning: " << w << "\n";
  std::cout << MarkdownReport(result, context) << std::flush;
  const auto files = WriteEvaluationOutputs(a.out, result, context);
  RecordOutputs(a.out, files);
  std::cout << "\nWrote " << files.size() << " files to " << a.out
            << " (report.md, report.json, summary.csv, pairs.csv, skipped.csv, time_*.png, "
               "precision_*.png, match_*.png)\n";
}

// Checked before the work starts: writable, and not a folder of somebody else's files.
void PrepareOut(const CommonArgs& a) {
  const OutputFolderCheck check = PrepareOutputFolder(a.out, a.overwrite);
  if (!check.note.empty()) std::cerr << "imumatch: note: " << check.note << "\n";
}

void RunEval(const std::string& path, const std::string& camera_file,
             std::optional<double> timeshift_s, CommonArgs a, double interval_s, int step,
             size_t max_pairs) {
  EvaluationOptions o = MakeOptions(a);
  PrepareOut(a);
  const std::optional<double> threshold =
      a.threshold > 0.0 ? std::optional<double>(a.threshold) : std::nullopt;
  EvalSource source;
  std::vector<std::string> notes;
  DatasetOptions dopts;
  dopts.imu_model = a.imu_model;
  dopts.imu_seed = a.seed;
  if (!camera_file.empty()) dopts.camera = ReadCameraFile(camera_file);
  dopts.timeshift_cam_imu_s = timeshift_s;
  source = MakeDiskSource(LoadDatasetOrPosePair(path, dopts));

  if (o.motion_source == MotionSource::kImu && source.dataset.imu.empty()) {
    notes.push_back(
        "the dataset has no IMU data: using the ground-truth motion (--motion-source gt)");
    o.motion_source = MotionSource::kGroundTruth;
  }
  PairSelection sel;
  sel.interval_s = interval_s;
  sel.step = step;
  sel.max_pairs = max_pairs;
  const std::vector<FramePair> pairs = SelectFramePairs(source.dataset.frames, sel);
  if (pairs.empty()) {
    throw InputError(
        path, "no frame pair to evaluate (" + WhyNoFramePairs(source.dataset.frames, sel) + ")");
  }
  std::cerr << "imumatch eval: " << source.dataset.name << " (" << ToString(source.dataset.kind)
            << ", " << source.dataset.frames.size() << " frames, " << pairs.size()
            << " pairs); IMU: " << source.dataset.imu_source_note << "\n";
  o.progress = MakeProgress(a.progress, pairs.size(), "eval");
  EvaluationResult result = EvaluateSource(source, pairs, o);
  for (auto& n : notes) result.notes.push_back(n);
  ReportContext context;
  context.title = "imumatch eval: " + source.dataset.name;
  context.threshold = ChooseThreshold(result, source.exact_ground_truth, threshold);
  if (a.e2e_frames > 0) {
    EndToEndOptions e;
    e.max_frames = static_cast<size_t>(a.e2e_frames);
    e.first_frame = pairs.front().a;
    try {
      context.end_to_end = MeasureEndToEnd(source, o, e);
    } catch (const InputError& err) {
      // The per-pair evaluation already listed the unreadable frame as skipped; the timing stream
      // needs every frame, so it is left out with the reason.
      result.notes.push_back(std::string("end-to-end timing not measured: ") + err.what());
    }
  }
  context.config.push_back({"dataset", path});
  context.config.push_back({"camera", source.dataset.camera.ToString()});
  context.config.push_back({"pairs", interval_s > 0
                                         ? "interval " + std::to_string(interval_s) + " s"
                                         : "step " + std::to_string(step) + " frame(s)"});
  Finish(result, context, a, o);
  if (result.records.empty()) {
    throw InputError(
        path, "no frame pair could be evaluated (" + std::to_string(result.skipped.size()) +
                  " skipped; first: " +
                  (result.skipped.empty() ? std::string("none") : result.skipped.front().reason) +
                  ")");
  }
}

void RunDemo(CommonArgs a, int intermediate, const std::string& motions, const std::string& gains) {
  const auto t0 = std::chrono::steady_clock::now();
  EvaluationOptions o = MakeOptions(a);
  PrepareOut(a);
  const std::optional<double> threshold =
      a.threshold > 0.0 ? std::optional<double>(a.threshold) : std::nullopt;
  SeedCaseOptions so;
  so.motions = SplitList(motions);
  so.intermediate_frames = intermediate;
  std::vector<double> gain_values;
  for (const std::string& g : SplitList(gains)) {
    char* end = nullptr;
    const double v = std::strtod(g.c_str(), &end);
    IMUMATCH_REQUIRE(end != g.c_str() && *end == '\0' && std::isfinite(v) && v > 0.0 && v <= 100.0,
                     "--gains: '" << g << "' is not a gain in (0, 100]");
    gain_values.push_back(v);
  }
  so.imu_model = a.imu_model;
  so.seed = a.seed;
  std::cerr << "imumatch demo: rendering the seed cases (" << motions << "; " << intermediate
            << " intermediate frames) ...\n";
  const std::vector<SeedCase> cases = MakeSeedCases(so);
  const double render_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Exposure changes: the consecutive frames of the first motion again, frame B of every pair
  // multiplied by each gain.
  const SeedCase* gain_case = nullptr;
  for (const SeedCase& c : cases) {
    if (gain_case == nullptr || c.name == so.motions.front() + "-steps") gain_case = &c;
  }
  size_t total = 0;
  for (const auto& c : cases) total += c.pairs.size();
  if (gain_case != nullptr) total += gain_values.size() * gain_case->pairs.size();
  EvaluationResult result;
  size_t done_before = 0;
  auto bar = MakeProgress(a.progress, total, "demo");
  for (const SeedCase& c : cases) {
    if (bar) o.progress = [&](size_t d, size_t) { bar(done_before + d, total); };
    result.Append(EvaluateSource(c.source, c.pairs, o, c.name));
    done_before += c.pairs.size();
  }
  for (double g : gain_values) {
    if (gain_case == nullptr) break;
    if (bar) o.progress = [&](size_t d, size_t) { bar(done_before + d, total); };
    EvaluationOptions og = o;
    og.gain_b = g;
    std::ostringstream name;
    name << gain_case->name << "-gain" << g;
    result.Append(EvaluateSource(gain_case->source, gain_case->pairs, og, name.str()));
    done_before += gain_case->pairs.size();
  }
  ReportContext context;
  context.title = "imumatch demo: IMU-guided vs brute-force matching on the synthetic seed cases";
  context.threshold = ChooseThreshold(result, true, threshold);
  if (a.e2e_frames > 0 && !cases.empty()) {
    // A stream of the first motion with --e2e-frames frames over its 2 s (the cases hold only
    // the intermediate frames and the two ends): the overlapped schedule takes three frames to
    // fill, which the cases' 5 frames do not amortise (throughput x2.38 over them against x2.70
    // over 31 frames in the same hour); best of 3 passes, as the machine is shared.
    SeedCaseOptions stream_options = so;
    stream_options.motions = {so.motions.front()};
    stream_options.intermediate_frames = std::max(0, a.e2e_frames - 2);
    const std::vector<SeedCase> stream = MakeSeedCases(stream_options);
    EndToEndOptions e;
    e.max_frames = static_cast<size_t>(a.e2e_frames);
    e.repetitions = 3;
    context.end_to_end = MeasureEndToEnd(stream.front().source, o, e);
  }
  std::ostringstream r;
  r << std::fixed << std::setprecision(1) << render_s;
  context.config.push_back(
      {"cases",
       "seed pairs at the start and end of each 2 s motion" +
           std::string(intermediate > 0 ? ", plus <motion>-steps (consecutive frames)" : "") +
           (gain_values.empty() || gain_case == nullptr
                ? std::string()
                : ", plus " + gain_case->name +
                      "-gain<g> (frame B of every pair times the gain g)")});
  context.config.push_back({"rendering", r.str() + " s (640x480, synthetic room, exact depth)"});
  Finish(result, context, a, o);
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "Demo finished in " << std::fixed << std::setprecision(1) << total_s << " s.\n";
}

}  // namespace

int ApplyThreads(int threads) {
  IMUMATCH_REQUIRE(threads >= 0 && threads <= 1024,
                   "--threads must be in [0, 1024], got " << threads);
  const int n =
      threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  cv::setNumThreads(n);
  return n;
}

// A one-line progress bar on stderr.
std::function<void(size_t, size_t)> MakeProgress(bool forced, size_t total,
                                                 const std::string& label,
                                                 const std::string& unit) {
  if (!(forced || (isatty(fileno(stderr)) && total >= 10))) return nullptr;
  const auto start = std::chrono::steady_clock::now();
  return [start, label, unit](size_t done, size_t n) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int width = 30;
    const int filled = n > 0 ? static_cast<int>(width * done / n) : width;
    const double eta = done > 0 ? elapsed / done * (n - done) : 0.0;
    std::fprintf(stderr, "\r%s [%s%s] %zu/%zu %s, %.0f s, eta %.0f s ", label.c_str(),
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), done,
                 n, unit.c_str(), elapsed, eta);
    if (done == n) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  };
}

void AddEvalCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "eval",
      "Compare IMU-guided and brute-force matching per detector on a dataset, judged by "
      "its ground truth (TUM RGB-D, EuRoC, synthetic folder or a two-frame pose pair)");
  struct Args {
    std::string path;
    std::string camera;
    std::optional<double> timeshift;
    CommonArgs common;
    double interval = 0.0;
    int step = 1;
    size_t max_pairs = 0;
  };
  auto args = std::make_shared<Args>();
  args->common.out = "imumatch-eval-out";
  args->common.images = 2;
  cmd->add_option("DATASET", args->path, "dataset folder")->required();
  cmd->add_option("--out", args->common.out, "output folder")->capture_default_str();
  auto* interval = cmd->add_option("--interval", args->interval,
                                   "pair frames this many seconds apart (e.g. 2 as in the seed)")
                       ->check(NonNegativeFinite());
  cmd->add_option("--step", args->step, "pair frame i with frame i+N")
      ->capture_default_str()
      ->check(CLI::PositiveNumber)
      ->excludes(interval);
  cmd->add_option("--max-pairs", args->max_pairs, "stop after N pairs (0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--camera", args->camera, kCameraOptionHelp);
  cmd->add_option("--timeshift-cam-imu", args->timeshift, kTimeshiftOptionHelp)
      ->check(NumberIn(-1.0, false, 1.0, false));
  AddCommonOptions(cmd, args->common);
  cmd->callback([args] {
    RunEval(args->path, args->camera, args->timeshift, args->common, args->interval, args->step,
            args->max_pairs);
  });
}

void AddDemoCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "demo",
      "Render the seed paper's synthetic cases (front1m, back1m, left30, right30) plus an "
      "in-plane roll and an exposure change in memory, and compare IMU-guided matching, "
      "brute force and KLT tracking (unseeded, IMU-seeded, hybrid) for every detector");
  struct Args {
    CommonArgs common;
    int intermediate = 3;
    std::string motions = "front1m,back1m,left30,right30,roll45";
    std::string gains = "0.6";
  };
  auto args = std::make_shared<Args>();
  args->common.out = "imumatch-demo-out";
  args->common.methods = "bf,guided,fixed10,klt0,klt,hybrid";
  cmd->add_option("--out", args->common.out, "output folder")->capture_default_str();
  cmd->add_option("--intermediate", args->intermediate,
                  "frames rendered between the start and end of each motion (0 = seed pair only)")
      ->capture_default_str();
  AddCommonOptions(cmd, args->common);
  cmd->add_option("--motions", args->motions,
                  "synthetic motions: front1m, back1m, left30, right30, roll45 (45 deg/s about "
                  "the optical axis), shake, fast_rotation, walk")
      ->capture_default_str();
  cmd->add_option("--gains", args->gains,
                  "exposure gains applied to frame B of the first motion's consecutive pairs, "
                  "one extra case each (empty: none)")
      ->capture_default_str();
  cmd->callback([args] { RunDemo(args->common, args->intermediate, args->motions, args->gains); });
}

}  // namespace imumatch::apps
