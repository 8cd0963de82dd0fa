// The real flight: the EuRoC MH_05 excerpt in ../shared/data (real ADIS16448 IMU, k1 = -0.28 lens,
// depth for frames 0..35 only) evaluated end to end against its laser-tracker ground truth: window
// recall, guided against brute force with and without depth, the second pass, the patch look,
// take-off and a log without a still start. The shared run's pairs 0-19 have depth, 100-119 none.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/QR>

#include "imumatch/core/time.h"
#include "imumatch/eval/eval_test_util.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/summary.h"
#include "imumatch/io/dataset.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

struct FlightRun {
  EvaluationResult result;
  double threshold_px = 0.0;
};

EvalSource FlightSource() {
  return MakeDiskSource(LoadDataset(testing::DataPath("euroc_mh05_flight"), DatasetOptions()));
}

// ORB and SIFT, brute force and guided, a fixed seed.
EvaluationOptions FlightOptions() {
  EvaluationOptions o;
  o.detectors = {DetectorKind::kOrb, DetectorKind::kSift};
  o.methods = {MatchMethod::kBruteForce, MatchMethod::kGuided};
  o.seed = 42;
  return o;
}

// Consecutive pairs (a, a + 1) for a in [first, end).
std::vector<FramePair> ConsecutivePairs(size_t first, size_t end) {
  std::vector<FramePair> pairs;
  for (size_t a = first; a < end; ++a) pairs.push_back({a, a + 1});
  return pairs;
}

FlightRun RunFlight(MotionSource source, bool refine) {
  EvaluationOptions o = FlightOptions();
  o.motion_source = source;
  o.refine_subpixel = refine;
  std::vector<FramePair> pairs = ConsecutivePairs(0, 20);
  const std::vector<FramePair> flight = ConsecutivePairs(100, 120);
  pairs.insert(pairs.end(), flight.begin(), flight.end());
  FlightRun run;
  run.result = EvaluateSource(FlightSource(), pairs, o);
  run.threshold_px = ChooseThreshold(run.result, false, std::nullopt).threshold_px;
  return run;
}

const FlightRun& FlightImu() {
  static const FlightRun run = RunFlight(MotionSource::kImu, true);
  return run;
}

TEST(EvalFlightTest, DepthImagesAndTheStillStartAreUsed) {
  const FlightRun& run = FlightImu();
  ASSERT_TRUE(run.result.skipped.empty()) << run.result.skipped.front().reason;
  ASSERT_EQ(run.result.records.size(), 80u);  // 40 pairs x 2 detectors
  int with_depth = 0, keypoints_with_depth = 0;
  for (const auto& r : run.result.records) {
    with_depth += r.has_depth;
    EXPECT_EQ(r.has_depth, r.frame_a < 36) << r.frame_a;
    keypoints_with_depth += r.keypoints_a_with_depth;
    if (!r.has_depth) {
      EXPECT_EQ(r.keypoints_a_with_depth, 0);
    }
    // The gyro bias from the still start (about 0.08 rad/s about z) is removed: the IMU's
    // rotation over 50 ms agrees with the ground truth to hundredths of a degree (0.2 deg
    // without it).
    EXPECT_LT(r.motion_rotation_error_deg, 0.03) << r.frame_a;
  }
  EXPECT_EQ(with_depth, 40);
  // depth0 covers 0.5-16 % of the pixels (motion stereo, up to about 20 m in the machine hall).
  EXPECT_GT(keypoints_with_depth, 20 * with_depth);
  bool bias_note = false, epipolar_note = false;
  for (const auto& n : run.result.notes) {
    bias_note |= n.find("gyro bias from the still") != std::string::npos;
    // The pairs without depth are judged by epipolar distance, and the report says what that
    // judge cannot see.
    epipolar_note |= n.find("36 of 200 frames have a depth image") != std::string::npos &&
                     n.find("upper bound") != std::string::npos;
  }
  EXPECT_TRUE(bias_note);
  EXPECT_TRUE(epipolar_note);
}

