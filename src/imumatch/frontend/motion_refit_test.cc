#include "imumatch/frontend/motion_refit.h"

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/frontend/motion_refit_test_util.h"

namespace imumatch {
namespace {

using namespace refit_test;  // NOLINT(build/namespaces)

// What the second pass needs of a fit: the truth inside its covariance (chi-square, 6 dof,
// 99.9 %: 22.46), and every axis's sigma below `shrink` times the prior's.
void ExpectTruthInsideAndTighter(const MotionRefit& r, const Eigen::Matrix<double, 6, 1>& sigma,
                                 double shrink) {
  EXPECT_LT(SquaredMahalanobis(r.motion, TrueMotion()), 22.46);
  for (int k = 0; k < 6; ++k) {
    EXPECT_LT(std::sqrt(r.motion.covariance(k, k)), shrink * sigma[k]) << "axis " << k;
  }
}

TEST(MotionRefitTest, WithDepthTheFitHoldsTheTruthAndIsFarTighterThanTheIMU) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 300, 0.5, 0.15);
  const PixelUndistorter und(Camera());
  // An IMU prediction 2 sigma off on every axis (0.1 deg, 1 cm sigmas).
  const Eigen::Matrix<double, 6, 1> sigma = Vec6(2e-3, 2e-3, 2e-3, 0.01, 0.01, 0.01);
  const CameraMotion prior = Prior(2.0 * sigma.cwiseProduct(Vec6(1, -1, 1, -1, 1, 1)), sigma);
  const MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                    PredictionOptions(), und, MotionRefitOptions());
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_EQ(r.correspondences, 300);
  EXPECT_EQ(r.with_depth, 300);
  // 85 % inliers; the outliers start 3 px away, some land within 3 sigma.
  EXPECT_GT(r.inliers, 250);
  EXPECT_LT(r.inliers, 280);
  EXPECT_NEAR(r.sigma_px, 0.5 * 1.08, 0.15);  // robust sigma of 0.5 px noise (plus a few outliers)
  // The fit far tighter than the prior on every axis.
  ExpectTruthInsideAndTighter(r, sigma, 0.25);
  // The prior was 6.9e-3 rad and 3.5 cm off.
  EXPECT_LT(RotationDistance(r.motion.cam_b_from_cam_a.rotation, TrueMotion().rotation), 5e-4);
  EXPECT_LT((r.motion.cam_b_from_cam_a.translation - TrueMotion().translation).norm(), 3e-3);
  // The prior was 2 sigma off on 6 axes: squared distance 24 from where the fit lands.
  EXPECT_NEAR(r.mahalanobis2, 24.0, 3.0);
}

TEST(MotionRefitTest, WithoutDepthTheDirectionIsFittedAndTheLengthStaysTheIMUs) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 300, 0.5, 0.15);
  const PixelUndistorter und(Camera());
  const Eigen::Vector3d t = TrueMotion().translation;
  const Eigen::Vector3d dir = t.normalized();
  // Rotation 1 sigma off (the gyro is good), translation 2 cm sideways (2 sigma) and 1 cm long.
  const Eigen::Vector3d side = dir.cross(Eigen::Vector3d::UnitY()).normalized();
  const Eigen::Matrix<double, 6, 1> sigma = Vec6(2e-4, 2e-4, 2e-4, 0.01, 0.01, 0.01);
  Eigen::Matrix<double, 6, 1> offset = Vec6(2e-4, -2e-4, 0.0, 0, 0, 0);
  offset.tail<3>() = 0.02 * side + 0.01 * dir;
  const CameraMotion prior = Prior(offset, sigma);
  const MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, {},
                                    PredictionOptions(), und, MotionRefitOptions());
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_EQ(r.with_depth, 0);
  const Eigen::Vector3d got = r.motion.cam_b_from_cam_a.translation;
  const double prior_angle = std::acos(prior.cam_b_from_cam_a.translation.normalized().dot(dir));
  const double angle = std::acos(std::min(1.0, got.normalized().dot(dir)));
  EXPECT_GT(prior_angle, 0.18);
  EXPECT_LT(angle, 0.02);  // 10.6 deg off -> under 1.2 deg
  // The length is not seen by epipolar distances: it stays the prior's (to the 1 cm it was off).
  EXPECT_NEAR(got.norm(), prior.cam_b_from_cam_a.translation.norm(), 2e-3);
  // Across the translation the covariance shrank; along it, it stayed the prior's 1 cm.
  const Eigen::Matrix3d ct = r.motion.covariance.bottomRightCorner<3, 3>();
  const Eigen::Vector3d gdir = got.normalized();
  const Eigen::Vector3d across = gdir.cross(Eigen::Vector3d::UnitX()).normalized();
  EXPECT_NEAR(std::sqrt(gdir.dot(ct * gdir)), 0.01, 1e-3);
  EXPECT_LT(std::sqrt(across.dot(ct * across)), 1e-3);
}

