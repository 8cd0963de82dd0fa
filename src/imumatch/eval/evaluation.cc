#include "imumatch/eval/evaluation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <iomanip>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/statistics.h"
#include "imumatch/core/time.h"
#include "imumatch/imu/time_offset.h"
#include "imumatch/io/image_io.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/field_of_view.h"
#include "imumatch/matching/klt_tracker.h"
#include "imumatch/matching/scene_depth.h"

#include "imumatch/eval/method_run.h"
#include "imumatch/eval/pair_motion.h"
#include "imumatch/eval/pipelined.h"
#include "imumatch/frontend/rotation_from_fit.h"

namespace imumatch {
namespace {

using Clock = SteadyClock;

struct PairItem {
  FrameImages a, b;
  double read_ms = 0.0;
  std::string error;
};

// Decodes pairs in order, reusing the previous pair's frame B when it is this pair's frame A.
class PairReader {
 public:
  PairReader(const FrameReader& reader, const std::vector<FramePair>& pairs)
      : reader_(reader), pairs_(pairs) {}
  PairItem operator()(size_t i) {
    PairItem item;
    const FramePair& p = pairs_[i];
    const auto t0 = Clock::now();
    try {
      if (has_last_ && last_index_ == p.a) {
        item.a = last_;
      } else {
        item.a = reader_(p.a, true);
      }
      item.b = reader_(p.b, true);
      last_ = item.b;
      last_index_ = p.b;
      has_last_ = true;
    } catch (const Error& e) {
      item.error = std::string("cannot read frame: ") + e.what();
      has_last_ = false;
    } catch (const cv::Exception& e) {
      item.error = std::string("cannot decode frame: ") + e.what();
      has_last_ = false;
    }
    item.read_ms = MsSince(t0);
    return item;
  }