// A log that does not start still (here: the still start not used, still_init_s = 0) leaves the
// gyro bias, about 0.08 rad/s, in the IMU's rotation: 0.23 deg per pair against the ground truth.
// Learnt from the guided pairs' fitted rotations, in flight and without depth (pairs 100-129), the
// error falls below a third of that within five pairs (to 0.05-0.07 deg: the learnt bias's y
// component stays 0.008 rad/s from the still start's); without the learning it stays.
TEST(EvalFlightVariantTest, WithoutAStillStartTheGyroBiasIsLearntFromTheMatches) {
  const EvalSource src = FlightSource();
  EvaluationOptions o = FlightOptions();
  o.detectors = {DetectorKind::kOrb};
  o.methods = {MatchMethod::kGuided};
  o.still_init_s = 0.0;
  const std::vector<FramePair> pairs = ConsecutivePairs(100, 130);
  for (const bool learn : {true, false}) {
    SCOPED_TRACE(learn ? "learnt" : "not learnt");
    o.gyro_bias_from_matches = learn;
    const EvaluationResult r = EvaluateSource(src, pairs, o);
    ASSERT_EQ(r.records.size(), pairs.size());
    EXPECT_GT(r.records.front().motion_rotation_error_deg, 0.15);
    for (size_t i = 5; i < r.records.size(); ++i) {
      if (learn) {
        EXPECT_LT(r.records[i].motion_rotation_error_deg, 0.08) << "pair " << i;
      } else {
        EXPECT_GT(r.records[i].motion_rotation_error_deg, 0.15) << "pair " << i;
      }
    }
    bool note = false;
    for (const auto& n : r.notes) note |= n.find("gyro bias learnt") != std::string::npos;
    EXPECT_EQ(note, learn);
  }
}

// MH_05's camera and IMU share one clock (the hardware triggers the camera). A camera whose clock
// ran 10 ms behind the IMU's (t_imu = t_cam + 0.010 s: a USB camera, a phone) is simulated by
// stamping every frame 10 ms early, its ground truth left at the true instant. The guided pairs'
// fitted rotations measure that offset (in flight, without depth: pairs 80-119) and eval advises
// setting it; on the frames as recorded it finds none worth setting. Either way within 3 sigmas
// and 1 ms of the truth: the rotations are measured from each pair's final matches. From the first
// pass's, found in the IMU's windows, they leaned towards the IMU's rotation and the estimate fell
// short of a true offset by up to a fifth (8.0-11.2 ms over windows of 40 and 80 pairs), beyond
// its stated sigma. (The IMU's rotation error against the ground truth cannot show an offset:
// both are read at the frame's stamp.)
TEST(EvalFlightVariantTest, TheFittedRotationsMeasureTheCamerasClockOffset) {
  EvaluationOptions o = FlightOptions();
  o.detectors = {DetectorKind::kOrb};
  o.methods = {MatchMethod::kGuided};
  const std::vector<FramePair> pairs = ConsecutivePairs(80, 120);
  for (const double offset_s : {0.0, 0.010}) {
    SCOPED_TRACE(offset_s);
    Dataset d = LoadDataset(testing::DataPath("euroc_mh05_flight"), DatasetOptions());
    for (FrameRecord& f : d.frames) f.t_ns -= SecondsToNs(offset_s);
    const EvaluationResult r = EvaluateSource(MakeDiskSource(std::move(d)), pairs, o);
    ASSERT_EQ(r.time_offsets.size(), 1u);
    const TimeOffsetEstimate& est = r.time_offsets[0].estimate;
    ASSERT_TRUE(est.measured) << est.reason;
    EXPECT_GE(est.observations, 25);
    EXPECT_LT(est.sigma_s, 1e-3);
    std::printf("shift %+.1f ms: offset %+.2f ms, sigma %.2f ms\n", 1e3 * offset_s,
                1e3 * est.offset_s, 1e3 * est.sigma_s);
    EXPECT_NEAR(est.offset_s, offset_s, std::min(3.0 * est.sigma_s, 1e-3));
    bool advised = false;
    for (const std::string& w : r.warnings) advised |= w.find("clocks look") != std::string::npos;
    EXPECT_EQ(advised, offset_s != 0.0);
  }
}