// A first pass on a hard pair (MH_05 at take-off: 35 % judged false).
TEST(MotionRefitTest, AThirdOfTheMatchesWrongStillGivesTheTruth) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 400, 0.5, 0.35, 9);
  const PixelUndistorter und(Camera());
  const Eigen::Matrix<double, 6, 1> sigma = Vec6(2e-3, 2e-3, 2e-3, 0.01, 0.01, 0.01);
  const CameraMotion prior = Prior(sigma, sigma);
  const MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                    PredictionOptions(), und, MotionRefitOptions());
  ASSERT_TRUE(r.ok) << r.reason;
  // A third of wrong matches costs precision, not the truth.
  ExpectTruthInsideAndTighter(r, sigma, 0.5);
  // The prior was 3.5e-3 rad and 1.7 cm off.
  EXPECT_LT(RotationDistance(r.motion.cam_b_from_cam_a.rotation, TrueMotion().rotation), 1e-3);
  EXPECT_LT((r.motion.cam_b_from_cam_a.translation - TrueMotion().translation).norm(), 5e-3);
}

TEST(MotionRefitTest, AFitFarOutsideThePriorIsRefused) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 300, 0.5, 0.0);
  const PixelUndistorter und(Camera());
  // A prior sure to 1 mm / 0.006 deg but 3 cm off: the images disagree, the prior stands.
  const Eigen::Matrix<double, 6, 1> sigma = Vec6(1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3);
  const CameraMotion prior = Prior(Vec6(0, 0, 0, 0.03, 0.0, 0.0), sigma);
  const MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                    PredictionOptions(), und, MotionRefitOptions());
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.reason.find("disagrees"), std::string::npos) << r.reason;
  EXPECT_GT(r.mahalanobis2, 34.0);  // chi-square 6 dof at 0.9999: 33.1 (its gate: 27.86 at 0.9999?)
  EXPECT_EQ(r.motion.cam_b_from_cam_a.translation, prior.cam_b_from_cam_a.translation);
  EXPECT_EQ(r.motion.covariance, prior.covariance);
}

// The chi-square quantiles of 6 degrees of freedom (tables: 22.458 at 0.999, 27.856 at 0.9999,
// 12.592 at 0.95), and a probability outside (0, 1) refused.
TEST(MotionRefitTest, TheAgreementGateIsTheChiSquareQuantileOfSixDof) {
  EXPECT_NEAR(MotionAgreementGate(0.999), 22.458, 2e-3);
  EXPECT_NEAR(MotionAgreementGate(0.9999), 27.856, 2e-3);
  EXPECT_NEAR(MotionAgreementGate(0.95), 12.592, 2e-3);
  EXPECT_THROW(MotionAgreementGate(1.0), InvalidArgument);
  EXPECT_THROW(MotionAgreementGate(0.0), InvalidArgument);
}

