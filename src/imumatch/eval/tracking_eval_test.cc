// The tracking methods (klt0, klt, hybrid) in the evaluation, judged by exact synthetic ground
// truth (in-plane roll, exposure gain) and by the real TUM pair's and EuRoC flight's.
#include <algorithm>
#include <string>

#include <gtest/gtest.h>

#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/seed_cases.h"
#include "imumatch/eval/summary.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/pose_pair.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

const MethodSummary& Row(const std::vector<MethodSummary>& rows, MatchMethod m) {
  for (const auto& r : rows) {
    if (r.method == m) return r;
  }
  ADD_FAILURE() << "no row " << ToString(m);
  static const MethodSummary empty;
  return empty;
}

EvaluationOptions TrackingOptions() {
  EvaluationOptions o;
  o.detectors = {DetectorKind::kOrb};
  o.features.max_keypoints = 400;
  o.methods = {MatchMethod::kBruteForce, MatchMethod::kGuided, MatchMethod::kKltUnseeded,
               MatchMethod::kKlt, MatchMethod::kHybrid};
  return o;
}

// Consecutive frames of a seed motion, 0.5 s apart (3 intermediate frames over 2 s), 320 x 240.
SeedCase Steps(const std::string& motion) {
  SeedCaseOptions so;
  so.motions = {motion};
  so.intermediate_frames = 3;
  so.camera = PinholeCamera::KinectDefault().ScaledToWidth(320);
  for (SeedCase& c : MakeSeedCases(so)) {
    if (c.name == motion + "-steps") return c;
  }
  ADD_FAILURE() << "no steps case";
  return SeedCase();
}

// The hybrid's promise on one run: at least as many correct correspondences as the better of
// its two paths, and never less precise than brute force.
void ExpectHybridHolds(const std::vector<MethodSummary>& rows) {
  const MethodSummary& h = Row(rows, MatchMethod::kHybrid);
  EXPECT_GE(h.correct, std::max(Row(rows, MatchMethod::kKlt).correct,
                                Row(rows, MatchMethod::kGuided).correct));
  EXPECT_GE(h.precision, Row(rows, MatchMethod::kBruteForce).precision);
}

TEST(TrackingEvalTest, InPlaneRollIsTrackedWithThePredictedRotation) {
  const SeedCase c = Steps("roll45");  // about 22 deg of roll between frames
  const EvaluationResult r = EvaluateSource(c.source, c.pairs, TrackingOptions(), c.name);
  ASSERT_TRUE(r.skipped.empty()) << r.skipped.front().reason;
  const auto rows = Summarize(r.records, 1.5);  // exact ground truth
  const MethodSummary& klt = Row(rows, MatchMethod::kKlt);
  const MethodSummary& klt0 = Row(rows, MatchMethod::kKltUnseeded);
  EXPECT_GE(klt.precision, 0.99);
  EXPECT_GT(klt.correct, 0.8 * klt.keypoints);
  // An axis-aligned 21 x 21 window does not follow a 22 deg roll.
  EXPECT_LT(klt0.correct, 0.8 * klt.correct);
  ExpectHybridHolds(rows);
  for (const DetectorPairRecord& rec : r.records) {
    for (const MethodRun& run : rec.runs) {
      if (!IsTracking(run.method)) continue;
      EXPECT_EQ(run.track_stats.OutcomeSum(), rec.keypoints_a);
      EXPECT_EQ(run.from_tracks, run.track_stats.tracked);
      if (run.method != MatchMethod::kHybrid) {
        EXPECT_EQ(run.from_descriptors, 0);
      }
    }
  }
}

TEST(TrackingEvalTest, ExposureGainCancelsInNormalisedPatches) {
  const SeedCase c = Steps("left30");
  EvaluationOptions o = TrackingOptions();
  o.gain_b = 0.6;
  const EvaluationResult r = EvaluateSource(c.source, c.pairs, o, c.name);
  ASSERT_TRUE(r.skipped.empty()) << r.skipped.front().reason;
  const auto rows = Summarize(r.records, 1.5);
  const MethodSummary& klt = Row(rows, MatchMethod::kKlt);
  EXPECT_GE(klt.precision, 0.99);
  EXPECT_GE(klt.correct, Row(rows, MatchMethod::kGuided).correct);
  EXPECT_LT(Row(rows, MatchMethod::kKltUnseeded).correct, klt.correct);
  ExpectHybridHolds(rows);
  // The gain reached frame B: the same run without it gives the unseeded tracker far more.
  o.gain_b = 1.0;
  const auto plain = Summarize(EvaluateSource(c.source, c.pairs, o, c.name).records, 1.5);
  EXPECT_GT(Row(plain, MatchMethod::kKltUnseeded).correct,
            Row(rows, MatchMethod::kKltUnseeded).correct);
}

TEST(TrackingEvalTest, RealTumPair) {
  const EvalSource source =
      MakeDiskSource(LoadPosePairFolder(testing::DataPath("tum_fr1_xyz_pair")));
  EvaluationOptions o = TrackingOptions();
  o.features.max_keypoints = 1000;
  o.motion_source = MotionSource::kGroundTruth;  // the excerpt has no IMU
  const EvaluationResult r = EvaluateSource(source, {{0, 1}}, o);
  ASSERT_EQ(r.records.size(), 1u);
  const double threshold = ChooseThreshold(r, false, std::nullopt).threshold_px;
  const auto rows = Summarize(r.records, threshold);
  EXPECT_GT(Row(rows, MatchMethod::kKlt).precision, 0.98);
  ExpectHybridHolds(rows);
}

TEST(TrackingEvalTest, RealFlightWithAndWithoutDepth) {
  const EvalSource src =
      MakeDiskSource(LoadDataset(testing::DataPath("euroc_mh05_flight"), DatasetOptions()));
  std::vector<FramePair> pairs;
  for (size_t a = 0; a < 6; ++a) pairs.push_back({a, a + 1});      // depth
  for (size_t a = 100; a < 106; ++a) pairs.push_back({a, a + 1});  // none
  const EvaluationResult r = EvaluateSource(src, pairs, TrackingOptions());
  ASSERT_TRUE(r.skipped.empty()) << r.skipped.front().reason;
  const double threshold = ChooseThreshold(r, false, std::nullopt).threshold_px;
  ExpectHybridHolds(Summarize(r.records, threshold));
  ExpectHybridHolds(Summarize(SplitByDepth(r.records), threshold));
}

}  // namespace
}  // namespace imumatch
