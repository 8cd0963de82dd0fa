#include "imumatch/matching/predictor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

PinholeCamera TestCamera() {
  PinholeCamera c;
  c.width = 640;
  c.height = 480;
  c.fx = 500.0;
  c.fy = 480.0;
  c.cx = 320.0;
  c.cy = 240.0;
  return c;
}

CameraMotion MakeMotion(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  CameraMotion m;
  m.cam_b_from_cam_a = Rigid3d(q, t);
  return m;
}

TEST(PredictorTest, WithDepthEqualsDirectReprojection) {
  const PinholeCamera cam = TestCamera();
  const CameraMotion motion = MakeMotion(FromEulerZYX(0.02, -0.03, 0.05), {0.1, -0.05, 0.08});
  const KeypointPredictor predictor(cam, motion, PredictionOptions());
  // Hand computation for one point: pixel (400, 300) at depth 2 m.
  const Eigen::Vector3d p_a((400.0 - 320.0) / 500.0 * 2.0, (300.0 - 240.0) / 480.0 * 2.0, 2.0);
  const Eigen::Vector3d p_b = motion.cam_b_from_cam_a * p_a;
  const Eigen::Vector2d expected(500.0 * p_b.x() / p_b.z() + 320.0,
                                 480.0 * p_b.y() / p_b.z() + 240.0);
  const KeypointPrediction p = predictor.Predict({400.0, 300.0}, 2.0);
  ASSERT_EQ(p.status, PredictionStatus::kWithDepth);
  EXPECT_NEAR(p.uv.x(), expected.x(), 1e-3);
  EXPECT_NEAR(p.uv.y(), expected.y(), 1e-3);
  EXPECT_TRUE(p.Contains(p.uv.x(), p.uv.y()));
  // Zero motion covariance: the covariance is the keypoint noise of A (1 px, mapped through a
  // Jacobian close to the identity for this small motion) plus B's (1 px) plus the tiny depth
  // noise: about 2 px^2 per axis; the half sizes are sqrt(9.21 * variance) (>= the 4 px minimum).
  EXPECT_GT(p.covariance(0, 0), 1.8f);
  EXPECT_LT(p.covariance(0, 0), 2.4f);
  EXPECT_NEAR(p.max_x - p.uv.x(), std::max(4.0, std::sqrt(9.2103 * p.covariance(0, 0))), 1e-3);
  EXPECT_NEAR(p.uv.y() - p.min_y, std::max(4.0, std::sqrt(9.2103 * p.covariance(1, 1))), 1e-3);
  EXPECT_NEAR(p.scale_min, p_a.norm() / p_b.norm(), 1e-5);
}

TEST(PredictorTest, InverseDepthOfRecoversTheDepthAlongTheEpipolarLine) {
  const PinholeCamera cam = TestCamera();
  const CameraMotion motion = MakeMotion(FromEulerZYX(0.02, -0.03, 0.05), {0.1, -0.05, 0.08});
  const KeypointPredictor predictor(cam, motion, PredictionOptions());
  for (const double z : {0.3, 1.0, 2.0, 7.5, 40.0}) {
    // The point's projection in B by hand, as in the test above.
    const Eigen::Vector3d p_a((150.0 - 320.0) / 500.0 * z, (400.0 - 240.0) / 480.0 * z, z);
    const Eigen::Vector3d p_b = motion.cam_b_from_cam_a * p_a;
    const Eigen::Vector2d uv_b(500.0 * p_b.x() / p_b.z() + 320.0,
                               480.0 * p_b.y() / p_b.z() + 240.0);
    EXPECT_NEAR(predictor.InverseDepthOf({150.0, 400.0}, uv_b), 1.0 / z, 1e-9) << z;
  }
  // The point at infinity (the rotation-only prediction) has rho 0; a position beyond it along
  // the line, a negative rho.
  const Eigen::Vector2d inf_b = predictor.RotationOnly({150.0, 400.0});
  EXPECT_NEAR(predictor.InverseDepthOf({150.0, 400.0}, inf_b), 0.0, 1e-9);
  const Eigen::Vector2d near_b = predictor.Predict({150.0, 400.0}, 1.0).uv.cast<double>();
  EXPECT_LT(predictor.InverseDepthOf({150.0, 400.0}, inf_b + (inf_b - near_b)), 0.0);
  // Without translation the depth is not observable.
  const KeypointPredictor pure_rotation(
      cam, MakeMotion(FromEulerZYX(0.02, -0.03, 0.05), Eigen::Vector3d::Zero()),
      PredictionOptions());
  EXPECT_TRUE(std::isnan(pure_rotation.InverseDepthOf({150.0, 400.0}, {160.0, 390.0})));
}