TEST(MotionRefitTest, AnExactPriorStaysExact) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 200, 0.5, 0.1);
  const PixelUndistorter und(Camera());
  CameraMotion prior;
  prior.cam_b_from_cam_a = TrueMotion();  // zero covariance: the ground truth
  const MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                    PredictionOptions(), und, MotionRefitOptions());
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_LT(RotationDistance(r.motion.cam_b_from_cam_a.rotation, TrueMotion().rotation), 1e-7);
  EXPECT_LT((r.motion.cam_b_from_cam_a.translation - TrueMotion().translation).norm(), 1e-7);
  EXPECT_LT(r.motion.covariance.diagonal().maxCoeff(), 1.1e-12);
}

TEST(MotionRefitTest, TooFewMatchesAndBadInput) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 8, 0.5, 0.0);
  const PixelUndistorter und(Camera());
  const Eigen::Matrix<double, 6, 1> sigma = Vec6(2e-3, 2e-3, 2e-3, 0.01, 0.01, 0.01);
  const CameraMotion prior = Prior(sigma, sigma);
  const MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                    PredictionOptions(), und, MotionRefitOptions());
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.reason.find("too few"), std::string::npos) << r.reason;
  std::vector<Match> bad = s.matches;
  bad[0].query_idx = 99;
  EXPECT_THROW(RefitMotion(prior, bad, s.keypoints_a, s.keypoints_b, s.depths, PredictionOptions(),
                           und, MotionRefitOptions()),
               InvalidArgument);
  EXPECT_THROW(RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, {1.0f, 2.0f},
                           PredictionOptions(), und, MotionRefitOptions()),
               InvalidArgument);
  MotionRefitOptions o;
  o.agreement_probability = 1.0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = MotionRefitOptions();
  o.min_inliers = 5;
  EXPECT_THROW(o.Check(), InvalidArgument);
}

// Residuals of 3 px where the keypoints promise 1 px: the motion does not explain the matches
// (here: B's positions scattered), and the IMU's windows stand.
TEST(MotionRefitTest, ResidualsBeyondTheKeypointsNoiseAreRefused) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 300, 3.0, 0.0);
  const PixelUndistorter und(Camera());
  const Eigen::Matrix<double, 6, 1> sigma = Vec6(2e-3, 2e-3, 2e-3, 0.01, 0.01, 0.01);
  const CameraMotion prior = Prior(sigma, sigma);
  const MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                    PredictionOptions(), und, MotionRefitOptions());
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.disagrees);
  EXPECT_GT(r.sigma_px, 2.5);
  EXPECT_NE(r.reason.find("beyond the keypoints' noise"), std::string::npos) << r.reason;
  // Keypoints of 3 px localisation noise: the same fit is the one to use.
  PredictionOptions noisy;
  noisy.keypoint_sigma_px = 3.0;
  EXPECT_TRUE(RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths, noisy, und,
                          MotionRefitOptions())
                  .ok);
}