TEST(EvalFlightTest, WindowsHoldTheTruePartners) {
  for (MotionSource source : {MotionSource::kImu, MotionSource::kGroundTruth}) {
    const FlightRun gt_run = source == MotionSource::kImu ? FlightRun() : RunFlight(source, false);
    const FlightRun& run = source == MotionSource::kImu ? FlightImu() : gt_run;
    const auto rows = Summarize(run.result.records, run.threshold_px);
    for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
      SCOPED_TRACE(ToString(d) + std::string(" ") + ToString(source));
      const MethodSummary& g = Row(rows, run.result.records[0].case_name, d, MatchMethod::kGuided);
      ASSERT_GT(g.window_checked, 5000);
      // Issue #10's bounds: 0.98 with the IMU, 0.99 with the exact motion. Before the fix (the
      // segment straight in distorted pixels, no gyro bias, no near floor) ORB had 0.91 / 0.76
      // in its worst pairs.
      EXPECT_GE(g.window_recall, source == MotionSource::kImu ? 0.98 : 0.99);
    }
  }
}

TEST(EvalFlightTest, InFlightTheSegmentsStartWhereTheSceneDoes) {
  // Pairs 100-119: the drone flies metres from the hall's walls and floor. The pilot moves the
  // near end of the epipolar segments away from 0.1 m, and every pair's window recall (judged by
  // the ground truth) stays above issue #10's bound for the IMU.
  const FlightRun& run = FlightImu();
  for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
    SCOPED_TRACE(ToString(d));
    int flight_pairs = 0, moved = 0;
    for (const auto& r : run.result.records) {
      if (r.detector != d || r.frame_a < 100) continue;
      for (const auto& mr : r.runs) {
        if (mr.method != MatchMethod::kGuided) continue;
        ++flight_pairs;
        EXPECT_EQ(mr.scene_near.pilot_queries, 100);
        if (mr.scene_near.moved) {
          ++moved;
          EXPECT_GT(mr.scene_near.segment_min_depth_m, 0.1);
        }
        EXPECT_GE(ComputeWindowRecall(r, mr, run.threshold_px).Recall(), 0.98) << r.frame_a;
      }
    }
    EXPECT_EQ(flight_pairs, 20);
    EXPECT_GE(moved, 15);
  }
}

TEST(EvalFlightTest, InFlightTheSecondPassShrinksTheWindows) {
  // Pairs 100-119: the motion fitted to the first pass's matches is tighter than the IMU's, and
  // the first pass's matches bound the depths of their neighbours, so the second pass searches
  // smaller windows and shorter segments (the window recall above is that of its windows) in
  // almost every pair.
  const FlightRun& run = FlightImu();
  for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
    SCOPED_TRACE(ToString(d));
    int ran = 0;
    for (const auto& r : run.result.records) {
      if (r.detector != d || r.frame_a < 100) continue;
      for (const auto& mr : r.runs) {
        if (mr.method != MatchMethod::kGuided) continue;
        if (mr.second_pass != SecondPassOutcome::kRan) continue;
        ++ran;
        // ORB's windows are the motion's as much as the keypoints' (fine keypoints); SIFT's are
        // the keypoints' own noise (its sizes), which no fit shrinks.
        if (d == DetectorKind::kOrb) {
          EXPECT_LT(mr.window_px, 0.95 * mr.first_window_px) << r.frame_a;
        }
        EXPECT_LE(mr.refit.sigma_px, std::sqrt(2.0)) << r.frame_a;
        // Nearly every keypoint without depth has matched neighbours: its segment is cut to their
        // inverse depths (the window recall above is that of the cut segments).
        EXPECT_GE(mr.narrowed_segments, 0.8 * mr.stats.predicted_without_depth) << r.frame_a;
        EXPECT_LE(mr.narrowed_segments, mr.stats.predicted_without_depth) << r.frame_a;
        // The fit and the IMU agree with the ground truth to millimetres and thousandths of a
        // degree (its error is of the ground truth's own size).
        EXPECT_LT(mr.refit_translation_error_m, 0.02) << r.frame_a;
        EXPECT_LT(mr.refit_rotation_error_deg, 0.05) << r.frame_a;
      }
    }
    EXPECT_GE(ran, 18);
  }
}