TEST(PredictorTest, BehindCameraAndOutsideImageAreReported) {
  const PinholeCamera cam = TestCamera();
  // B is 3 m in front of A looking the same way: a point at 2 m ends up behind B.
  const KeypointPredictor forward(cam, MakeMotion(Eigen::Quaterniond::Identity(), {0, 0, -3.0}),
                                  PredictionOptions());
  EXPECT_EQ(forward.Predict({320, 240}, 2.0).status, PredictionStatus::kBehindCamera);
  // Sideways motion of 1 m at 2 m depth moves the point 250 px: out of the image.
  const KeypointPredictor side(cam, MakeMotion(Eigen::Quaterniond::Identity(), {-1.0, 0, 0}),
                               PredictionOptions());
  const KeypointPrediction p = side.Predict({200, 240}, 2.0);
  EXPECT_EQ(p.status, PredictionStatus::kOutsideImage);
  EXPECT_NEAR(p.uv.x(), 200.0 - 250.0, 1e-3);
  EXPECT_FALSE(p.HasWindow());
  EXPECT_EQ(side.Predict({std::nan(""), 240}, 2.0).status, PredictionStatus::kInvalid);
  PredictionOptions no_segment;
  no_segment.predict_without_depth = false;
  EXPECT_EQ(
      KeypointPredictor(cam, MakeMotion(Eigen::Quaterniond::Identity(), {0, 0, 0}), no_segment)
          .Predict({100, 100}, 0.0)
          .status,
      PredictionStatus::kInvalid);
}

TEST(PredictorTest, RotationOnlyIsTheInfiniteHomography) {
  const PinholeCamera cam = TestCamera();
  const double a = 5.0 * M_PI / 180.0;
  // Rotation about the camera's y axis by 5 degrees (R = Ry(a)), no translation.
  const Eigen::Quaterniond q(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()));
  const KeypointPredictor predictor(cam, MakeMotion(q, Eigen::Vector3d::Zero()),
                                    PredictionOptions());
  // Hand check: the principal point's ray (0,0,1) becomes (sin a, 0, cos a): u = cx + fx tan a.
  const Eigen::Vector2d centre = predictor.RotationOnly({320.0, 240.0});
  EXPECT_NEAR(centre.x(), 320.0 + 500.0 * std::tan(a), 1e-9);  // 363.744...
  EXPECT_NEAR(centre.y(), 240.0, 1e-9);
  // A general point against H = K R K^-1 applied in homogeneous coordinates.
  const Eigen::Matrix3d h = predictor.InfiniteHomography();
  const Eigen::Vector3d x = h * Eigen::Vector3d(100.0, 50.0, 1.0);
  const Eigen::Vector2d rot = predictor.RotationOnly({100.0, 50.0});
  EXPECT_NEAR(rot.x(), x.x() / x.z(), 1e-9);
  EXPECT_NEAR(rot.y(), x.y() / x.z(), 1e-9);
  // Pure rotation: the prediction is independent of the depth, with or without one.
  const KeypointPrediction with_depth = predictor.Predict({100.0, 50.0}, 1.7);
  EXPECT_NEAR(with_depth.uv.x(), rot.x(), 1e-3);
  const KeypointPrediction no_depth = predictor.Predict({100.0, 50.0}, 0.0);
  ASSERT_EQ(no_depth.status, PredictionStatus::kWithoutDepth);
  EXPECT_NEAR(no_depth.uv.x(), rot.x(), 1e-3);
  EXPECT_NEAR((no_depth.segment_end - no_depth.segment_start).norm(), 0.0, 1e-3);
  // In-plane rotation: roll about the optical axis by 10 degrees rotates the image by 10 degrees
  // (x toward y, the sense of cv::KeyPoint::angle in image coordinates).
  const Eigen::Quaterniond roll(Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()));
  PinholeCamera square = cam;
  square.fy = square.fx;
  const KeypointPredictor rolled(square, MakeMotion(roll, Eigen::Vector3d::Zero()),
                                 PredictionOptions());
  EXPECT_NEAR(rolled.Predict({320, 240}, 2.0).angle_change_deg, 10.0, 1e-4);
  EXPECT_NEAR(rolled.Predict({500, 100}, 2.0).angle_change_deg, 10.0, 1e-4);
}