// A drone lifting off (EuRoC MH_05, frames 11 -> 12): 5.8 mm of translation, mostly up, and the
// IMU's translation 5 mm off, 45 degrees off in direction. Most points are far (8-12 m: 0.3 px
// of parallax), a quarter lie on the ground 0.3-0.8 m away at the bottom of the image (4-9 px);
// none has depth; a fifth of the matches are wrong by 3-15 px (a first pass at take-off). From
// the prior's direction the fit often settles in a wrong minimum and claims to be sure of it, or
// fails; with the second start from pairs of matches it holds more often and is right more often.
// Over 40 scenes.
TEST(MotionRefitTest, AtTakeOffAPriorFarOffInDirectionIsCorrected) {
  const PinholeCamera c = Camera();
  const PixelUndistorter und(c);
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(-0.0078, 0.0003, -0.0003)),
                      Eigen::Vector3d(0.0005, 0.0050, -0.0028));
  const Eigen::Vector3d t_true = truth.translation;
  CameraMotion prior;
  prior.cam_b_from_cam_a = Rigid3d(truth.rotation, Eigen::Vector3d(-0.0036, 0.0032, -0.0053));
  prior.covariance = Vec6(3e-4, 3e-4, 3e-4, 2.5e-3, 2.5e-3, 2.5e-3).cwiseAbs2().asDiagonal();
  ASSERT_GT(std::acos(prior.cam_b_from_cam_a.translation.normalized().dot(t_true.normalized())),
            0.75);  // 45 deg
  MotionRefitOptions one_start;
  one_start.direction_hypotheses = 0;
  // Per scene: the fit holds and the truth lies outside its 99.9 % ellipsoid (chi-square, 6 dof):
  // its windows would miss true partners. And the direction's error of the fits that hold.
  struct Tally {
    int confident_and_wrong = 0, held = 0;
    double angle_sum = 0.0;
  } with, without;
  auto tally = [&](const MotionRefit& r, Tally* t) {
    if (!r.ok) return;
    ++t->held;
    const Eigen::Vector3d got = r.motion.cam_b_from_cam_a.translation;
    t->angle_sum += std::acos(std::min(1.0, got.normalized().dot(t_true.normalized())));
    t->confident_and_wrong += SquaredMahalanobis(r.motion, truth) > 22.46 ? 1 : 0;
  };
  constexpr int kScenes = 40;
  for (int scene = 0; scene < kScenes; ++scene) {
    std::mt19937_64 rng(static_cast<uint64_t>(100 + scene));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 0.8);
    std::vector<cv::KeyPoint> ka, kb;
    std::vector<Match> matches;
    while (matches.size() < 200) {
      const bool near = matches.size() % 4 == 0;
      const Eigen::Vector2d uv(20 + 600 * u(rng), near ? 300 + 160 * u(rng) : 20 + 440 * u(rng));
      const double z = near ? 0.3 + 0.5 * u(rng) : 8.0 + 4.0 * u(rng);
      const Eigen::Vector3d q = truth * c.Unproject(uv, z);
      Eigen::Vector2d pb(c.fx * q.x() / q.z() + c.cx + gauss(rng),
                         c.fy * q.y() / q.z() + c.cy + gauss(rng));
      if (u(rng) < 0.2) {
        const double a = 2.0 * M_PI * u(rng), d = 3.0 + 12.0 * u(rng);
        pb += d * Eigen::Vector2d(std::cos(a), std::sin(a));
      }
      if (pb.x() < 0 || pb.x() >= c.width || pb.y() < 0 || pb.y() >= c.height) continue;
      AddMatch(uv, pb, &ka, &kb, &matches);
    }
    tally(RefitMotion(prior, matches, ka, kb, {}, PredictionOptions(), und, MotionRefitOptions()),
          &with);
    tally(RefitMotion(prior, matches, ka, kb, {}, PredictionOptions(), und, one_start), &without);
  }
  std::printf(
      "of %d scenes: fits held %d -> %d, sure and wrong %d -> %d, mean direction error "
      "%.1f -> %.1f deg\n",
      kScenes, without.held, with.held, without.confident_and_wrong, with.confident_and_wrong,
      without.angle_sum / std::max(1, without.held) * 180 / M_PI,
      with.angle_sum / std::max(1, with.held) * 180 / M_PI);
  // Measured: held 32 -> 39, sure and wrong 22 of 32 -> 7 of 39, direction error 25.6 -> 8.4
  // deg (before the epipolar rows' translation information was bounded, max_dedt2 in
  // motion_refit.cc: 23 -> 39, 21 of 23 -> 8 of 39, 38.6 -> 7.9 deg; before the rows beyond the
  // inliers lost their weight, reject_beyond_inliers: 24 -> 39, 23 of 24 -> 17 of 39, 40.7 ->
  // 11.1 deg). A fifth of the fits still claim too much certainty: a known limit.
  ASSERT_GT(without.held, 0);
  ASSERT_GT(with.held, 0);
  EXPECT_GT(with.held, without.held);
  EXPECT_GE(with.held, kScenes * 9 / 10);
  EXPECT_LT(static_cast<double>(with.confident_and_wrong) / with.held,
            0.6 * without.confident_and_wrong / without.held);
  EXPECT_LT(with.angle_sum / with.held, 0.5 * without.angle_sum / without.held);
  EXPECT_LE(with.confident_and_wrong, with.held * 3 / 10);  // 17 of 39 without the rejection

  MotionRefitOptions bad;
  bad.direction_hypotheses = -1;
  EXPECT_THROW(bad.Check(), InvalidArgument);
}
}  // namespace
}  // namespace imumatch

