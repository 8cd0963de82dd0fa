// `track` on data with ground truth that the front end never sees: a synthetic seed motion from
// rest (exact truth) and the real EuRoC MH_05 flight; compared with `eval`, which is given the
// ground-truth state.
#include <gtest/gtest.h>

#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/summary.h"
#include "imumatch/eval/track_run.h"
#include "imumatch/io/dataset.h"
#include "imumatch/sim/synthetic_sequence.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

// Pooled precision of one pass at threshold index i.
double Precision(const TrackRunResult& r, bool final_pass, size_t i) {
  double correct = 0, matches = 0;
  for (const TrackFrameRecord& f : r.frames) {
    if (!f.judged) continue;
    const JudgedCounts& c = final_pass ? f.final_counts[i] : f.pass1_counts[i];
    correct += c.correct;
    matches += c.matches;
  }
  return matches > 0 ? correct / matches : 0.0;
}

TEST(TrackRun, SyntheticFromRestMatchesEvalWithTheTrueState) {
  SyntheticSequenceOptions so;
  so.motion = "left30";
  so.camera = PinholeCamera::KinectDefault().ScaledToWidth(320);
  so.frame_rate_hz = 20.0;
  const EvalSource source = MakeSyntheticSource(MakeSyntheticSequence(so), "left30");
  TrackRunOptions o;
  o.front_end.features.max_keypoints = 400;
  o.front_end.still_s = 0.4;
  o.thresholds_px = {1.5};
  const TrackRunResult r = RunTrack(source, o);
  ASSERT_TRUE(r.has_truth);
  EXPECT_EQ(r.FallbackCount(), 0);
  int judged = 0;
  for (const TrackFrameRecord& f : r.frames) {
    EXPECT_TRUE(f.error.empty()) << f.error;
    judged += f.judged ? 1 : 0;
  }
  EXPECT_GE(judged, static_cast<int>(r.frames.size()) - 10);  // 0.4 s of waiting, at 20 Hz
  // eval on the same consecutive pairs, given the ground-truth state (perturbed as a VIO would).
  EvaluationOptions eo;
  eo.detectors = {DetectorKind::kOrb};
  eo.features.max_keypoints = 400;
  eo.methods = {MatchMethod::kGuided};
  std::vector<FramePair> pairs;
  for (size_t k = 10; k + 1 < source.dataset.frames.size(); ++k) pairs.push_back({k, k + 1});
  const auto rows = Summarize(EvaluateSource(source, pairs, eo).records, 1.5);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_NEAR(Precision(r, false, 0), rows[0].precision, 0.005);
  EXPECT_GE(Precision(r, true, 0), Precision(r, false, 0));
  // Exact ground truth: the relative pose error is small (depth everywhere: PnP on every frame).
  EXPECT_GT(r.rpe.pairs(), 40u);
  EXPECT_LT(r.rpe.rmse_translation_m, 0.005);
  EXPECT_LT(r.rpe.rmse_rotation_deg, 0.05);
}

TEST(TrackRun, RealFlightWithoutGroundTruthState) {
  const EvalSource source =
      MakeDiskSource(LoadDataset(testing::DataPath("euroc_mh05_flight"), DatasetOptions()));
  TrackRunOptions o;
  o.max_frames = 50;  // 36 frames with depth, then none
  const TrackRunResult r = RunTrack(source, o);
  EXPECT_EQ(r.frames.size(), 50u);
  EXPECT_EQ(r.FallbackCount(), 0);
  ASSERT_EQ(r.notes.size(), 2u);
  EXPECT_NE(r.notes[0].find("still start"), std::string::npos) << r.notes[0];
  // The bias learnt since (FrontEndOptions::learn_gyro_bias) agrees with the ground truth's batch
  // estimate for MH_05 (-0.0018, 0.0209, 0.0769 rad/s; the still start's: -0.0018, 0.0200, 0.0779).
  EXPECT_NE(r.notes[1].find("gyro bias learnt from the fitted rotations"), std::string::npos)
      << r.notes[1];
  ASSERT_TRUE(r.learnt_gyro_bias.has_value());
  EXPECT_LT((*r.learnt_gyro_bias - Eigen::Vector3d(-0.0018, 0.0209, 0.0769)).cwiseAbs().maxCoeff(),
            0.003)
      << r.learnt_gyro_bias->transpose();
  // Both passes are precise; the second (fitted pose + geometric check) more so at 1 px.
  EXPECT_GT(Precision(r, false, 1), 0.97);  // 3 px
  EXPECT_GT(Precision(r, true, 0), Precision(r, false, 0));
  EXPECT_EQ(r.rpe.pairs(), 49u);
}

}  // namespace
}  // namespace imumatch