// A camera that only turns (a roll about its optical axis, exactly known: zero covariance) and
// keypoints without depth: each epipolar segment is one point, and the window is the keypoints'
// noise alone, isotropic. Its largest eigenvalue once came out NaN for some keypoints (the
// covariance's off-diagonal terms differed in sign in their last bits), which made MatchGuided
// read outside its arrays.
TEST(PredictorTest, PureRotationWithoutDepthGivesFiniteWindowsAroundTheTruth) {
  PinholeCamera vga = TestCamera();
  vga.fy = vga.fx;
  PinholeCamera small;  // the camera of the case that failed
  small.width = 320;
  small.height = 240;
  small.fx = small.fy = 300.0;
  small.cx = 160.0;
  small.cy = 120.0;
  const double a = 20.0 * M_PI / 180.0;
  const Eigen::Quaterniond roll(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
  int checked = 0;
  for (const PinholeCamera& cam : {vga, small}) {
    const KeypointPredictor predictor(cam, MakeMotion(roll, Eigen::Vector3d::Zero()),
                                      PredictionOptions());
    for (const double sigma_scale : {1.0, 1.0796, 1.5}) {
      for (double v = 3.0; v < cam.height; v += 3.7) {
        for (double u = 3.0; u < cam.width; u += 3.9) {
          // Hand check: the image turns by a about the principal point.
          const Eigen::Vector2d d(u - cam.cx, v - cam.cy);
          const Eigen::Vector2d truth(cam.cx + std::cos(a) * d.x() - std::sin(a) * d.y(),
                                      cam.cy + std::sin(a) * d.x() + std::cos(a) * d.y());
          if (truth.x() < 0.0 || truth.y() < 0.0 || truth.x() > cam.width - 1.0 ||
              truth.y() > cam.height - 1.0) {
            continue;
          }
          const KeypointPrediction p = predictor.Predict({u, v}, 0.0, sigma_scale);
          ASSERT_EQ(p.status, PredictionStatus::kWithoutDepth) << u << " " << v;
          ASSERT_TRUE(std::isfinite(p.radius) && std::isfinite(p.min_x) && std::isfinite(p.max_x) &&
                      std::isfinite(p.min_y) && std::isfinite(p.max_y))
              << cam.width << " px wide, at " << u << " " << v << ": radius " << p.radius;
          EXPECT_GE(p.radius, PredictionOptions().min_half_size);
          EXPECT_NEAR(p.uv.x(), truth.x(), 1e-3);
          EXPECT_NEAR(p.uv.y(), truth.y(), 1e-3);
          EXPECT_TRUE(p.Contains(static_cast<float>(truth.x()), static_cast<float>(truth.y())));
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 30000);
}

TEST(PredictorTest, EpipolarSegmentContainsTrueProjectionForDepthsInRange) {
  const PinholeCamera cam = TestCamera();
  const CameraMotion motion = MakeMotion(FromEulerZYX(0.01, 0.02, -0.01), {0.15, 0.02, 0.05});
  PredictionOptions options;
  options.segment_min_depth = 0.5;
  options.segment_max_depth = std::numeric_limits<double>::infinity();
  const KeypointPredictor predictor(cam, motion, options);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uu(20, 620), uv(20, 460), uz(0.5, 30.0);
  int inside = 0, tested = 0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector2d pix(uu(rng), uv(rng));
    const double z = uz(rng);
    const Eigen::Vector3d p_b = motion.cam_b_from_cam_a * cam.Unproject(pix, z);
    const Eigen::Vector2d truth(500.0 * p_b.x() / p_b.z() + 320.0,
                                480.0 * p_b.y() / p_b.z() + 240.0);
    if (!cam.IsInside(truth)) continue;
    const KeypointPrediction p = predictor.Predict(pix, std::nan(""));
    ASSERT_EQ(p.status, PredictionStatus::kWithoutDepth);
    ++tested;
    // The true point lies on the segment (up to float rounding), hence in the capsule.
    EXPECT_LT(std::sqrt(p.SegmentDistanceSquared(truth.x(), truth.y())), 1e-2);
    inside += p.Contains(static_cast<float>(truth.x()), static_cast<float>(truth.y()));
    // A point 2 radii away from the segment, perpendicular to it, is not in the capsule.
    const Eigen::Vector2f dir = (p.segment_end - p.segment_start).normalized();
    if (dir.allFinite()) {
      const Eigen::Vector2f off =
          truth.cast<float>() + 2.0f * p.radius * Eigen::Vector2f(-dir.y(), dir.x());
      EXPECT_FALSE(p.Contains(off.x(), off.y()));
    }
    // The segment runs from the z_min end (the projection at 0.5 m, when not clipped) to the
    // rotation-only prediction (depth infinity), each moved out along the line by the gate's
    // extent along it: sqrt(9.21 d^T C d) <= sqrt(9.21 * the covariance's largest eigenvalue).
    const double out =
        std::sqrt(9.2103 * p.covariance.cast<double>().eigenvalues().real().maxCoeff());
    const Eigen::Vector3d near_b = motion.cam_b_from_cam_a * cam.Unproject(pix, 0.5);
    const Eigen::Vector2d near(500.0 * near_b.x() / near_b.z() + 320.0,
                               480.0 * near_b.y() / near_b.z() + 240.0);
    if (cam.IsInside(near)) {
      EXPECT_LT(std::sqrt(p.SegmentDistanceSquared(static_cast<float>(near.x()),
                                                   static_cast<float>(near.y()))),
                1e-2);
      EXPECT_GT((p.segment_start.cast<double>() - near).norm(), 1.0);  // moved out
      EXPECT_LT((p.segment_start.cast<double>() - near).norm(), out + 1e-2);
    }
    if (cam.IsInside(p.uv.cast<double>())) {
      EXPECT_LT(std::sqrt(p.SegmentDistanceSquared(p.uv.x(), p.uv.y())), 1e-2f);
      EXPECT_LT((p.segment_end - p.uv).norm(), out + 1e-2);
    }
  }
  EXPECT_GT(tested, 150);
  EXPECT_EQ(inside, tested);
}

// A motion whose translation is known in direction but not in length (what a fit to the images
// leaves: epipolar distances do not see the length) moves a point without depth along its epipolar
// line, not across it: the capsule stays thin and its ends move out. Checked against Monte Carlo
// draws of the motion and of the depth.
TEST(PredictorTest, CapsuleIsThinAcrossAndLongAlongWhenOnlyTheLengthIsUncertain) {
  const PinholeCamera cam = TestCamera();
  const Eigen::Vector3d t(0.1, 0.0, 0.02);
  CameraMotion motion = MakeMotion(FromEulerZYX(0.01, 0.02, -0.01), t);
  const Eigen::Vector3d dir = t.normalized();
  motion.covariance.topLeftCorner<3, 3>() = 1e-8 * Eigen::Matrix3d::Identity();  // 1e-4 rad
  motion.covariance.bottomRightCorner<3, 3>() =
      0.02 * 0.02 * dir * dir.transpose() +                                 // length: 2 cm
      1e-4 * 1e-4 * (Eigen::Matrix3d::Identity() - dir * dir.transpose());  // across: 0.1 mm
  PredictionOptions options;
  options.keypoint_sigma_px = 0.0;  // motion only
  options.min_half_size = 0.0;
  options.segment_min_depth = 1.0;
  options.segment_max_depth = std::numeric_limits<double>::infinity();
  const KeypointPredictor predictor(cam, motion, options);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uu(40, 600), uv(40, 440), urho(1.0 / 30.0, 1.0);
  std::normal_distribution<double> n01;
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(motion.covariance);
  const Eigen::Matrix<double, 6, 6> l = llt.matrixL();
  int tested = 0, inside = 0;
  double max_radius = 0.0, max_eigen_radius = 0.0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector2d pix(uu(rng), uv(rng));
    const KeypointPrediction p = predictor.Predict(pix, std::nan(""));
    if (p.status != PredictionStatus::kWithoutDepth) continue;
    max_radius = std::max(max_radius, static_cast<double>(p.radius));
    max_eigen_radius =
        std::max(max_eigen_radius,
                 std::sqrt(9.2103 * p.covariance.cast<double>().eigenvalues().real().maxCoeff()));
    for (int s = 0; s < 20; ++s) {
      Eigen::Matrix<double, 6, 1> z;
      for (int i = 0; i < 6; ++i) z[i] = n01(rng);
      const Eigen::Matrix<double, 6, 1> d = l * z;
      const Eigen::Vector3d p_b = ExpSO3(d.head<3>()) * (motion.cam_b_from_cam_a.rotation *
                                                         cam.Unproject(pix, 1.0 / urho(rng))) +
                                  t + d.tail<3>();
      const std::optional<Eigen::Vector2d> uv_b = cam.Project(p_b);
      if (!uv_b || !cam.IsInside(*uv_b)) continue;
      ++tested;
      inside += p.Contains(static_cast<float>(uv_b->x()), static_cast<float>(uv_b->y())) ? 1 : 0;
    }
  }
  ASSERT_GT(tested, 3000);
  // The gate's 99 % (the capsule holds each end's gate ellipse, so a little more).
  EXPECT_GE(static_cast<double>(inside) / tested, 0.99);
  // Across: the rotation (1e-4 rad -> 0.05 px) and 0.1 mm at 1 m (0.05 px), times 3.03.
  EXPECT_LT(max_radius, 0.6);
  // A radius from the largest eigenvalue (the length's 2 cm: up to 10 px at 1 m) would be far
  // wider.
  EXPECT_GT(max_eigen_radius, 10.0 * max_radius);

  // A length known to 1 m (a front end that has lost its velocity): the ends move out by at most
  // max_half_size, as no window reaches farther than that from its prediction.
  motion.covariance.bottomRightCorner<3, 3>() = dir * dir.transpose();
  options.max_half_size = 64.0;
  const KeypointPredictor lost(cam, motion, options);
  const Eigen::Vector2d pix(200.0, 300.0);
  const KeypointPrediction p = lost.Predict(pix, std::nan(""));
  ASSERT_EQ(p.status, PredictionStatus::kWithoutDepth);
  const KeypointPrediction exact =
      KeypointPredictor(cam, MakeMotion(motion.cam_b_from_cam_a.rotation, t), options)
          .Predict(pix, std::nan(""));
  const double moved_out =
      (p.segment_end - exact.segment_end).norm() + (p.segment_start - exact.segment_start).norm();
  EXPECT_GT(moved_out, 20.0);
  EXPECT_LE(moved_out, 2.0 * 64.0 + 1e-3);
}

// A translation whose length is uncertain by more than the length itself (a hovering or slowly
// climbing camera, whose velocity is known to a few cm/s) may point the other way: a point then
// moves beyond the rotation-only point, the far end of its segment. The near end's gate ellipse
// reaches there, and the capsule must hold it. Checked against Monte Carlo draws of the motion
// and of the depth.
TEST(PredictorTest, SegmentReachesBeyondTheRotationOnlyPointWhenTheTranslationsSignIsOpen) {
  const PinholeCamera cam = TestCamera();
  const Eigen::Vector3d t(0.0, 0.003, 0.0005);  // 3 mm, known to 5 mm along, 0.05 mm across
  CameraMotion motion = MakeMotion(FromEulerZYX(0.01, 0.0, -0.01), t);
  const Eigen::Vector3d dir = t.normalized();
  motion.covariance.topLeftCorner<3, 3>() = 1e-8 * Eigen::Matrix3d::Identity();
  motion.covariance.bottomRightCorner<3, 3>() =
      0.005 * 0.005 * dir * dir.transpose() +
      5e-5 * 5e-5 * (Eigen::Matrix3d::Identity() - dir * dir.transpose());
  PredictionOptions options;
  options.keypoint_sigma_px = 0.0;  // motion only
  options.min_half_size = 0.0;
  options.segment_min_depth = 0.3;
  const KeypointPredictor predictor(cam, motion, options);
  // 3 mm against a gate of sqrt(9.21) x 5 mm: the sign is open.
  EXPECT_TRUE(predictor.TranslationSignOpen());
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> uu(40, 600), uv(40, 440), urho(1.0 / 30.0, 1.0 / 0.3);
  std::normal_distribution<double> n01;
  const Eigen::Matrix<double, 6, 6> l =
      Eigen::LLT<Eigen::Matrix<double, 6, 6>>(motion.covariance).matrixL();
  int tested = 0, inside = 0, reversed = 0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector2d pix(uu(rng), uv(rng));
    const KeypointPrediction p = predictor.Predict(pix, std::nan(""));
    if (p.status != PredictionStatus::kWithoutDepth) continue;
    for (int s = 0; s < 20; ++s) {
      Eigen::Matrix<double, 6, 1> z;
      for (int i = 0; i < 6; ++i) z[i] = n01(rng);
      const Eigen::Matrix<double, 6, 1> d = l * z;
      const Eigen::Vector3d t_true = t + d.tail<3>();
      const Eigen::Vector3d p_b = ExpSO3(d.head<3>()) * (motion.cam_b_from_cam_a.rotation *
                                                         cam.Unproject(pix, 1.0 / urho(rng))) +
                                  t_true;
      const std::optional<Eigen::Vector2d> uv_b = cam.Project(p_b);
      if (!uv_b || !cam.IsInside(*uv_b)) continue;
      ++tested;
      reversed += t_true.dot(t) < 0.0 ? 1 : 0;
      inside += p.Contains(static_cast<float>(uv_b->x()), static_cast<float>(uv_b->y())) ? 1 : 0;
    }
  }
  ASSERT_GT(tested, 3000);
  // About a quarter of the draws move the camera the other way (P(N(3, 5) < 0) = 0.27).
  EXPECT_GT(reversed, tested / 5);
  EXPECT_GE(static_cast<double>(inside) / tested, 0.99);

  // A length known to 0.5 mm: the sign is not open, and the segment ends at the rotation-only
  // point (moved out only by the far end's own ellipse: rotation, 1e-4 rad -> 0.15 px).
  motion.covariance.bottomRightCorner<3, 3>() = 0.0005 * 0.0005 * Eigen::Matrix3d::Identity();
  const KeypointPredictor known(cam, motion, options);
  EXPECT_FALSE(known.TranslationSignOpen());
  const Eigen::Vector2d pix(200.0, 300.0);
  const KeypointPrediction p = known.Predict(pix, std::nan(""));
  ASSERT_EQ(p.status, PredictionStatus::kWithoutDepth);
  EXPECT_LT((p.segment_end.cast<double>() - known.RotationOnly(pix)).norm(), 0.5);
}

// TranslationSignOpen, by hand: 1 cm known to 5 mm along its direction is within the gate of
// zero (sqrt(9.21) x 5 mm = 15 mm), 2 cm is not; no translation, or no covariance.
TEST(PredictorTest, TranslationSignOpenWhenTheLengthIsWithinTheGateOfZero) {
  const PinholeCamera cam = TestCamera();
  PredictionOptions options;  // gate 0.99: chi2 9.21
  const auto open = [&](const Eigen::Vector3d& t, double sigma_along, double sigma_across) {
    CameraMotion m = MakeMotion(Eigen::Quaterniond::Identity(), t);
    const Eigen::Vector3d dir = t.norm() > 0.0 ? t.normalized() : Eigen::Vector3d::UnitZ();
    m.covariance.bottomRightCorner<3, 3>() =
        sigma_along * sigma_along * dir * dir.transpose() +
        sigma_across * sigma_across * (Eigen::Matrix3d::Identity() - dir * dir.transpose());
    return KeypointPredictor(cam, m, options).TranslationSignOpen();
  };
  EXPECT_TRUE(open(Eigen::Vector3d(0.0, 0.0, 0.01), 0.005, 0.0));
  EXPECT_FALSE(open(Eigen::Vector3d(0.0, 0.0, 0.02), 0.005, 0.0));
  // Only the extent along the translation counts: a wide uncertainty across it does not open it.
  EXPECT_FALSE(open(Eigen::Vector3d(0.02, 0.0, 0.0), 0.005, 1.0));
  EXPECT_TRUE(open(Eigen::Vector3d::Zero(), 0.0, 0.0));
  EXPECT_FALSE(open(Eigen::Vector3d(0.0, 0.001, 0.0), 0.0, 0.0));  // exact: known
}

TEST(PredictorTest, DistortedLensPredictsInIdealPixels) {
  // Points at random depths seen through the EuRoC lens: the truth is the camera model's own
  // projection. In ideal pixels it lies on the straight epipolar segment; in image pixels the
  // same points bend away from any straight segment by several pixels near the borders, which is
  // why the predictor and the grid work in ideal pixels.
  const PinholeCamera cam = PinholeCamera::EurocCam0();
  const PixelUndistorter undistorter(cam);
  const CameraMotion motion = MakeMotion(FromEulerZYX(0.02, 0.01, -0.015), {0.12, 0.03, 0.04});
  const KeypointPredictor predictor(undistorter, motion, PredictionOptions());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uu(5, 747), uv(5, 475), uz(0.5, 20.0);
  int tested = 0, inside = 0, off_in_image_pixels = 0;
  double worst_depth_error = 0.0;
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector2d pix_a(uu(rng), uv(rng));
    const double z = uz(rng);
    const Eigen::Vector3d p_b = motion.cam_b_from_cam_a * cam.Unproject(pix_a, z);
    const std::optional<Eigen::Vector2d> pix_b = cam.Project(p_b);
    if (!pix_b || !cam.IsInside(*pix_b)) continue;
    ++tested;
    const Eigen::Vector2d ideal_a = undistorter.ToIdeal(pix_a);
    const Eigen::Vector2d ideal_b = undistorter.ToIdeal(*pix_b);
    // With depth: the prediction is the truth (ideal pixels) and maps back onto the image point.
    const KeypointPrediction d = predictor.Predict(ideal_a, z);
    ASSERT_EQ(d.status, PredictionStatus::kWithDepth);
    worst_depth_error = std::max(worst_depth_error, (d.uv.cast<double>() - ideal_b).norm());
    EXPECT_LT((undistorter.ToImage(d.uv.cast<double>()) - *pix_b).norm(), 1e-3);
    // Without depth: the capsule holds the truth.
    const KeypointPrediction e = predictor.Predict(ideal_a, std::nan(""));
    ASSERT_EQ(e.status, PredictionStatus::kWithoutDepth);
    EXPECT_LT(std::sqrt(e.SegmentDistanceSquared(ideal_b.x(), ideal_b.y())), 1e-2);
    inside += e.Contains(static_cast<float>(ideal_b.x()), static_cast<float>(ideal_b.y()));
    // The same segment drawn between the image-pixel ends misses the image-pixel truth.
    KeypointPrediction naive = e;
    naive.segment_start = undistorter.ToImage(e.segment_start.cast<double>()).cast<float>();
    naive.segment_end = undistorter.ToImage(e.segment_end.cast<double>()).cast<float>();
    off_in_image_pixels +=
        naive.SegmentDistanceSquared(static_cast<float>(pix_b->x()),
                                     static_cast<float>(pix_b->y())) > 2.0f * 2.0f;
  }
  EXPECT_GT(tested, 250);
  EXPECT_LT(worst_depth_error, 1e-3);
  EXPECT_EQ(inside, tested);
  EXPECT_GT(off_in_image_pixels, tested / 40);  // measured: 15 of 383 more than 2 px off
}