namespace imumatch {
namespace {

// A turn on the spot (a translation of 0.1 mm, far below the IMU's 3 mm uncertainty) seen by
// keypoints without depth: every epipolar row's line passes near the epipole, and its derivative
// by the translation grows as 1 / |t|. Linearised as they are, those rows claimed to know the
// translation to a micrometre across its direction; each may now tell the translation no more
// than a point at the nearest depth the predictions consider (f / segment_min_depth per px).
// The exact truth then lies inside the fit's 99.9 % ellipsoid (chi-square, 6 dof) in every
// scene (squared Mahalanobis median 9, at most 20); before the bound, in 17 of 20 (31, 82 and
// 13922 outside).
TEST(MotionRefitTest, ATurnOnTheSpotWithoutDepthKeepsTheTruthInsideTheFitsCovariance) {
  const PinholeCamera c = Camera();
  const PixelUndistorter und(c);
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.002, 0.012, -0.001)),
                      Eigen::Vector3d(0.8e-4, -0.3e-4, 0.5e-4));
  int inside = 0, held = 0;
  constexpr int kScenes = 20;
  for (int scene = 0; scene < kScenes; ++scene) {
    std::mt19937_64 rng(static_cast<uint64_t>(500 + scene));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 0.7);
    std::vector<cv::KeyPoint> ka, kb;
    std::vector<Match> matches;
    while (matches.size() < 300) {
      const Eigen::Vector2d uv(20 + 600 * u(rng), 20 + 440 * u(rng));
      const Eigen::Vector3d q = truth * c.Unproject(uv, 1.0 + 6.0 * u(rng));
      const Eigen::Vector2d pb(c.fx * q.x() / q.z() + c.cx + gauss(rng),
                               c.fy * q.y() / q.z() + c.cy + gauss(rng));
      if (pb.x() < 0 || pb.x() >= c.width || pb.y() < 0 || pb.y() >= c.height) continue;
      AddMatch(uv, pb, &ka, &kb, &matches);
    }
    // The IMU: rotation good to 0.05 deg, translation to 3 mm (0.05 m/s over 1/20 s), drawn.
    std::normal_distribution<double> unit(0.0, 1.0);
    const Eigen::Vector3d dtheta(0.9e-3 * unit(rng), 0.9e-3 * unit(rng), 0.9e-3 * unit(rng));
    const Eigen::Vector3d dt(3e-3 * unit(rng), 3e-3 * unit(rng), 3e-3 * unit(rng));
    CameraMotion prior;
    prior.cam_b_from_cam_a = Rigid3d(ExpSO3(dtheta) * truth.rotation, truth.translation + dt);
    prior.covariance = Vec6(0.9e-3, 0.9e-3, 0.9e-3, 3e-3, 3e-3, 3e-3).cwiseAbs2().asDiagonal();
    const MotionRefit r =
        RefitMotion(prior, matches, ka, kb, {}, PredictionOptions(), und, MotionRefitOptions());
    if (!r.ok) continue;
    ++held;
    inside += SquaredMahalanobis(r.motion, truth) <= 22.46 ? 1 : 0;
  }
  std::printf("of %d scenes: fits held %d, truth inside the 99.9 %% ellipsoid %d\n", kScenes, held,
              inside);
  EXPECT_GE(held, kScenes * 3 / 4);
  EXPECT_GE(inside, held - 1);
}

