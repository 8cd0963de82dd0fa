#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/guided_pipeline.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/matching/matching_test_util.h"

namespace imumatch {
namespace {

// Random points seen by two cameras, descriptors with flipped bits (matching_test_util.h).
using testing::MakePair;
using testing::SyntheticPair;

CameraMotion Motion(const Rigid3d& r) {
  CameraMotion m;
  m.cam_b_from_cam_a = r;
  return m;
}

struct Outcome {
  MatchResult result;
  std::vector<KeypointPrediction> predictions;
  int correct = 0;
  int wrong = 0;
};

Outcome RunMatch(const SyntheticPair& s, const PredictionOptions& po,
                 const GuidedMatcherOptions& mo, bool use_depth = true) {
  Outcome o;
  o.predictions = PredictKeypoints(s.camera, s.motion, s.kps_a,
                                   use_depth ? s.depth_a : std::vector<float>(), po);
  GridIndex grid;
  grid.Build(s.kps_b, s.camera.width, s.camera.height, static_cast<float>(mo.grid_cell_size));
  o.result = MatchGuided(o.predictions, s.kps_a, DescriptorView::FromMat(s.desc_a), s.kps_b, grid,
                         DescriptorView::FromMat(s.desc_b), mo);
  for (const Match& m : o.result.matches) {
    (m.train_idx == s.partner[m.query_idx] ? o.correct : o.wrong)++;
  }
  EXPECT_EQ(o.result.stats.OutcomeSum(), o.result.stats.queries);
  // The per-query outcomes agree with the counts.
  EXPECT_EQ(o.result.outcomes.size(), s.kps_a.size());
  EXPECT_EQ(static_cast<int>(std::count(o.result.outcomes.begin(), o.result.outcomes.end(),
                                        QueryOutcome::kRatioTest)),
            o.result.stats.ratio_test);
  EXPECT_EQ(static_cast<int>(std::count(o.result.outcomes.begin(), o.result.outcomes.end(),
                                        QueryOutcome::kMatched)),
            o.result.stats.matched);
  return o;
}

const Rigid3d kTrueMotion(FromEulerZYX(0.03, -0.02, 0.04), Eigen::Vector3d(0.08, -0.03, 0.05));

TEST(GuidedMatcherTest, FindsEveryPartnerInsideItsWindow) {
  const SyntheticPair s = MakePair(400, 400, kTrueMotion, Motion(kTrueMotion), 1);
  const Outcome o = RunMatch(s, PredictionOptions(), GuidedMatcherOptions());
  int partner_in_window = 0;
  for (size_t i = 0; i < s.kps_a.size(); ++i) {
    const KeypointInfo& b = s.kps_b[s.partner[i]];
    partner_in_window += o.predictions[i].Contains(b.x, b.y);
  }
  EXPECT_EQ(partner_in_window, 400);
  EXPECT_EQ(o.correct, 400) << o.result.stats.ToString();
  EXPECT_EQ(o.wrong, 0);
  EXPECT_EQ(o.result.stats.predicted_with_depth, 400);
  // Far fewer distance computations than brute force (400 x 800).
  EXPECT_LT(o.result.stats.distances_computed, 400 * 800 / 50);
  for (const Match& m : o.result.matches) {
    EXPECT_LE(m.distance, 3.0f);  // 3 flipped bits
    EXPECT_TRUE(m.predicted_uv.allFinite());
  }
  const std::vector<cv::DMatch> dm = o.result.ToDMatches();
  ASSERT_EQ(dm.size(), o.result.matches.size());
  EXPECT_EQ(dm[0].trainIdx, o.result.matches[0].train_idx);
}

TEST(GuidedMatcherTest, GateExcludesPartnerJustOutsideTheWindow) {
  SyntheticPair s = MakePair(50, 0, kTrueMotion, Motion(kTrueMotion), 2);
  const PredictionOptions po;
  const std::vector<KeypointPrediction> pred =
      PredictKeypoints(s.camera, s.motion, s.kps_a, s.depth_a, po);
  // Keypoint 0's partner: move it 0.5 px outside the right edge of the window, keypoint 1's partner
  // 0.5 px inside the bottom edge.
  ASSERT_TRUE(pred[0].HasWindow() && pred[1].HasWindow());
  s.kps_b[s.partner[0]].x = pred[0].max_x + 0.5f;
  s.kps_b[s.partner[0]].y = pred[0].uv.y();
  s.kps_b[s.partner[1]].x = pred[1].uv.x();
  s.kps_b[s.partner[1]].y = pred[1].max_y - 0.5f;
  const Outcome o = RunMatch(s, po, GuidedMatcherOptions());
  std::map<int, int> by_query;
  for (const Match& m : o.result.matches) by_query[m.query_idx] = m.train_idx;
  EXPECT_EQ(by_query.count(0), 0u);
  ASSERT_EQ(by_query.count(1), 1u);
  EXPECT_EQ(by_query[1], s.partner[1]);
  EXPECT_EQ(o.result.stats.no_candidate_in_window, 1);
  EXPECT_EQ(o.correct, 49);
}

TEST(GuidedMatcherTest, UncertainPoseStillMatchesWithinTheGate) {
  // The matcher gets a nominal motion; the truth differs by a draw from the stated covariance.
  Eigen::Matrix<double, 6, 1> sig;
  sig << 0.01, 0.01, 0.005, 0.02, 0.02, 0.02;  // rad, m: ~5 px of rotation error at f=525
  // A perturbation of 0.8 sigma in every component (squared Mahalanobis norm 6 * 0.64 = 3.84):
  // its first-order image displacement has a 2-D squared Mahalanobis norm <= 3.84 < 9.21, so
  // every partner must lie inside its 99% gate. Truth: R_true = Exp(d) R, t_true = t + d_t.
  Eigen::Matrix<double, 6, 1> d;
  d << 0.8, -0.8, 0.8, -0.8, 0.8, -0.8;
  d = d.cwiseProduct(sig);
  const Rigid3d nominal = kTrueMotion;
  const Rigid3d truth(ExpSO3(d.head<3>()) * nominal.rotation, nominal.translation + d.tail<3>());
  CameraMotion given = Motion(nominal);
  given.covariance = sig.cwiseAbs2().asDiagonal();
  const SyntheticPair s = MakePair(400, 400, truth, given, 3);
  const Outcome o = RunMatch(s, PredictionOptions(), GuidedMatcherOptions());
  int in_window = 0;
  for (size_t i = 0; i < s.kps_a.size(); ++i) {
    in_window += o.predictions[i].Contains(s.kps_b[s.partner[i]].x, s.kps_b[s.partner[i]].y);
  }
  EXPECT_GE(in_window, 398);  // first-order bound; the projection's curvature may cost one or two
  EXPECT_GE(o.correct, 398) << o.result.stats.ToString();
  EXPECT_LE(o.wrong, 2);
  // The same nominal pose without its covariance gives windows too small for the error.
  SyntheticPair overconfident = s;
  overconfident.motion.covariance.setZero();
  const Outcome small = RunMatch(overconfident, PredictionOptions(), GuidedMatcherOptions());
  EXPECT_LT(small.correct, o.correct - 50) << small.result.stats.ToString();
}

TEST(GuidedMatcherTest, NoDepthKeypointsMatchAlongTheEpipolarSegment) {
  const SyntheticPair s = MakePair(200, 200, kTrueMotion, Motion(kTrueMotion), 4);
  GuidedMatcherOptions mo;
  const Outcome o = RunMatch(s, PredictionOptions(), mo, /*use_depth=*/false);
  EXPECT_EQ(o.result.stats.predicted_without_depth, 200);
  int contains = 0;
  for (size_t i = 0; i < s.kps_a.size(); ++i) {
    const KeypointInfo& b = s.kps_b[s.partner[i]];
    contains += o.predictions[i].Contains(b.x, b.y);
  }
  EXPECT_EQ(contains, 200);  // true depths 0.8..4 m lie in [0.3, inf)
  // Longer search regions admit distractors, but descriptors with 3 flipped bits stay unique.
  EXPECT_GE(o.correct, 198) << o.result.stats.ToString();
  EXPECT_EQ(o.wrong, 0);
}

TEST(GuidedMatcherTest, OrientationScaleAndMutualRejectionsAreCounted) {
  SyntheticPair s = MakePair(20, 0, kTrueMotion, Motion(kTrueMotion), 5);
  PredictionOptions po;
  std::vector<KeypointPrediction> pred =
      PredictKeypoints(s.camera, s.motion, s.kps_a, s.depth_a, po);
  // Angles and sizes consistent with the prediction for everyone...
  for (size_t i = 0; i < s.kps_a.size(); ++i) {
    s.kps_a[i].angle_deg = 100.0f;
    s.kps_a[i].size = 20.0f;
    s.kps_b[s.partner[i]].angle_deg = std::fmod(100.0f + pred[i].angle_change_deg + 360.0f, 360.0f);
    s.kps_b[s.partner[i]].size = 20.0f * pred[i].scale_min;
  }
  // ...except keypoint 0 (B angle off by 90 degrees) and keypoint 1 (B 5x larger).
  s.kps_b[s.partner[0]].angle_deg = std::fmod(s.kps_b[s.partner[0]].angle_deg + 90.0f, 360.0f);
  s.kps_b[s.partner[1]].size *= 5.0f;
  Outcome o = RunMatch(s, po, GuidedMatcherOptions());
  EXPECT_EQ(o.result.stats.orientation, 1);
  EXPECT_EQ(o.result.stats.scale, 1);
  EXPECT_EQ(o.correct, 18);
  GuidedMatcherOptions lax;
  lax.check_orientation = false;
  lax.check_scale = false;
  EXPECT_EQ(RunMatch(s, po, lax).correct, 20);

  // Mutual: keypoint 3's partner is removed from B's content by giving it a copy of keypoint 2's
  // position; A's keypoint 3 gets a descriptor close to (but farther than A2 from) B's partner
  // of 2.
  SyntheticPair m = MakePair(20, 0, kTrueMotion, Motion(kTrueMotion), 6);
  const int b2 = m.partner[2];
  m.kps_a[3] = m.kps_a[2];
  m.depth_a[3] = m.depth_a[2];
  m.desc_b.row(b2).copyTo(m.desc_a.row(3));
  m.desc_a.at<uint8_t>(3, 0) ^= 0xFF;  // 8 bits from B's partner of 2 (A2 is 3 bits away)
  GuidedMatcherOptions mo;
  mo.mutual = false;
  Outcome without = RunMatch(m, po, mo);
  int to_b2 = 0;
  for (const Match& x : without.result.matches) to_b2 += x.train_idx == b2;
  EXPECT_EQ(to_b2, 2);  // keypoints 2 and 3 both take it (3's own partner is farther away)
  mo.mutual = true;
  Outcome with = RunMatch(m, po, mo);
  to_b2 = 0;
  for (const Match& x : with.result.matches) {
    if (x.train_idx == b2) {
      ++to_b2;
      EXPECT_EQ(x.query_idx, 2);
    }
  }
  EXPECT_EQ(to_b2, 1);
  EXPECT_EQ(with.result.stats.mutual, 1);
}

TEST(GuidedMatcherTest, DistanceThresholdAndRatioTest) {
  SyntheticPair s = MakePair(30, 0, kTrueMotion, Motion(kTrueMotion), 8, /*flipped_bits=*/100);
  GuidedMatcherOptions mo;  // 0.35 * 256 = 89.6 bits allowed: 100 flipped bits are all rejected
  Outcome o = RunMatch(s, PredictionOptions(), mo);
  EXPECT_EQ(o.result.stats.distance_threshold, 30);
  EXPECT_EQ(o.result.stats.matched, 0);
  mo.max_hamming_fraction = 0.5;  // 128 bits; 100 < 0.8 * 128 passes the ratio against it too
  EXPECT_EQ(RunMatch(s, PredictionOptions(), mo).correct, 30);
  // The threshold is a virtual second-best: 80 bits pass the 89.6-bit threshold but are not
  // distinctive against it (80 >= 0.8 * 89.6 = 71.7), so a lone candidate is rejected by ratio.
  SyntheticPair lone = MakePair(30, 0, kTrueMotion, Motion(kTrueMotion), 8, /*flipped_bits=*/80);
  o = RunMatch(lone, PredictionOptions(), GuidedMatcherOptions());
  EXPECT_EQ(o.result.stats.ratio_test, 30);
  EXPECT_EQ(o.result.stats.matched, 0);
  // 70 bits are distinctive enough (70 < 71.7).
  SyntheticPair close = MakePair(30, 0, kTrueMotion, Motion(kTrueMotion), 8, /*flipped_bits=*/70);
  EXPECT_EQ(RunMatch(close, PredictionOptions(), GuidedMatcherOptions()).correct, 30);
  // Ratio: a second candidate 3 px from keypoint 0's partner (inside its window, outside the
  // 2 px twin radius), with a descriptor as close -> rejected.
  SyntheticPair r = MakePair(30, 0, kTrueMotion, Motion(kTrueMotion), 8);
  KeypointInfo rival = r.kps_b[r.partner[0]];
  rival.x += 3.0f;
  r.kps_b.push_back(rival);
  const cv::Mat twin = r.desc_b.row(r.partner[0]).clone();  // equal distance: ratio 1
  r.desc_b.push_back(twin);
  const Outcome ro = RunMatch(r, PredictionOptions(), GuidedMatcherOptions());
  EXPECT_EQ(ro.result.stats.ratio_test, 1);
  EXPECT_EQ(ro.correct, 29);
  EXPECT_EQ(ro.result.outcomes[0], QueryOutcome::kRatioTest);
}

TEST(GuidedMatcherTest, ATwinAtThePartnersPlaceIsNoRival) {
  // The same point detected twice (another pyramid level): a second keypoint 1 px from keypoint
  // 0's partner with the same descriptor. Brute force's ratio test cannot tell it from a distant
  // look-alike; guided matching sees that both sit at one place and keeps the match.
  SyntheticPair r = MakePair(30, 0, kTrueMotion, Motion(kTrueMotion), 8);
  KeypointInfo twin = r.kps_b[r.partner[0]];
  twin.x += 1.0f;
  r.kps_b.push_back(twin);
  r.desc_b.push_back(r.desc_b.row(r.partner[0]).clone());
  const Outcome kept = RunMatch(r, PredictionOptions(), GuidedMatcherOptions());
  EXPECT_EQ(kept.result.stats.ratio_test, 0);
  EXPECT_EQ(kept.result.stats.matched, 30);
  // Query 0 went to the partner or its twin, both at the true place.
  for (const Match& m : kept.result.matches) {
    if (m.query_idx != 0) continue;
    EXPECT_TRUE(m.train_idx == r.partner[0] || m.train_idx == static_cast<int>(r.kps_b.size()) - 1);
  }
  GuidedMatcherOptions classic;
  classic.duplicate_radius_px = 0.0;
  const Outcome strict = RunMatch(r, PredictionOptions(), classic);
  EXPECT_EQ(strict.result.stats.ratio_test, 1);
}

TEST(GuidedMatcherTest, InconsistentCandidatesStillCompeteInTheRatioTest) {
  // A twin of keypoint 0's partner, same place and descriptor but turned by 90 degrees: it fails
  // the orientation check, so it cannot be the match, yet it makes the match ambiguous.
  SyntheticPair r = MakePair(30, 0, kTrueMotion, Motion(kTrueMotion), 8);
  for (auto& k : r.kps_a) k.angle_deg = 10.0f;
  for (auto& k : r.kps_b) k.angle_deg = 10.0f;  // the true motion barely rolls the camera
  KeypointInfo twin = r.kps_b[r.partner[0]];
  twin.angle_deg = 100.0f;
  r.kps_b.push_back(twin);
  r.desc_b.push_back(r.desc_b.row(r.partner[0]).clone());
  GuidedMatcherOptions mo;
  mo.duplicate_radius_px = 0.0;  // the twin sits at the partner's place: not a rival otherwise
  const Outcome strict = RunMatch(r, PredictionOptions(), mo);
  EXPECT_EQ(strict.result.stats.ratio_test, 1);
  EXPECT_EQ(strict.correct, 29);
  mo.inconsistent_candidates_in_ratio = false;
  const Outcome lax = RunMatch(r, PredictionOptions(), mo);
  EXPECT_EQ(lax.result.stats.ratio_test, 0);
  EXPECT_EQ(lax.correct, 30);
}

// MatchGuided against a straightforward reference written from the matcher's contract: every
// keypoint of B tested against every window (no grid), the consistency tests, the ratio test with
// the best rival, duplicates of the best skipped, the distance threshold and the mutual check.
// Float descriptors (no ties) with planted near-copies, random angles and sizes, windows with and
// without depth (capsules), some outside B's image; dense enough that windows hold many
// candidates.
TEST(GuidedMatcherTest, EqualsABruteForceReference) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> ux(0.0f, 639.0f), uy(0.0f, 479.0f), u01(0.0f, 1.0f);
  std::uniform_real_distribution<float> angle(0.0f, 360.0f), size(7.0f, 60.0f);
  std::normal_distribution<float> noise(0.0f, 0.05f);
  const int n = 1500, m = 6000, dims = 16;
  std::vector<KeypointInfo> kps_a(n), kps_b(m);
  cv::Mat desc_a(n, dims, CV_32F), desc_b(m, dims, CV_32F);
  for (int j = 0; j < m; ++j) {
    kps_b[j] = {ux(rng), uy(rng), j % 7 == 0 ? -1.0f : angle(rng), j % 11 == 0 ? 0.0f : size(rng),
                0};
    for (int d = 0; d < dims; ++d) desc_b.at<float>(j, d) = u01(rng);
  }
  std::vector<KeypointPrediction> predictions(n);
  for (int i = 0; i < n; ++i) {
    const int partner = (i * 13) % m;
    const KeypointInfo& kb = kps_b[partner];
    KeypointPrediction& p = predictions[i];
    p.angle_change_deg = 60.0f * (u01(rng) - 0.5f);
    p.scale_min = 0.8f + 0.2f * u01(rng);
    p.scale_max = p.scale_min * (1.0f + 0.5f * u01(rng));
    // Most partners consistent with the prediction (angle within +-40 deg of it, so some are not;
    // size in range), the rest random.
    const bool consistent = i % 6 != 0;
    kps_a[i] = {kb.x, kb.y,
                i % 5 == 0 ? -1.0f
                : consistent && kb.angle_deg >= 0.0f
                    ? kb.angle_deg - p.angle_change_deg + 80.0f * (u01(rng) - 0.5f) + 360.0f
                    : angle(rng),
                i % 9 == 0                     ? 0.0f
                : consistent && kb.size > 0.0f ? kb.size / p.scale_min
                                               : size(rng),
                0};
    for (int d = 0; d < dims; ++d) {
      desc_a.at<float>(i, d) = i % 4 == 0 ? u01(rng) : desc_b.at<float>(partner, d) + noise(rng);
    }
    const float cx = kb.x + 4.0f * (u01(rng) - 0.5f), cy = kb.y + 4.0f * (u01(rng) - 0.5f);
    if (i % 3 == 0) {
      p.status = PredictionStatus::kWithoutDepth;
      const float len = 150.0f * u01(rng), dir = 6.2832f * u01(rng);
      p.segment_start = Eigen::Vector2f(cx, cy);
      p.segment_end = Eigen::Vector2f(cx + len * std::cos(dir), cy + len * std::sin(dir));
      p.radius = 2.0f + 8.0f * u01(rng);
      p.min_x = std::min(p.segment_start.x(), p.segment_end.x()) - p.radius;
      p.max_x = std::max(p.segment_start.x(), p.segment_end.x()) + p.radius;
      p.min_y = std::min(p.segment_start.y(), p.segment_end.y()) - p.radius;
      p.max_y = std::max(p.segment_start.y(), p.segment_end.y()) + p.radius;
      p.uv = p.segment_end;
    } else if (i % 29 == 1) {
      p.status = PredictionStatus::kOutsideImage;
    } else {
      p.status = PredictionStatus::kWithDepth;
      p.uv = Eigen::Vector2f(cx, cy);
      p.segment_start = p.segment_end = p.uv;
      const float hw = 3.0f + 20.0f * u01(rng), hh = 3.0f + 20.0f * u01(rng);
      p.min_x = cx - hw;
      p.max_x = cx + hw;
      p.min_y = cy - hh;
      p.max_y = cy + hh;
    }
  }
  const auto wrap = [](float a) { return a - 360.0f * std::floor((a + 180.0f) / 360.0f); };
  for (const int variant : {0, 1, 2}) {
    const bool rivals_all = variant != 1, mutual = variant != 2;
    GuidedMatcherOptions o;
    o.inconsistent_candidates_in_ratio = rivals_all;
    o.mutual = mutual;
    o.max_l2_relative = 0.6;
    o.duplicate_radius_px = 3.0;
    // The reference.
    float ref_b = 1e30f;
    for (const KeypointInfo& k : kps_b) {
      if (k.size > 0.0f) ref_b = std::min(ref_b, k.size);
    }
    std::vector<QueryOutcome> outcome(n, QueryOutcome::kMatched);
    std::vector<int> best_of(n, -1);
    std::vector<double> best_cost(n, 0.0), second_cost(n, 0.0);
    std::vector<double> reverse_cost(m, 1e300);
    std::vector<int> reverse_idx(m, -1);
    int64_t expected_distances = 0;
    const auto cost = [&](int i, int j) {
      return cv::norm(desc_a.row(i), desc_b.row(j), cv::NORM_L2SQR);
    };
    for (int i = 0; i < n; ++i) {
      const KeypointPrediction& p = predictions[i];
      if (p.status == PredictionStatus::kOutsideImage) {
        outcome[i] = QueryOutcome::kOutsideImage;
        continue;
      }
      const KeypointInfo& ka = kps_a[i];
      bool any_in = false, any_angle = false;
      std::vector<std::pair<int, bool>> candidates;  // (j, consistent)
      for (int j = 0; j < m; ++j) {
        const KeypointInfo& kb = kps_b[j];
        if (!p.Contains(kb.x, kb.y)) continue;
        any_in = true;
        const bool angle_ok =
            !(ka.angle_deg >= 0.0f && kb.angle_deg >= 0.0f &&
              std::fabs(wrap(kb.angle_deg - ka.angle_deg - p.angle_change_deg)) > 30.0f);
        const float lo = ka.size * p.scale_min / 2.0f, hi = ka.size * p.scale_max * 2.0f;
        const bool size_ok = !(ka.size > 0.0f && kb.size > 0.0f && (kb.size < lo || kb.size > hi));
        any_angle |= angle_ok;
        if (angle_ok && size_ok) {
          candidates.push_back({j, true});
        } else if (rivals_all) {
          candidates.push_back({j, false});
        }
      }
      ASSERT_DOUBLE_EQ(o.orientation_tolerance_deg, 30.0);
      ASSERT_DOUBLE_EQ(o.scale_tolerance_factor, 2.0);
      for (const auto& c : candidates) expected_distances += c.second ? 1 : 0;
      int best = -1;
      double best_c = 1e300;
      for (const auto& [j, consistent] : candidates) {
        if (!consistent) continue;
        const double c = cost(i, j);
        if (c < best_c) best_c = c, best = j;
        if (c < reverse_cost[j]) reverse_cost[j] = c, reverse_idx[j] = i;
      }
      if (!any_in) {
        outcome[i] = QueryOutcome::kNoCandidateInWindow;
        continue;
      }
      if (!any_angle) {
        outcome[i] = QueryOutcome::kOrientation;
        continue;
      }
      if (best < 0) {
        outcome[i] = QueryOutcome::kScale;
        continue;
      }
      const float scale = std::max(1.0f, kps_b[best].size > 0.0f ? kps_b[best].size / ref_b : 1.0f);
      const double dup = 3.0 * scale;
      double second = 1e300, rival = 1e300;
      int rivals = 0;
      for (const auto& [j, consistent] : candidates) {
        if (j == best ||
            std::hypot(kps_b[j].x - kps_b[best].x, kps_b[j].y - kps_b[best].y) <= dup) {
          continue;
        }
        (consistent ? second : rival) = std::min(consistent ? second : rival, cost(i, j));
        rivals += consistent ? 0 : 1;
      }
      const double max_cost =
          0.36 * 0.5 *
          (cv::norm(desc_a.row(i), cv::NORM_L2SQR) + cv::norm(desc_b.row(best), cv::NORM_L2SQR));
      if (best_c > max_cost) {
        outcome[i] = QueryOutcome::kDistanceThreshold;
        continue;
      }
      // The inconsistent rivals' distances are needed only when they decide.
      if (best_c < 0.64 * std::min(second, max_cost)) expected_distances += rivals;
      if (!(best_c < 0.64 * std::min({second, rival, max_cost}))) {
        outcome[i] = QueryOutcome::kRatioTest;
        continue;
      }
      best_of[i] = best;
      best_cost[i] = best_c;
      second_cost[i] = second;
    }
    ASSERT_DOUBLE_EQ(o.ratio, 0.8);
    std::vector<int> expected_matches;
    for (int i = 0; i < n; ++i) {
      if (best_of[i] < 0) continue;
      if (mutual && reverse_idx[best_of[i]] != i) {
        outcome[i] = QueryOutcome::kMutual;
      } else {
        expected_matches.push_back(i);
      }
    }
    // The matcher, on every instruction-set path of its window tests this CPU has.
    GridIndex grid;
    grid.Build(kps_b, 640, 480, static_cast<float>(o.grid_cell_size));
    for (const BruteForceKernel kernel : AvailableBruteForceKernels()) {
      SCOPED_TRACE(ToString(kernel));
      o.kernel = kernel;
      const MatchResult r = MatchGuided(predictions, kps_a, DescriptorView::FromMat(desc_a), kps_b,
                                        grid, DescriptorView::FromMat(desc_b), o);
      int differing = 0;
      for (int i = 0; i < n; ++i) {
        differing += r.outcomes[i] != outcome[i];
        if (r.outcomes[i] != outcome[i]) {
          ADD_FAILURE() << "query " << i << ": matcher " << ToString(r.outcomes[i])
                        << ", reference " << ToString(outcome[i]);
        }
      }
      EXPECT_EQ(differing, 0) << "rivals_all " << rivals_all << " mutual " << mutual;
      ASSERT_EQ(r.matches.size(), expected_matches.size());
      for (size_t k = 0; k < r.matches.size(); ++k) {
        const Match& mt = r.matches[k];
        const int i = expected_matches[k];
        EXPECT_EQ(mt.query_idx, i);
        EXPECT_EQ(mt.train_idx, best_of[i]);
        EXPECT_NEAR(mt.distance, std::sqrt(best_cost[i]), 1e-4);
        if (second_cost[i] < 1e300) {
          EXPECT_NEAR(mt.second_distance, std::sqrt(second_cost[i]), 1e-4);
        }
      }
      // Every consistent candidate's distance is computed; an inconsistent rival's only when the
      // best passes the ratio against the runner-up and the threshold, where it decides.
      EXPECT_EQ(r.stats.distances_computed, expected_distances);
      // The case is not trivial: many candidates per window, all outcomes present.
      EXPECT_GT(r.stats.distances_computed, 3 * n);
      EXPECT_GT(r.stats.points_scanned, 10 * n);
      EXPECT_GT(r.stats.matched, n / 4);
      EXPECT_GT(r.stats.ratio_test + r.stats.distance_threshold, n / 20);
      EXPECT_EQ(r.stats.mutual > 0, mutual);
    }
  }
}

TEST(GuidedMatcherTest, CheckAndInputValidation) {
  GuidedMatcherOptions o;
  EXPECT_NO_THROW(o.Check());
  o.ratio = 0.0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = GuidedMatcherOptions();
  o.grid_cell_size = 0.0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  const SyntheticPair s = MakePair(10, 0, kTrueMotion, Motion(kTrueMotion), 10);
  GridIndex grid;
  grid.Build(s.kps_b, 640, 480, 24.0f);
  std::vector<KeypointPrediction> too_few(3);
  EXPECT_THROW(MatchGuided(too_few, s.kps_a, DescriptorView::FromMat(s.desc_a), s.kps_b, grid,
                           DescriptorView::FromMat(s.desc_b), GuidedMatcherOptions()),
               InvalidArgument);
  // A window that is not finite (a caller's own predictions) is refused, not indexed.
  std::vector<KeypointPrediction> nan_window =
      PredictKeypoints(s.camera, s.motion, s.kps_a, s.depth_a, PredictionOptions());
  ASSERT_EQ(nan_window[4].status, PredictionStatus::kWithDepth);
  nan_window[4].min_x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(MatchGuided(nan_window, s.kps_a, DescriptorView::FromMat(s.desc_a), s.kps_b, grid,
                           DescriptorView::FromMat(s.desc_b), GuidedMatcherOptions()),
               InvalidArgument);
  // cv adapter end to end: depth image in metres.
  std::vector<cv::KeyPoint> ka, kb;
  for (const auto& k : s.kps_a) ka.emplace_back(k.x, k.y, 7.0f);
  for (const auto& k : s.kps_b) kb.emplace_back(k.x, k.y, 7.0f);
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(0.0f));
  for (size_t i = 0; i < ka.size(); ++i) {
    depth.at<float>(static_cast<int>(std::lround(ka[i].pt.y)),
                    static_cast<int>(std::lround(ka[i].pt.x))) = s.depth_a[i];
  }
  const MatchResult r = MatchFramesGuided(s.camera, s.motion, ka, s.desc_a, depth, kb, s.desc_b,
                                          PredictionOptions(), GuidedMatcherOptions());
  EXPECT_EQ(r.stats.predicted_with_depth, 10);
  EXPECT_EQ(r.stats.matched, 10);
  for (const Match& m : r.matches) EXPECT_EQ(m.train_idx, s.partner[m.query_idx]);
  // A depth image of another size than the camera's would be read at the wrong pixels: refused.
  EXPECT_THROW(MatchFramesGuided(s.camera, s.motion, ka, s.desc_a, depth(cv::Rect(0, 0, 320, 240)),
                                 kb, s.desc_b, PredictionOptions(), GuidedMatcherOptions()),
               InvalidArgument);
}

}  // namespace
}  // namespace imumatch