 private:
  const FrameReader& reader_;
  const std::vector<FramePair>& pairs_;
  FrameImages last_;
  size_t last_index_ = 0;
  bool has_last_ = false;
};

}  // namespace

const char* ToString(SecondPassOutcome outcome) {
  switch (outcome) {
    case SecondPassOutcome::kNotTried:
      return "not_tried";
    case SecondPassOutcome::kRan:
      return "ran";
    case SecondPassOutcome::kNoFit:
      return "no_fit";
    case SecondPassOutcome::kFitDisagreed:
      return "fit_disagreed";
    case SecondPassOutcome::kNotTighter:
      return "not_tighter";
  }
  return "?";
}

std::vector<std::string> CheckInputsLookRight(const std::vector<DetectorPairRecord>& records,
                                              bool recorded_imu) {
  std::vector<std::string> warnings;
  int pairs_with_depth = 0, keypoints_with_depth = 0;
  std::vector<float> residuals;
  std::vector<double> rotation_errors;
  for (const DetectorPairRecord& r : records) {
    if (r.has_depth) {
      ++pairs_with_depth;
      keypoints_with_depth += r.keypoints_a_with_depth;
    }
    rotation_errors.push_back(r.motion_rotation_error_deg);
    if (r.bf_run < 0) continue;
    for (const MatchResidual& m : r.runs[static_cast<size_t>(r.bf_run)].residuals) {
      if (m.kind != ResidualKind::kUnjudgeable) residuals.push_back(m.residual_px);
    }
  }
  // Medians in place (the vectors are local copies); -1 when empty.
  auto median = [](auto& v) {
    return v.empty() ? -1.0 : static_cast<double>(UpperMedianInPlace(v));
  };
  const double median_residual = residuals.size() >= 20 ? median(residuals) : -1.0;
  const double median_rotation_error = median(rotation_errors);
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(2);
  if (pairs_with_depth > 0 && keypoints_with_depth == 0) {
    msg << "the depth images of " << pairs_with_depth
        << " pair(s) hold no valid depth at any keypoint (all zero?): every match was predicted "
           "and judged without depth";
    warnings.push_back(msg.str());
    msg.str("");
  }
  // Brute-force matches are mostly right (their precision is 0.9+ on every dataset measured), so
  // the ground truth places most of them within the keypoints' localisation noise (~1 px; TUM's
  // motion-capture ground truth: 2 px). A median far beyond is a ground truth that does not
  // describe these images.
  if (median_residual > kMaxPlausibleMedianResidualPx) {
    msg << "the ground truth disagrees with the images: brute-force matches lie a median "
        << median_residual << " px from where it puts them (expected about 1-2 px); "
        << "timestamps shifted, another camera, or a quaternion in another order?";
    warnings.push_back(msg.str());
    msg.str("");
  }
  // A recorded IMU integrates between frames to within a few thousandths of a degree of the
  // ground truth (EuRoC MH_05: median 0.005 deg); half a degree per frame interval is a ground
  // truth or an IMU log that do not belong together.
  if (recorded_imu && median_rotation_error > kMaxPlausibleImuRotationErrorDeg) {
    msg << "the IMU disagrees with the ground truth: the rotation it integrates between frames is "
           "a median "
        << median_rotation_error << " deg off (expected < 0.05 deg); time offset, another "
        << "IMU, or the ground truth in another frame?";
    warnings.push_back(msg.str());
  }
  return warnings;
}

// ---------------------------------------------------------------------------------------------

void EvaluationResult::Append(EvaluationResult other) {
  for (auto& r : other.records) records.push_back(std::move(r));
  for (auto& s : other.skipped) skipped.push_back(std::move(s));
  for (auto& v : other.visuals) visuals.push_back(std::move(v));
  for (auto& n : other.notes) notes.push_back(std::move(n));
  for (auto& w : other.warnings) warnings.push_back(std::move(w));
  for (auto& t : other.time_offsets) time_offsets.push_back(std::move(t));
  pairs_total += other.pairs_total;
  wall_s += other.wall_s;
}

EvaluationResult EvaluateSource(const EvalSource& source, const std::vector<FramePair>& pairs,
                                const EvaluationOptions& options, const std::string& case_name) {
  options.Check();
  IMUMATCH_CHECK(static_cast<bool>(source.reader), "the source has no frame reader");
  const Dataset& dataset = source.dataset;
  const std::string name = case_name.empty() ? dataset.name : case_name;
  EvaluationResult result;
  result.pairs_total = pairs.size();
  for (const FramePair& p : pairs) {
    IMUMATCH_CHECK(p.a < dataset.frames.size() && p.b < dataset.frames.size(),
                   "frame pair outside the dataset");
  }
  const size_t frames_with_depth = static_cast<size_t>(
      std::count_if(dataset.frames.begin(), dataset.frames.end(),
                    [](const FrameRecord& f) { return !f.depth_path.empty(); }));
  // An epipolar distance cannot see an error along the line: a false partner near the line
  // passes (on EuRoC MH_05's depth frames, 44-79 % of the matches depth calls false), more often
  // for guided matching, whose search region follows the line.
  const std::string epipolar_caveat =
      " (blind to errors along the line: precision there is an upper bound, guided matching's "
      "more so)";
  if (frames_with_depth == 0) {
    result.notes.push_back(name +
                           ": no depth images: predictions use epipolar segments and "
                           "matches are judged by epipolar distance only" +
                           epipolar_caveat);
  } else if (frames_with_depth < dataset.frames.size()) {
    result.notes.push_back(name + ": " + std::to_string(frames_with_depth) + " of " +
                           std::to_string(dataset.frames.size()) +
                           " frames have a depth image; pairs whose frame A has none are "
                           "predicted along epipolar segments and judged by epipolar distance" +
                           epipolar_caveat);
  }
  if (options.monocular && frames_with_depth > 0) {
    result.notes.push_back(name +
                           ": monocular: every keypoint is predicted along its epipolar segment; "
                           "the depth images only judge the matches");
  }
  ImuBiasEstimate bias;
  if (options.motion_source == MotionSource::kImu) {
    bias = EstimateImuBias(dataset, options.still_init_s);
    if (!bias.note.empty()) result.notes.push_back(name + ": " + bias.note);
  }
  // One gyro bias filter per detector (each detector a front end of its own), on a recorded IMU.
  const bool learn_bias = options.motion_source == MotionSource::kImu && !dataset.imu.empty() &&
                          !dataset.imu_simulated && options.gyro_bias_from_matches;
  std::vector<std::optional<GyroBiasFilter>> bias_filters(options.detectors.size());
  // The fit's rotation measurement is a second solve: only when a filter or the estimate of the
  // offset between the camera's and the IMU's clocks reads it (a recorded IMU).
  const bool measure_offset = !dataset.imu.empty() && !dataset.imu_simulated;
  std::vector<std::vector<RotationObservation>> fitted_rotations(options.detectors.size());
  EvaluationOptions run_options = options;
  run_options.refit.measure_rotation = learn_bias || measure_offset;
  const PixelUndistorter undistorter(dataset.camera);
  const cv::Mat field_mask = FieldOfViewMask(dataset.camera);  // empty but for a wide fisheye
  const auto wall0 = Clock::now();
  std::vector<CachedFeatures> cache;  // features of the previous pair's frame B

  PairReader pair_reader(source.reader, pairs);
  size_t done = 0;
  auto process = [&](PairItem item) {
    const size_t index = done++;
    const FramePair& pair = pairs[index];
    auto skip = [&](const std::string& detector, const std::string& reason) {
      result.skipped.push_back({name, index, pair.a, pair.b, detector, reason});
    };
    auto report_progress = [&] {
      if (options.progress) options.progress(done, pairs.size());
    };
    const FrameRecord& fa = dataset.frames[pair.a];
    const FrameRecord& fb = dataset.frames[pair.b];
    if (!item.error.empty()) {
      skip("", item.error);
      cache.clear();
      return report_progress();
    }
    if (!fa.world_from_cam || !fb.world_from_cam) {
      skip("",
           "no ground-truth pose for frame " + std::to_string(fa.world_from_cam ? pair.b : pair.a));
      return report_progress();
    }
    std::string reason;
    const std::optional<PairMotion> motion =
        ComputePairMotion(dataset, pair, index, options, bias, reason);
    if (!motion) {
      skip("", reason);
      return report_progress();
    }
    const CameraMotion gt =
        CameraMotionFromPoses(fa.t_ns, *fa.world_from_cam, fb.t_ns, *fb.world_from_cam);

    if (options.gain_b != 1.0) {
      // A new buffer: the reader keeps the ungained frame B as the next pair's frame A.
      cv::Mat gained;
      item.b.image.convertTo(gained, -1, options.gain_b);
      item.b.image = gained;
    }
    std::vector<CachedFeatures> next_cache;
    for (size_t detector = 0; detector < options.detectors.size(); ++detector) {
      const DetectorKind kind = options.detectors[detector];
      FeatureOptions fopts = options.features;
      fopts.kind = kind;
      auto extract = [&](size_t frame, const cv::Mat& image) {
        for (CachedFeatures& c : cache) {
          if (c.frame == frame && c.kind == kind) return c;
        }
        CachedFeatures c;
        c.frame = frame;
        c.kind = kind;
        const auto t0 = Clock::now();
        c.features = ExtractFeatures(image, fopts, field_mask);
        c.features.descriptors = PadBinaryDescriptors(c.features.descriptors);
        c.ms = MsSince(t0);
        const auto t1 = Clock::now();
        ToIdealKeypointInfos(c.features.keypoints, undistorter, &c.ideal);
        c.ideal_ms = MsSince(t1);
        return c;
      };
      const CachedFeatures ca = extract(pair.a, item.a.image);
      const CachedFeatures cb = extract(pair.b, item.b.image);
      next_cache.push_back(cb);
      const Features& feat_a = ca.features;  // image pixels (the judge's and the images')
      const Features& feat_b = cb.features;
      const int na = static_cast<int>(feat_a.keypoints.size());
      const int nb = static_cast<int>(feat_b.keypoints.size());
      if (na < 2 || nb < 2) {
        skip(ToString(kind),
             "too few features (A: " + std::to_string(na) + ", B: " + std::to_string(nb) + ")");
        continue;
      }
      const PairGroundTruth judge(dataset.camera, gt.cam_b_from_cam_a, item.a.depth,
                                  feat_a.keypoints, feat_b.keypoints, options.ground_truth);
      DetectorPairRecord rec;
      rec.case_name = name;
      rec.pair_index = index;
      rec.frame_a = pair.a;
      rec.frame_b = pair.b;
      rec.t_a_ns = fa.t_ns;
      rec.t_b_ns = fb.t_ns;
      rec.detector = kind;
      rec.keypoints_a = na;
      rec.keypoints_b = nb;
      rec.keypoints_a_with_depth = judge.num_with_depth();
      rec.read_ms = item.read_ms;
      rec.extract_ms = ca.ms + cb.ms;
      // The detector's own bias: the IMU's motion with it removed and its sigma.
      std::optional<PairMotion> own_motion;
      std::optional<GyroBiasFilter>& bias_filter = bias_filters[detector];
      if (learn_bias) {
        if (!bias_filter) {
          bias_filter.emplace(bias.from_still_start ? bias.bias.gyro : Eigen::Vector3d::Zero(),
                              bias.from_still_start ? bias.gyro_bias_sigma
                                                    : options.gyro_bias_filter.unknown_bias_sigma,
                              dataset.imu_params.gyro_random_walk,
                              bias.from_still_start ? bias.t_ns : fa.t_ns,
                              options.gyro_bias_filter);
        }
        ImuBiasEstimate learnt;
        learnt.bias.gyro = bias_filter->bias();
        learnt.estimated = true;
        learnt.gyro_bias_sigma = bias_filter->SigmaAt(fa.t_ns);
        learnt.t_ns = fa.t_ns;
        std::string why;
        own_motion = ComputePairMotion(dataset, pair, index, options, learnt, why);
      }
      const PairMotion& pair_motion = own_motion ? *own_motion : *motion;
      rec.motion_ms = pair_motion.ms;
      rec.motion_rotation_error_deg = RotationDistance(pair_motion.motion.cam_b_from_cam_a.rotation,
                                                       gt.cam_b_from_cam_a.rotation) *
                                      180.0 / M_PI;
      rec.motion_translation_error_m =
          (pair_motion.motion.cam_b_from_cam_a.translation - gt.cam_b_from_cam_a.translation)
              .norm();
      rec.candidates = judge.candidates();
      PairVisual visual;
      const bool keep_visual = static_cast<int>(index) < options.keep_visuals;
      if (keep_visual) {
        visual.case_name = name;
        visual.pair_index = index;
        visual.detector = kind;
        visual.image_a = item.a.image;
        visual.image_b = item.b.image;
        visual.keypoints_a = feat_a.keypoints;
        visual.keypoints_b = feat_b.keypoints;
        visual.camera = dataset.camera;
      }
      rec.has_depth = !item.a.depth.empty();
      std::vector<Match> matches;
      std::vector<KeypointPrediction> predictions;
      std::vector<Match> bf_matches;  // of the first brute-force run, for the window recall
      std::vector<std::vector<KeypointPrediction>> run_predictions(options.methods.size());
      std::vector<std::vector<Match>> run_matches(options.methods.size());
      for (size_t m = 0; m < options.methods.size(); ++m) {
        const MatchMethod method = options.methods[m];
        MethodRun run = RunMethod(method, undistorter, pair_motion.motion, ca, cb, item.a, item.b,
                                  run_options, matches, predictions);
        if (bias_filter && method == MatchMethod::kGuided) {
          // The rotation the fitted motion's matches measure updates the detector's bias.
          UpdateGyroBiasFromFit(run.refit, dataset.cam_from_imu, dataset.imu, dataset.imu_params,
                                fa.t_ns, fb.t_ns, &*bias_filter);
        }
        if (measure_offset && method == MatchMethod::kGuided) {
          if (std::optional<RotationObservation> observed =
                  RotationObservationFromFit(run.refit, dataset.cam_from_imu, fa.t_ns, fb.t_ns)) {
            fitted_rotations[detector].push_back(*observed);
          }
        }
        run.residuals = judge.Judge(matches);
        if (run.refit.ok) {
          const Rigid3d& fitted = run.refit.motion.cam_b_from_cam_a;
          run.refit_rotation_error_deg =
              RotationDistance(fitted.rotation, gt.cam_b_from_cam_a.rotation) * 180.0 / M_PI;
          run.refit_translation_error_m =
              (fitted.translation - gt.cam_b_from_cam_a.translation).norm();
          run.refit_truth_mahalanobis2 = SquaredMahalanobis(run.refit.motion, gt.cam_b_from_cam_a);
        }
        if (IsBruteForce(method) && rec.bf_run < 0) {
          rec.bf_run = static_cast<int>(m);
          bf_matches = matches;
        }
        if (keep_visual) {
          visual.runs.push_back({method, matches, run.residuals, predictions});
        }
        run_predictions[m] = std::move(predictions);
        if (UsesPrediction(method) && !IsTracking(method)) run_matches[m] = matches;
        rec.runs.push_back(std::move(run));
      }
      if (rec.bf_run >= 0) {
        for (size_t m = 0; m < options.methods.size(); ++m) {
          if (UsesPrediction(options.methods[m]) && !IsTracking(options.methods[m])) {
            CompareWithBruteForce(bf_matches, run_predictions[m], cb.ideal, run_matches[m],
                                  rec.runs[m]);
          }
        }
      }
      result.records.push_back(std::move(rec));
      if (keep_visual) result.visuals.push_back(std::move(visual));
    }
    // Features of a gained frame B are not those of the next pair's (ungained) frame A.
    if (options.gain_b == 1.0) {
      cache = std::move(next_cache);
    } else {
      cache.clear();
    }
    report_progress();
  };
  RunPipelined<PairItem>(
      pairs.size(), options.queue_capacity, [&](size_t i) { return pair_reader(i); }, process);
  result.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  for (size_t d = 0; d < bias_filters.size(); ++d) {
    if (!bias_filters[d]) continue;
    const GyroBiasFilter& f = *bias_filters[d];
    std::ostringstream note;
    note << name << ": " << ToString(options.detectors[d])
         << ": gyro bias learnt from the guided pairs' fitted rotations: "
         << f.Summary(dataset.frames[pairs.back().b].t_ns);
    result.notes.push_back(note.str());
  }
  if (measure_offset) {
    for (size_t d = 0; d < fitted_rotations.size(); ++d) {
      if (fitted_rotations[d].empty()) continue;
      const Eigen::Vector3d gyro_bias = bias_filters[d]         ? bias_filters[d]->bias()
                                        : bias.from_still_start ? bias.bias.gyro
                                                                : Eigen::Vector3d::Zero();
      const TimeOffsetEstimate offset =
          TryEstimateTimeOffset(dataset.imu, dataset.imu_params, gyro_bias, fitted_rotations[d]);
      result.time_offsets.push_back({name, options.detectors[d], offset});
      const std::string detector = ToString(options.detectors[d]);
      result.notes.push_back(name + ": " + detector +
                             ": camera-IMU time offset measured from the guided pairs' fitted "
                             "rotations (t_imu = t_cam + offset): " +
                             offset.Summary());
      const std::string advice = TimeOffsetAdvice(offset, dataset.timeshift_cam_imu_s);
      if (!advice.empty()) result.warnings.push_back(name + ": " + detector + ": " + advice);
    }
  }
  for (const std::string& w : dataset.warnings) result.warnings.push_back(name + ": " + w);
  for (std::string& w : CheckInputsLookRight(
           result.records, !dataset.imu_simulated && options.motion_source == MotionSource::kImu)) {
    result.warnings.push_back(name + ": " + w);
  }
  return result;
}

}  // namespace imumatch