// Why the rotation is measured from the final matches (MeasureRotationFromMatches): a first pass
// searches windows around the prior's prediction, here a prior 4 mrad off in rotation (2.1 px,
// about what a camera clock 10 ms off gives in a drone's turns) with 1.5 px boxes. A keypoint whose
// true partner lies outside its box is matched, half the time, to a look-alike near the
// prediction. The rotation measured from those matches leans towards the prior's; from the
// final matches (the true partners, as a second pass in the fit's windows finds them) it does not:
// the mean error along the prior's offset within 3 standard errors of zero, the covariance
// calibrated (mean chi-square, 3 dof, within 1.5-4.5), and the prior's rotation not used. 40
// scenes without depth (MH_05's frames mostly have none).
TEST(MotionRefitTest, TheFirstPassLeansTowardsThePriorAndTheFinalMatchesDoNot) {
  const PinholeCamera c = Camera();
  const PixelUndistorter und(c);
  const Eigen::Vector3d offset_in_cam(2.3e-3, -2.3e-3, 2.3e-3);  // 4 mrad
  const Eigen::Vector3d dir = offset_in_cam.normalized();
  Eigen::Matrix<double, 6, 1> offset = Eigen::Matrix<double, 6, 1>::Zero();
  offset.head<3>() = offset_in_cam;
  const CameraMotion prior = Prior(offset, Vec6(3e-3, 3e-3, 3e-3, 0.01, 0.01, 0.01));
  MotionRefitOptions measuring;
  measuring.measure_rotation = true;
  const int n = 40;
  double first_along = 0.0, along = 0.0, along2 = 0.0, chi2 = 0.0;
  int measured = 0;
  for (int k = 0; k < n; ++k) {
    const MatchScene s = MakeMatchScene(TrueMotion(), 300, 0.5, 0.0, 500 + k);
    std::mt19937_64 rng(900 + k);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 0.5);
    // The first pass: the true partner when it lies in the box around the prior's prediction,
    // else half the time a look-alike near the prediction (a new keypoint of B).
    std::vector<cv::KeyPoint> kb = s.keypoints_b;
    std::vector<Match> first;
    for (const Match& m : s.matches) {
      const cv::Point2f& pa = s.keypoints_a[static_cast<size_t>(m.query_idx)].pt;
      const Eigen::Vector3d q =
          prior.cam_b_from_cam_a * c.Unproject(Eigen::Vector2d(pa.x, pa.y), s.depths[m.query_idx]);
      const Eigen::Vector2d predicted(c.fx * q.x() / q.z() + c.cx, c.fy * q.y() / q.z() + c.cy);
      const cv::Point2f& pb = s.keypoints_b[static_cast<size_t>(m.train_idx)].pt;
      if (std::fabs(pb.x - predicted.x()) <= 1.5 && std::fabs(pb.y - predicted.y()) <= 1.5) {
        first.push_back(m);
      } else if (u(rng) < 0.5) {
        Match wrong = m;
        wrong.train_idx = static_cast<int>(kb.size());
        kb.emplace_back(static_cast<float>(predicted.x() + gauss(rng)),
                        static_cast<float>(predicted.y() + gauss(rng)), 7.0f);
        first.push_back(wrong);
      }
    }
    MotionRefit r =
        RefitMotion(prior, first, s.keypoints_a, kb, {}, PredictionOptions(), und, measuring);
    ASSERT_TRUE(r.ok) << r.reason;
    ASSERT_TRUE(r.rotation_from_matches_ok);
    first_along += LogSO3(r.rotation_from_matches * TrueMotion().rotation.conjugate()).dot(dir);
    MeasureRotationFromMatches(prior, s.matches, s.keypoints_a, s.keypoints_b, {},
                               PredictionOptions(), und, measuring, &r);
    if (!r.rotation_from_matches_ok) continue;
    ++measured;
    const Eigen::Vector3d e = LogSO3(r.rotation_from_matches * TrueMotion().rotation.conjugate());
    chi2 += e.dot(r.rotation_from_matches_covariance.ldlt().solve(e));
    along += e.dot(dir);
    along2 += e.dot(dir) * e.dot(dir);
  }
  ASSERT_EQ(measured, n);
  first_along /= n;
  along /= n;
  chi2 /= n;
  const double standard_error = std::sqrt((along2 / n - along * along) / n);
  std::printf(
      "along the prior's offset of %.1e rad: first pass %.2e, final %.2e (standard error "
      "%.1e), mean chi-square %.2f\n",
      offset_in_cam.norm(), first_along, along, standard_error, chi2);
  EXPECT_GT(first_along, 5.0 * standard_error);
  EXPECT_LT(std::fabs(along), 3.0 * standard_error);
  EXPECT_GT(chi2, 1.5);
  EXPECT_LT(chi2, 4.5);
}