// A monocular camera at take-off (pairs 0-19, predicted without depth; the depth images only
// judge). The drone climbs 1-5 mm per frame and the IMU's velocity is known to 0.05 m/s (2.5 mm
// per frame): the translation's sign is open, and a fit to epipolar distances cannot settle it.
// The true partners of pairs 7-8 lay beyond the rotation-only point, outside segments that ended
// there: window recall 0.54-0.69 in those pairs, and cutting the segments to the neighbours'
// inverse depths (clamped at infinity) made it worse. The segments now span both ends' gate
// ellipses, and the neighbours' ranges keep their sign when it is open.
TEST(EvalFlightVariantTest, MonocularAtTakeOffTheWindowsHoldThePartners) {
  EvaluationOptions o = FlightOptions();
  o.monocular = true;
  const EvaluationResult result = EvaluateSource(FlightSource(), ConsecutivePairs(0, 20), o);
  ASSERT_EQ(result.records.size(), 40u);
  const double threshold = ChooseThreshold(result, false, std::nullopt).threshold_px;
  bool note = false;
  for (const auto& n : result.notes) note |= n.find("monocular") != std::string::npos;
  EXPECT_TRUE(note);
  int keypoints_with_depth = 0;
  for (const auto& r : result.records) {
    keypoints_with_depth += r.keypoints_a_with_depth;  // the judge has depth
    for (const auto& mr : r.runs) {
      if (mr.method != MatchMethod::kGuided) continue;
      EXPECT_EQ(mr.stats.predicted_with_depth, 0) << r.frame_a;  // the predictor has none
      EXPECT_GE(ComputeWindowRecall(r, mr, threshold).Recall(), 0.9) << r.frame_a;
    }
  }
  EXPECT_GT(keypoints_with_depth, 40 * 20);
  const auto rows = Summarize(result.records, threshold);
  for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
    SCOPED_TRACE(ToString(d));
    const MethodSummary& g = Row(rows, result.records[0].case_name, d, MatchMethod::kGuided);
    const MethodSummary& b = Row(rows, result.records[0].case_name, d, MatchMethod::kBruteForce);
    EXPECT_GE(g.window_recall, 0.99);
    EXPECT_GE(g.correct, b.correct);
    EXPECT_GE(g.precision, b.precision);
  }
}

// Take-off pairs: every guided run's window recall >= 0.99 and its second-pass fit held; prints
// each and returns the fits' mean translation error against the ground truth (m), and their count.
std::pair<double, int> ExpectTakeOffWindowsHold(const EvaluationResult& result) {
  const double threshold = ChooseThreshold(result, false, std::nullopt).threshold_px;
  double fit_error_m = 0.0;
  int fits = 0;
  for (const auto& r : result.records) {
    EXPECT_GT(r.keypoints_a_with_depth, 0) << r.frame_a;
    for (const auto& mr : r.runs) {
      if (mr.method != MatchMethod::kGuided) continue;
      SCOPED_TRACE(ToString(r.detector) + " frame " + std::to_string(r.frame_a));
      const double recall = ComputeWindowRecall(r, mr, threshold).Recall();
      EXPECT_GE(recall, 0.99);
      EXPECT_TRUE(mr.refit.ok) << mr.refit.reason;
      if (!mr.refit.ok) continue;
      fit_error_m += mr.refit_translation_error_m;
      ++fits;
      std::printf("%s frame %zu: window recall %.3f, fit %.1f mm off\n",
                  ToString(r.detector).c_str(), r.frame_a, recall,
                  1e3 * mr.refit_translation_error_m);
    }
  }
  return {fits > 0 ? fit_error_m / fits : 0.0, fits};
}