TEST(PredictorTest, KeypointNoiseGrowsWithSizeAndTowardsTheLensBorder) {
  const PinholeCamera cam = PinholeCamera::EurocCam0();
  const PixelUndistorter undistorter(cam);
  const CameraMotion motion = MakeMotion(Eigen::Quaterniond::Identity(), {0.05, 0.0, 0.0});
  PredictionOptions options;
  const KeypointPredictor predictor(undistorter, motion, options);
  // kSize: a keypoint 4x the frame's smallest size sits on a 4 px grid: sigma^2 = 1 + 15 / 12.
  std::vector<KeypointInfo> kps(2);
  kps[0].size = 31.0f;
  kps[1].size = 124.0f;
  const float ref = ReferenceKeypointSize(kps);
  EXPECT_FLOAT_EQ(ref, 31.0f);
  EXPECT_DOUBLE_EQ(KeypointSigmaScale(options, kps[1], ref), std::sqrt(1.0 + 15.0 / 12.0));
  EXPECT_DOUBLE_EQ(KeypointSigmaScale(options, kps[0], ref), 1.0);
  // The same model on another base sigma: a 0.5 px base makes the rounding weigh 4x as much.
  EXPECT_DOUBLE_EQ(SizeSigmaFactor(124.0f, 31.0f, 0.5), std::sqrt(1.0 + 15.0 / 3.0));
  EXPECT_DOUBLE_EQ(SizeSigmaFactor(20.0f, 31.0f, 1.0), 1.0);  // below the reference: s = 1
  EXPECT_DOUBLE_EQ(SizeSigmaFactor(0.0f, 31.0f, 1.0), 1.0);   // no size
  options.sigma_scaling = KeypointSigmaScaling::kNone;
  EXPECT_DOUBLE_EQ(KeypointSigmaScale(options, kps[1], ref), 1.0);
  options.sigma_scaling = KeypointSigmaScaling::kOctave;
  options.octave_scale = 2.0;
  kps[1].octave = 3;
  EXPECT_DOUBLE_EQ(KeypointSigmaScale(options, kps[1], ref), 8.0);
  // Zero motion noise: the window is the keypoint noise of both frames, in ideal pixels. At the
  // centre it is the image-pixel sigma; near a corner a barrel lens stretches it.
  const KeypointPrediction centre =
      predictor.Predict(undistorter.ToIdeal({cam.cx, cam.cy}), 5.0, 3.0);
  EXPECT_NEAR(centre.covariance(0, 0), 2.0 * 9.0, 0.2);  // A and B, sigma 3 px each
  const KeypointPrediction corner = predictor.Predict(undistorter.ToIdeal({30.0, 30.0}), 5.0, 3.0);
  EXPECT_GT(corner.covariance.trace(), 1.3 * centre.covariance.trace());
}