// What is not measured: a fit that does not hold, fewer matches than min_inliers; a measurement
// of an earlier call does not survive either.
TEST(MotionRefitTest, MeasureRotationFromMatchesNeedsAFitAndEnoughMatches) {
  const MatchScene s = MakeMatchScene(TrueMotion(), 200, 0.5, 0.0);
  const PixelUndistorter und(Camera());
  const CameraMotion prior =
      Prior(Eigen::Matrix<double, 6, 1>::Zero(), Vec6(3e-3, 3e-3, 3e-3, 0.01, 0.01, 0.01));
  MotionRefitOptions measuring;
  measuring.measure_rotation = true;
  MotionRefit r = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                              PredictionOptions(), und, measuring);
  ASSERT_TRUE(r.ok && r.rotation_from_matches_ok) << r.reason;
  const std::vector<Match> few(s.matches.begin(), s.matches.begin() + measuring.min_inliers - 1);
  MeasureRotationFromMatches(prior, few, s.keypoints_a, s.keypoints_b, s.depths,
                             PredictionOptions(), und, measuring, &r);
  EXPECT_FALSE(r.rotation_from_matches_ok);
  MotionRefit failed = r;
  failed.ok = false;
  MeasureRotationFromMatches(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                             PredictionOptions(), und, measuring, &failed);
  EXPECT_FALSE(failed.rotation_from_matches_ok);
  MeasureRotationFromMatches(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                             PredictionOptions(), und, measuring, &r);
  ASSERT_TRUE(r.rotation_from_matches_ok);
  EXPECT_LT(RotationDistance(r.rotation_from_matches, TrueMotion().rotation), 1e-3);
  // A match outside the keypoints is an error, not a crash.
  std::vector<Match> bad = s.matches;
  bad[3].query_idx = 100000;
  EXPECT_THROW(MeasureRotationFromMatches(prior, bad, s.keypoints_a, s.keypoints_b, s.depths,
                                          PredictionOptions(), und, measuring, &r),
               InvalidArgument);
}