// Three frames apart at take-off (frames 21-33, depth from stereo): the nearest keypoints with
// depth are corners of a beam's outline 0.6 m away that move with the background behind it. Fed
// to the second pass's fit, they set the translation's length 19.7 mm off on average with a
// stated sigma under a millimetre, and its windows lost up to 11 % of the pair's correct matches
// (checked by clearing no depth: window recall 0.885-0.977 in five of the eight runs). The fit
// now leaves out depth read near an occlusion edge.
TEST(EvalFlightVariantTest, AtTakeOffTheFitIgnoresDepthReadAcrossOcclusionEdges) {
  EvaluationOptions o = FlightOptions();
  o.detectors = {DetectorKind::kOrb, DetectorKind::kFastBrief};
  std::vector<FramePair> pairs;
  for (const size_t a : {size_t{21}, size_t{24}, size_t{27}, size_t{30}})
    pairs.push_back({a, a + 3});
  const EvaluationResult result = EvaluateSource(FlightSource(), pairs, o);
  ASSERT_EQ(result.records.size(), 8u);
  const auto [mean_fit_error_m, fits] = ExpectTakeOffWindowsHold(result);
  ASSERT_EQ(fits, 8);
  EXPECT_LT(mean_fit_error_m, 0.014);  // 7.7 mm now (8.9 before the second start)
}

// At take-off (MH_05 frames 10-13, 4-8 mm between frames, the IMU's translation 3-5 mm off and
// up to 57 degrees off in direction), the second pass's fit started from the IMU's direction and
// settled in a wrong minimum with a stated sigma of 0.3 mm along the translation: FAST+BRIEF
// frames 11 -> 12 lost a third of the correct matches to its windows (window recall 0.677, 0.913
// on the next pair, SIFT 0.963 on frames 10 -> 11). The fit now also starts from directions
// through pairs of matches when they explain the matches better (translation_direction.h).
TEST(EvalFlightVariantTest, AtTakeOffTheFitFindsTheTranslationsDirection) {
  EvaluationOptions o = FlightOptions();
  o.detectors = {DetectorKind::kSift, DetectorKind::kFastBrief};
  const std::vector<FramePair> pairs = {{10, 11}, {11, 12}, {12, 13}};
  const EvaluationResult result = EvaluateSource(FlightSource(), pairs, o);
  ASSERT_EQ(result.records.size(), 6u);
  const auto [mean_fit_error_m, fits] = ExpectTakeOffWindowsHold(result);
  ASSERT_EQ(fits, 6);
  EXPECT_LT(mean_fit_error_m, 0.01);  // 1.5 mm now
}

TEST(EvalFlightTest, GuidedBeatsBruteForceWithAndWithoutDepth) {
  const FlightRun& run = FlightImu();
  const auto split = SplitByDepth(run.result.records);
  const auto rows = Summarize(split, run.threshold_px);
  for (const std::string half : {" [depth]", " [no depth]"}) {
    for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
      SCOPED_TRACE(ToString(d) + half);
      const std::string c = run.result.records[0].case_name + half;
      const MethodSummary& g = Row(rows, c, d, MatchMethod::kGuided);
      const MethodSummary& b = Row(rows, c, d, MatchMethod::kBruteForce);
      EXPECT_EQ(g.pairs, 20);
      // Today's main had 0.58 (SIFT) and 0.83 (ORB) of brute force's correct matches.
      EXPECT_GE(g.correct, b.correct);
      EXPECT_GE(g.precision, b.precision);
    }
  }
  // Precision at tight thresholds, pooled: the refined positions are within a pixel far more
  // often than the keypoints brute force matches.
  for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
    for (double t : {1.0, 3.0, 8.0}) {
      SCOPED_TRACE(ToString(d) + " @" + std::to_string(t));
      JudgedCounts g, b;
      for (const auto& r : run.result.records) {
        if (r.detector != d) continue;
        for (const auto& mr : r.runs) {
          const JudgedCounts c = CountCorrect(mr.residuals, t);
          JudgedCounts& acc = mr.method == MatchMethod::kGuided ? g : b;
          acc.matches += c.matches;
          acc.correct += c.correct;
        }
      }
      ASSERT_GT(g.matches, 0);
      EXPECT_GE(static_cast<double>(g.correct) / g.matches,
                static_cast<double>(b.correct) / b.matches);
    }
  }
}