TEST(PredictorTest, CovarianceMatchesMonteCarloAndSizesTheWindow) {
  const PinholeCamera cam = TestCamera();
  CameraMotion motion = MakeMotion(FromEulerZYX(0.01, 0.02, 0.03), {0.1, 0.0, 0.05});
  Eigen::Matrix<double, 6, 1> sig;
  sig << 0.004, 0.006, 0.002, 0.01, 0.02, 0.015;
  motion.covariance = sig.cwiseAbs2().asDiagonal();
  PredictionOptions options;
  options.keypoint_sigma_px = 0.0;  // motion only, so the Monte Carlo needs no pixel noise
  options.depth_noise_coeff = 0.0;
  options.min_half_size = 0.0;
  const KeypointPredictor predictor(cam, motion, options);
  const Eigen::Vector2d pix(450.0, 120.0);
  const double z = 1.5;
  const KeypointPrediction p = predictor.Predict(pix, z);
  ASSERT_EQ(p.status, PredictionStatus::kWithDepth);
  // Monte Carlo over R_true = Exp(dtheta) R, t_true = t + dt.
  std::mt19937 rng(42);
  std::normal_distribution<double> n01;
  const int samples = 20000;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  std::vector<Eigen::Vector2d> uvs(samples);
  const Eigen::Vector3d p_a = cam.Unproject(pix, z);
  for (int s = 0; s < samples; ++s) {
    Eigen::Matrix<double, 6, 1> d;
    for (int k = 0; k < 6; ++k) d[k] = sig[k] * n01(rng);
    const Eigen::Vector3d p_b = ExpSO3(d.head<3>()) * (motion.cam_b_from_cam_a.rotation * p_a) +
                                motion.cam_b_from_cam_a.translation + d.tail<3>();
    uvs[s] = *cam.Project(p_b);
    mean += uvs[s] / samples;
  }
  for (const auto& u : uvs) cov += (u - mean) * (u - mean).transpose() / (samples - 1);
  const Eigen::Matrix2d predicted = p.covariance.cast<double>();
  EXPECT_NEAR(predicted(0, 0), cov(0, 0), 0.05 * cov(0, 0));
  EXPECT_NEAR(predicted(1, 1), cov(1, 1), 0.05 * cov(1, 1));
  EXPECT_NEAR(predicted(0, 1), cov(0, 1), 0.05 * std::sqrt(cov(0, 0) * cov(1, 1)));
  // Window half sizes: sqrt(9.21 * variance).
  EXPECT_NEAR(p.max_x - p.uv.x(), std::sqrt(9.2103 * predicted(0, 0)), 1e-2);
  EXPECT_NEAR(p.max_y - p.uv.y(), std::sqrt(9.2103 * predicted(1, 1)), 1e-2);
  // Fixed mode ignores the covariance.
  options.window_mode = WindowMode::kFixed;
  const KeypointPrediction f = KeypointPredictor(cam, motion, options).Predict(pix, z);
  EXPECT_NEAR(f.max_x - f.uv.x(), 10.0f, 1e-4);
  EXPECT_NEAR(f.uv.y() - f.min_y, 10.0f, 1e-4);
}