// A fit's rotation as an observation of the camera's clock offset: the measurement between the
// given camera times; left out when its covariance is not positive definite (a degenerate fit)
// or the times are not in order, so one such fit cannot fail a whole estimate.
// The take-off of EuRoC MH_05 in miniature: the scene's readings far away (8-12 m, where a 2.4 cm
// translation moves a point by about 1 px), and 14 corners along the top edge of a beam 0.6 m
// away, above which the depth image has no reading (the background it occludes). Those corners
// move with the background, 20 m away, but read the beam's depth: their leverage on the
// translation's length is 20 times a far point's. The fit given every reading is pulled to a
// wrong length with a tight covariance; with the readings near the depth image's edges cleared
// (ClearDepthsNearEdges, as the callers do) it holds the truth.
TEST(MotionRefitTest, DepthsReadAcrossAnOcclusionEdgeNoLongerSetTheTranslationsLength) {
  const PinholeCamera c = Camera();
  const Rigid3d truth(ExpSO3(Eigen::Vector3d(0.002, -0.004, 0.001)),
                      Eigen::Vector3d(0.002, 0.022, -0.011));
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 0.3);
  cv::Mat depth(c.height, c.width, CV_16UC1, cv::Scalar(0));  // 1000 units per metre
  MatchScene s;
  auto add = [&](const Eigen::Vector2d& uv, double z_true, double z_read) {
    const Eigen::Vector3d q = truth * c.Unproject(uv, z_true);
    const Eigen::Vector2d pb(c.fx * q.x() / q.z() + c.cx + gauss(rng),
                             c.fy * q.y() / q.z() + c.cy + gauss(rng));
    Match m;
    m.query_idx = m.train_idx = static_cast<int>(s.matches.size());
    s.keypoints_a.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 7.0f);
    s.keypoints_b.emplace_back(static_cast<float>(pb.x()), static_cast<float>(pb.y()), 7.0f);
    s.matches.push_back(m);
    s.depths.push_back(static_cast<float>(z_read));
  };
  // Far points on a jittered 15 x 10 grid over the upper 2/3 of the image, each on its own
  // 15 x 15 patch of its reading.
  for (int i = 0; i < 150; ++i) {
    const Eigen::Vector2d uv(40 + 38 * (i % 15) + 10 * (u(rng) - 0.5),
                             30 + 27 * (i / 15) + 10 * (u(rng) - 0.5));
    const double z = 8.0 + 4.0 * u(rng);
    const int x = static_cast<int>(std::lround(uv.x())), y = static_cast<int>(std::lround(uv.y()));
    depth(cv::Rect(x - 7, y - 7, 15, 15)).setTo(static_cast<int>(std::lround(z * 1000.0)));
    add(uv, z, static_cast<double>(depth.at<uint16_t>(y, x)) / 1000.0);
  }
  // The beam: rows 400-479 at 0.6 m, its top edge at row 400, holes above; corners on row 401.
  depth.rowRange(400, c.height).setTo(600);
  const size_t first_corner = s.matches.size();
  for (int i = 0; i < 14; ++i) add(Eigen::Vector2d(60.0 + 38.0 * i, 401.0), 20.0, 0.6);
  const std::vector<float> sampled =
      SampleDepths(depth, 1000.0, s.keypoints_a, DepthSampling::kNearest);
  for (size_t i = 0; i < sampled.size(); ++i) {
    ASSERT_NEAR(sampled[i], s.depths[i], 1e-3) << i;
  }

  const PixelUndistorter und(c);
  CameraMotion prior;  // the IMU: 8 mm short, 0.1 deg and 8 mm sigmas
  prior.cam_b_from_cam_a = Rigid3d(truth.rotation, truth.translation * (16.0 / 24.6));
  prior.covariance = Vec6(2e-3, 2e-3, 2e-3, 8e-3, 8e-3, 8e-3).cwiseAbs2().asDiagonal();
  auto truth_m2 = [&](const MotionRefit& r) { return SquaredMahalanobis(r.motion, truth); };
  const MotionRefit pulled = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, s.depths,
                                         PredictionOptions(), und, MotionRefitOptions());
  ASSERT_TRUE(pulled.ok) << pulled.reason;
  EXPECT_GT(truth_m2(pulled), 100.0);  // the truth far outside the fit's covariance

  std::vector<float> cleared = s.depths;
  EXPECT_EQ(ClearDepthsNearEdges(depth, 1000.0, s.keypoints_a, DepthEdgeOptions(), &cleared), 14);
  for (size_t i = first_corner; i < cleared.size(); ++i) EXPECT_TRUE(std::isnan(cleared[i]));
  const MotionRefit fit = RefitMotion(prior, s.matches, s.keypoints_a, s.keypoints_b, cleared,
                                      PredictionOptions(), und, MotionRefitOptions());
  ASSERT_TRUE(fit.ok) << fit.reason;
  EXPECT_EQ(fit.with_depth, 150);
  EXPECT_LT(truth_m2(fit), 22.46);  // chi-square, 6 dof, 99.9 %
  std::printf("translation error: every reading %.1f mm, edges cleared %.1f mm\n",
              1e3 * (pulled.motion.cam_b_from_cam_a.translation - truth.translation).norm(),
              1e3 * (fit.motion.cam_b_from_cam_a.translation - truth.translation).norm());
}

}  // namespace
}  // namespace imumatch