// The second look by the image patch: the queries the descriptors left unmatched with candidates
// in their windows, matched where A's patch (warped by the IMU's prediction) aligns at one place.
// Judged by the ground truth: on the frames with depth its matches are at least as precise as the
// guided matches of the descriptors, and it adds a good share of matches.
TEST(EvalFlightTest, ThePatchLookAddsMatchesAsPreciseAsTheDescriptors) {
  const FlightRun& run = FlightImu();
  for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
    SCOPED_TRACE(ToString(d));
    int added = 0, added_correct = 0, added_depth = 0, added_depth_correct = 0;
    int other_depth = 0, other_depth_correct = 0, pairs = 0;
    for (const auto& r : run.result.records) {
      if (r.detector != d) continue;
      for (const auto& mr : r.runs) {
        if (mr.method != MatchMethod::kGuided) continue;
        ++pairs;
        ASSERT_EQ(mr.match_by_patch.size(), mr.residuals.size());
        for (size_t j = 0; j < mr.residuals.size(); ++j) {
          const bool correct = mr.residuals[j].CorrectAt(run.threshold_px);
          const bool by_depth = mr.residuals[j].kind == ResidualKind::kDepth;
          if (mr.match_by_patch[j]) {
            ++added;
            added_correct += correct;
            added_depth += by_depth;
            added_depth_correct += by_depth && correct;
          } else if (by_depth) {
            ++other_depth;
            other_depth_correct += correct;
          }
        }
      }
    }
    std::cout << ToString(d) << ": patch look added " << added << " matches in " << pairs
              << " pairs (" << added_correct << " correct), judged by depth " << added_depth << " ("
              << added_depth_correct << " correct); the descriptors' judged by depth "
              << other_depth << " (" << other_depth_correct << " correct)\n";
    ASSERT_EQ(pairs, 40);
    EXPECT_GT(added, (d == DetectorKind::kOrb ? 10 : 1) * pairs);
    ASSERT_GT(added_depth, 10);
    EXPECT_GE(static_cast<double>(added_depth_correct) / added_depth,
              static_cast<double>(other_depth_correct) / other_depth);
  }
}

TEST(EvalFlightTest, TheFateOfBruteForcesCorrectMatchesAddsUp) {
  // Each query has at most one match per method, so brute force's correct matches split into
  // kept, matched wrong and the not-matched outcomes, and gained - lost is exactly the difference
  // of the correct counts (an identity between two independent countings of the same runs).
  const FlightRun& run = FlightImu();
  for (DetectorKind d : {DetectorKind::kOrb, DetectorKind::kSift}) {
    SCOPED_TRACE(ToString(d));
    BruteForceFate total;
    int bf_correct = 0, guided_correct = 0;
    for (const auto& r : run.result.records) {
      if (r.detector != d) continue;
      for (const auto& mr : r.runs) {
        const int correct = CountCorrect(mr.residuals, run.threshold_px).correct;
        if (mr.method == MatchMethod::kGuided) {
          total.Add(ComputeBruteForceFate(r, mr, run.threshold_px));
          guided_correct += correct;
        } else {
          bf_correct += correct;
        }
      }
    }
    EXPECT_EQ(total.checked, bf_correct);
    EXPECT_EQ(total.checked, total.kept + total.matched_wrong + total.refine_dropped +
                                 total.no_prediction + total.no_candidate + total.inconsistent +
                                 total.distance + total.ratio + total.mutual);
    EXPECT_EQ(total.kept + total.gained, guided_correct);
    // Guided keeps almost all of them (the window recall is >= 0.98) and gains more than it loses.
    EXPECT_GT(total.kept, 0.97 * total.checked);
    EXPECT_GT(total.gained, total.checked - total.kept);
  }
}

}  // namespace
}  // namespace imumatch