TEST(PredictorTest, DepthNoiseFollowsKinectModel) {
  // Camera moving sideways by t: the pixel shift is fx * t / z, so sigma_u = fx t sigma_z / z^2 =
  // fx t c (independent of z for sigma_z = c z^2).
  const PinholeCamera cam = TestCamera();
  PredictionOptions options;
  options.keypoint_sigma_px = 0.0;
  options.min_half_size = 0.0;
  options.depth_noise_coeff = 0.01;
  const KeypointPredictor predictor(cam, MakeMotion(Eigen::Quaterniond::Identity(), {0.2, 0, 0}),
                                    options);
  for (double z : {1.0, 3.0}) {
    const KeypointPrediction p = predictor.Predict({320, 240}, z);
    EXPECT_NEAR(std::sqrt(p.covariance(0, 0)), 500.0 * 0.2 * 0.01, 1e-4);
    EXPECT_NEAR(p.covariance(1, 1), 0.0, 1e-9);
  }
}

TEST(PredictorTest, OptionsCheck) {
  PredictionOptions o;
  EXPECT_NO_THROW(o.Check());
  EXPECT_NEAR(o.GateChiSquare(), 9.2103, 1e-4);
  o.gate_probability = 1.0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = PredictionOptions();
  o.max_half_size = 2.0;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = PredictionOptions();
  o.segment_max_depth = 0.1;
  EXPECT_THROW(o.Check(), InvalidArgument);
  o = PredictionOptions();
  o.min_depth = -1;
  EXPECT_THROW(o.Check(), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
