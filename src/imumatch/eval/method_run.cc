#include "imumatch/eval/method_run.h"

#include <chrono>
#include <utility>

#include "imumatch/core/time.h"
#include "imumatch/frontend/motion_refit.h"
#include "imumatch/frontend/second_pass.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/grid_index.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/klt_tracker.h"
#include "imumatch/matching/neighbour_depth.h"
#include "imumatch/matching/patch_matching.h"
#include "imumatch/matching/scene_depth.h"
#include "imumatch/matching/subpixel_refinement.h"

namespace imumatch {
namespace {

using Clock = SteadyClock;

// The mean half size (px) of the predictions' search windows: the capsule's radius without depth,
// the mean of the box's half width and height with it; 0 when none has a window.
double MeanWindowHalfSize(const std::vector<KeypointPrediction>& predictions) {
  double sum = 0.0;
  int n = 0;
  for (const KeypointPrediction& p : predictions) {
    if (!p.HasWindow()) continue;
    sum += p.status == PredictionStatus::kWithoutDepth
               ? static_cast<double>(p.radius)
               : 0.25 * static_cast<double>(p.max_x - p.min_x + p.max_y - p.min_y);
    ++n;
  }
  return n > 0 ? sum / n : 0.0;
}

}  // namespace

// Runs one method on one detector's features.
MethodRun RunMethod(MatchMethod method, const PixelUndistorter& undistorter,
                    const CameraMotion& motion, const CachedFeatures& ca, const CachedFeatures& cb,
                    const FrameImages& image_a, const FrameImages& image_b,
                    const EvaluationOptions& options, std::vector<Match>& matches,
                    std::vector<KeypointPrediction>& predictions) {
  const Features& fa = ca.features;
  const Features& fb = cb.features;
  const PinholeCamera& camera = undistorter.camera();
  MethodRun run;
  run.method = method;
  predictions.clear();
  if (method == MatchMethod::kKltUnseeded) {
    const auto t0 = Clock::now();
    TrackResult tracks =
        TrackOpenCvLk(image_a.image, image_b.image, fa.keypoints, options.klt_unseeded);
    run.match_ms = MsSince(t0);
    run.track_stats = tracks.stats;
    run.from_tracks = static_cast<int>(tracks.tracks.size());
    matches = std::move(tracks.tracks);
    return run;
  }
  if (IsBruteForce(method)) {
    const auto t0 = Clock::now();
    if (method == MatchMethod::kBruteForce) {
      matches = MatchOpenCvKnnRatio(fa.descriptors, fb.descriptors, options.ratio);
    } else {
      BruteForceOptions bf;
      bf.ratio = options.ratio;
      matches = MatchBruteForce(fa.descriptors, fb.descriptors, bf);
    }
    run.match_ms = MsSince(t0);
    return run;
  }
  PredictionOptions popts = options.prediction;
  if (method == MatchMethod::kFixedWindow) {
    // The paper's window: a fixed square, and fixed segments (the scene's near end is ours).
    popts.window_mode = WindowMode::kFixed;
    popts.scene_near.enabled = false;
  }
  // Mapping a frame's keypoints to ideal pixels is done once per frame; a stream pays it once per
  // pair (frame B's), so that is what the prediction stage is charged.
  auto t0 = Clock::now();
  const cv::Mat& depth_a = image_a.depth;
  std::vector<float> depths;  // empty: predicted without depth
  if (!depth_a.empty() && !options.monocular) {
    depths = SampleDepths(depth_a, camera.depth_scale, fa.keypoints, popts.depth_sampling);
  }
  const KeypointPredictor predictor(undistorter, motion, popts);
  // The grid over B serves the scene's near depth (its pilot matching) and the search.
  GridIndex grid_b;
  grid_b.Build(cb.ideal, camera.width, camera.height,
               static_cast<float>(options.guided.grid_cell_size));
  // B in the grid's order, prepared once for the pilot and every pass.
  GuidedCandidates candidates_b;
  PrepareGuidedCandidates(cb.ideal, grid_b, DescriptorView::FromMat(fb.descriptors), &candidates_b);
  GuidedSearchScratch scratch;
  run.scene_near =
      PredictKeypointsInScene(predictor, ca.ideal, depths, DescriptorView::FromMat(fa.descriptors),
                              cb.ideal, candidates_b, options.guided, &predictions, &scratch);
  run.predict_ms = MsSince(t0) + cb.ideal_ms;
  if (IsTracking(method)) {
    // Frame A's pyramid would be frame B's of the previous pair in a stream: not charged.
    const TrackingPyramid pyr_a = TrackingPyramid::Build(image_a.image, options.klt.max_level);
    t0 = Clock::now();
    const TrackingPyramid pyr_b = TrackingPyramid::Build(image_b.image, options.klt.max_level);
    TrackResult tracks =
        TrackSeeded(pyr_a, pyr_b, fa.keypoints, predictions, undistorter, options.klt);
    run.match_ms = MsSince(t0);
    run.track_stats = tracks.stats;
    run.from_tracks = static_cast<int>(tracks.tracks.size());
    matches = std::move(tracks.tracks);
    if (method == MatchMethod::kKlt) return run;
    // Hybrid: guided matching for the keypoints whose track failed, inside the same windows.
    t0 = Clock::now();
    MatchResult result = MatchGuided(PredictionsOfFailedTracks(predictions, tracks), ca.ideal,
                                     DescriptorView::FromMat(fa.descriptors), candidates_b,
                                     options.guided, &scratch);
    if (options.refine_subpixel) {
      run.refine_stats = RefineMatches(image_a.image, image_b.image, fa.keypoints, fb.keypoints,
                                       predictions, camera, options.subpixel, result.matches);
    }
    run.match_ms += MsSince(t0);
    run.stats = result.stats;
    run.from_descriptors = static_cast<int>(result.matches.size());
    matches.insert(matches.end(), result.matches.begin(), result.matches.end());
    return run;
  }
  t0 = Clock::now();
  MatchResult result = MatchGuided(predictions, ca.ideal, DescriptorView::FromMat(fa.descriptors),
                                   candidates_b, options.guided, &scratch);
  run.match_ms = MsSince(t0);
  std::vector<float> fit_depths;  // the fit takes no depth read near an edge of the depth image
  if (options.second_pass && method == MatchMethod::kGuided) {
    // Second pass: the motion fitted to the first pass's matches, windows from its covariance,
    // when they search less than the first pass's. The fit and the new predictions are charged to
    // the prediction stage, the search to matching.
    run.first_window_px = MeanWindowHalfSize(predictions);
    t0 = Clock::now();
    // The fit takes no depth read near an edge of the depth image; the predictions keep them.
    // The rotation the matches alone show is measured from the final matches (below).
    fit_depths = FitDepths(depth_a, camera.depth_scale, fa.keypoints, depths, options.refit);
    MotionRefitOptions refit_options = options.refit;
    refit_options.measure_rotation = false;
    run.refit = RefitMotion(motion, result.matches, fa.keypoints, fb.keypoints, fit_depths, popts,
                            undistorter, refit_options);
    run.second_pass = run.refit.ok          ? SecondPassOutcome::kRan
                      : run.refit.disagrees ? SecondPassOutcome::kFitDisagreed
                                            : SecondPassOutcome::kNoFit;
    std::vector<KeypointPrediction> second;
    if (run.refit.ok) {
      const KeypointPredictor fitted =
          SecondPassPredictor(undistorter, run.refit, popts, run.scene_near);
      run.narrowed_segments = PredictKeypointsNearMatches(
          fitted, ca.ideal, depths, result.matches, cb.ideal, options.neighbour_depth, &second);
      if (!(SearchArea(second) < SearchArea(predictions))) {
        run.second_pass = SecondPassOutcome::kNotTighter;
      }
    }
    run.refit_ms = MsSince(t0);
    run.predict_ms += run.refit_ms;
    if (run.second_pass == SecondPassOutcome::kRan) {
      predictions.swap(second);
      t0 = Clock::now();
      result = MatchGuided(predictions, ca.ideal, DescriptorView::FromMat(fa.descriptors),
                           candidates_b, options.guided, &scratch);
      run.match_ms += MsSince(t0);
    }
  }
  std::vector<uint8_t> patch_query;  // by query of A: matched by the patch
  if (method == MatchMethod::kGuided && options.patch_second_look) {
    t0 = Clock::now();
    std::vector<QueryOutcome> before = result.outcomes;
    run.patch =
        MatchByPatch(predictions, ca.ideal, fa.keypoints, DescriptorView::FromMat(fa.descriptors),
                     cb.ideal, grid_b, fb.keypoints, DescriptorView::FromMat(fb.descriptors),
                     image_a.image, image_b.image, camera, options.guided, options.patch, &result);
    run.patch_ms = MsSince(t0);
    run.match_ms += run.patch_ms;
    patch_query.assign(before.size(), 0);
    for (size_t i = 0; i < before.size(); ++i) {
      patch_query[i] =
          before[i] != QueryOutcome::kMatched && result.outcomes[i] == QueryOutcome::kMatched;
    }
  }
  run.window_px = MeanWindowHalfSize(predictions);
  run.stats = result.stats;
  run.outcomes = std::move(result.outcomes);
  matches = std::move(result.matches);
  if (options.refine_subpixel && method == MatchMethod::kGuided) {
    t0 = Clock::now();
    run.refine_stats = RefineMatches(image_a.image, image_b.image, fa.keypoints, fb.keypoints,
                                     predictions, camera, options.subpixel, matches);
    run.refine_ms = MsSince(t0);
  }
  if (options.refit.measure_rotation && run.refit.ok) {
    // The rotation the final matches alone measure, for the gyro bias filter and the time
    // offset: those of the first pass, found in the IMU's windows, lean towards its rotation
    // (MeasureRotationFromMatches). Charged to the fit.
    t0 = Clock::now();
    MeasureRotationFromMatches(motion, matches, fa.keypoints, fb.keypoints, fit_depths, popts,
                               undistorter, options.refit, &run.refit);
    const double ms = MsSince(t0);
    run.refit_ms += ms;
    run.predict_ms += ms;
  }
  if (!patch_query.empty()) {
    run.match_by_patch.resize(matches.size());
    for (size_t j = 0; j < matches.size(); ++j) {
      run.match_by_patch[j] = patch_query[static_cast<size_t>(matches[j].query_idx)];
    }
  }
  return run;
}

// For each match of the brute-force run: does the guided search region of its query contain its
// partner (in ideal pixels), and if not, why; and which match of this run has the same query (and
// back), for the fate of brute force's correct matches (ComputeBruteForceFate).
void CompareWithBruteForce(const std::vector<Match>& bf_matches,
                           const std::vector<KeypointPrediction>& predictions,
                           const std::vector<KeypointInfo>& ideal_b,
                           const std::vector<Match>& run_matches, MethodRun& run) {
  std::vector<int> run_match_of(predictions.size(), -1), bf_match_of(predictions.size(), -1);
  for (size_t j = 0; j < run_matches.size(); ++j) {
    run_match_of[static_cast<size_t>(run_matches[j].query_idx)] = static_cast<int>(j);
  }
  for (size_t k = 0; k < bf_matches.size(); ++k) {
    bf_match_of[static_cast<size_t>(bf_matches[k].query_idx)] = static_cast<int>(k);
  }
  run.bf_query_match.resize(bf_matches.size());
  run.bf_query_outcome.resize(bf_matches.size());
  for (size_t k = 0; k < bf_matches.size(); ++k) {
    const size_t q = static_cast<size_t>(bf_matches[k].query_idx);
    run.bf_query_match[k] = run_match_of[q];
    run.bf_query_outcome[k] = q < run.outcomes.size() ? run.outcomes[q] : QueryOutcome::kMatched;
  }
  run.match_bf_match.resize(run_matches.size());
  for (size_t j = 0; j < run_matches.size(); ++j) {
    run.match_bf_match[j] = bf_match_of[static_cast<size_t>(run_matches[j].query_idx)];
  }
  run.bf_partner_in_window.resize(bf_matches.size());
  run.bf_partner_prediction.resize(bf_matches.size());
  run.bf_partner_beyond_segment.assign(bf_matches.size(), 0);
  for (size_t k = 0; k < bf_matches.size(); ++k) {
    const Match& m = bf_matches[k];
    const KeypointPrediction& p = predictions[static_cast<size_t>(m.query_idx)];
    const KeypointInfo& b = ideal_b[static_cast<size_t>(m.train_idx)];
    run.bf_partner_in_window[k] = p.HasWindow() && p.Contains(b.x, b.y) ? 1 : 0;
    run.bf_partner_prediction[k] = p.status;
    if (!run.bf_partner_in_window[k] && p.status == PredictionStatus::kWithoutDepth) {
      const Eigen::Vector2f d = p.segment_end - p.segment_start;
      const Eigen::Vector2f r = Eigen::Vector2f(b.x, b.y) - p.segment_start;
      const float len2 = d.squaredNorm();
      const float along = len2 > 0.0f ? r.dot(d) / len2 : 0.0f;
      const float lateral2 = len2 > 0.0f ? (r - along * d).squaredNorm() : r.squaredNorm();
      run.bf_partner_beyond_segment[k] =
          (along < 0.0f || along > 1.0f) && lateral2 <= p.radius * p.radius ? 1 : 0;
    }
  }
}

}  // namespace imumatch