namespace imumatch {
namespace {

// EuRoC's lens written as an equidistant (Kannala-Brandt) lens with the same K: k1..k4 fitted by
// least squares to the radial part of its radial-tangential model, theta from 0 to the image
// corners' ray angle (its tangential terms, p1 = 2e-4, move a point by 0.1 px at most).
PinholeCamera EquidistantFitOf(const PinholeCamera& radtan) {
  double max_theta = 0.0;
  for (const double u : {-0.5, radtan.width - 0.5}) {
    for (const double v : {-0.5, radtan.height - 0.5}) {
      max_theta = std::max(max_theta, std::atan(radtan.PixelToNormalized({u, v}).norm()));
    }
  }
  const auto& [k1, k2, p1, p2, k3] = radtan.distortion;
  constexpr int kSamples = 200;
  Eigen::MatrixXd a(kSamples, 4);
  Eigen::VectorXd b(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const double theta = max_theta * (i + 1) / kSamples, r = std::tan(theta), r2 = r * r;
    b(i) = r * (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))) - theta;
    for (int c = 0; c < 4; ++c) a(i, c) = std::pow(theta, 2 * c + 3);
  }
  const Eigen::Vector4d k = a.colPivHouseholderQr().solve(b);
  PinholeCamera kb = radtan;
  kb.model = DistortionModel::kEquidistant;
  kb.distortion = {k(0), k(1), k(2), k(3), 0.0};
  return kb;
}

// The same lens in the other model: the matcher must not care. The fitted equidistant camera
// agrees with EuRoC's calibration to a fraction of a pixel over the whole image (checked against
// the radial-tangential closed form, which the equidistant code does not use), and guided matching
// on real frames with and without depth keeps its partners in the windows and finds the same
// correct matches within a few percent.
TEST(EvalFlightVariantTest, TheSameLensAsAnEquidistantModelMatchesAlike) {
  Dataset radtan_set = LoadDataset(testing::DataPath("euroc_mh05_flight"), DatasetOptions());
  const PinholeCamera radtan = radtan_set.camera;
  const PinholeCamera kb = EquidistantFitOf(radtan);
  ASSERT_NO_THROW(kb.Check());
  std::vector<double> errors;
  for (double v = -0.5; v <= radtan.height - 0.5; v += 9.5) {
    for (double u = -0.5; u <= radtan.width - 0.5; u += 9.5) {
      const Eigen::Vector2d uv(u, v);
      errors.push_back((kb.NormalizedToPixel(radtan.PixelToNormalized(uv)) - uv).norm());
    }
  }
  // Four coefficients in theta cannot follow a polynomial in tan(theta) exactly: 0.14 px in the
  // median, 0.66 px in the top-left corner.
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.2);
  EXPECT_LT(errors.back(), 0.75);

  EvaluationOptions o = FlightOptions();
  o.detectors = {DetectorKind::kOrb};
  std::vector<FramePair> pairs = ConsecutivePairs(2, 8);
  const std::vector<FramePair> flight = ConsecutivePairs(100, 106);
  pairs.insert(pairs.end(), flight.begin(), flight.end());
  Dataset kb_set = radtan_set;
  kb_set.camera = kb;
  const EvaluationResult with_radtan =
      EvaluateSource(MakeDiskSource(std::move(radtan_set)), pairs, o);
  const EvaluationResult with_kb = EvaluateSource(MakeDiskSource(std::move(kb_set)), pairs, o);
  const double threshold = ChooseThreshold(with_radtan, false, std::nullopt).threshold_px;
  const auto rows_radtan = Summarize(with_radtan.records, threshold);
  const auto rows_kb = Summarize(with_kb.records, threshold);
  const std::string c = with_radtan.records[0].case_name;
  const MethodSummary& g_radtan = Row(rows_radtan, c, DetectorKind::kOrb, MatchMethod::kGuided);
  const MethodSummary& g_kb =
      Row(rows_kb, with_kb.records[0].case_name, DetectorKind::kOrb, MatchMethod::kGuided);
  const MethodSummary& b_kb =
      Row(rows_kb, with_kb.records[0].case_name, DetectorKind::kOrb, MatchMethod::kBruteForce);
  ASSERT_GT(g_kb.window_checked, 2000);
  EXPECT_GE(g_kb.window_recall, 0.98);
  EXPECT_NEAR(g_kb.correct, g_radtan.correct, 0.03 * g_radtan.correct);
  EXPECT_GE(g_kb.correct, b_kb.correct);
  EXPECT_GE(g_kb.precision, b_kb.precision);
}

}  // namespace
}  // namespace imumatch
