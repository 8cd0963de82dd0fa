#include "imumatch/camera/pixel_undistorter.h"

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "imumatch/camera/camera_test_util.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

TEST(PinholeCamera, DistortionJacobianMatchesFiniteDifferences) {
  for (const PinholeCamera& cam : {PinholeCamera::EurocCam0(), PinholeCamera::TumFreiburg1(),
                                   testing::EquidistantTestCamera()}) {
    for (const Eigen::Vector2d& xy :
         {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(0.6, -0.4), Eigen::Vector2d(-0.8, 0.5)}) {
      Eigen::Matrix2d j;
      cam.DistortNormalized(xy, &j);
      const double h = 1e-6;
      for (int k = 0; k < 2; ++k) {
        const Eigen::Vector2d e = h * Eigen::Vector2d::Unit(k);
        const Eigen::Vector2d numeric =
            (cam.DistortNormalized(xy + e) - cam.DistortNormalized(xy - e)) / (2 * h);
        EXPECT_LT((j.col(k) - numeric).norm(), 1e-7) << xy.transpose();
      }
    }
  }
}

TEST(PixelUndistorter, AgreesWithTheForwardModelEverywhereInTheImage) {
  for (const PinholeCamera& cam : {PinholeCamera::EurocCam0(), testing::EquidistantTestCamera()}) {
    SCOPED_TRACE(ToString(cam.model));
    const PixelUndistorter undistorter(cam);
    EXPECT_FALSE(undistorter.identity());
    double worst = 0.0;
    for (double v = -0.5; v <= 479.5; v += 3.7) {
      for (double u = -0.5; u <= 751.5; u += 4.3) {
        const Eigen::Vector2d uv(u, v);
        Eigen::Matrix2d jac;
        const Eigen::Vector2d ideal = undistorter.ToIdeal(uv, &jac);
        // The independent truth: the closed-form distortion model maps the result back onto uv.
        worst = std::max(worst, (cam.IdealToPixel(ideal) - uv).norm());
        ASSERT_TRUE(undistorter.camera().IsInside(uv));
        // The Jacobian against central differences of the exact (iterative) inverse. ToIdeal takes
        // it at the table's start, not at the solution: within 0.2 % of its size for EuRoC's
        // lens, 0.4 % at this equidistant lens's corners (it maps noise, not positions).
        if (std::fmod(u, 40.0) < 4.3 && std::fmod(v, 40.0) < 3.7) {
          const double h = 1e-3;
          for (int k = 0; k < 2; ++k) {
            const Eigen::Vector2d e = h * Eigen::Vector2d::Unit(k);
            const Eigen::Vector2d numeric =
                (cam.PixelToIdeal(uv + e) - cam.PixelToIdeal(uv - e)) / (2 * h);
            EXPECT_LT((jac.col(k) - numeric).norm(), 4e-3 * numeric.norm()) << uv.transpose();
          }
        }
      }
    }
    EXPECT_LT(worst, 1e-5);
    // A barrel lens: the corners of the image reach further out in ideal pixels than the image.
    EXPECT_LT(undistorter.ideal_min_x(), -0.5 - 20.0);
    EXPECT_GT(undistorter.ideal_max_x(), 751.5 + 20.0);
    const Eigen::Vector2d corner = cam.PixelToIdeal(Eigen::Vector2d(-0.5, -0.5));
    EXPECT_NEAR(undistorter.ideal_min_x(), std::min(corner.x(), undistorter.ideal_min_x()), 1e-9);
    // Outside the table: the iterative inverse, still exact.
    const Eigen::Vector2d outside(-5.0, 490.0);
    EXPECT_LT((cam.IdealToPixel(undistorter.ToIdeal(outside)) - outside).norm(), 1e-6);
    EXPECT_LT((undistorter.ToImage(undistorter.ToIdeal(outside)) - outside).norm(), 1e-6);
  }
}

TEST(PixelUndistorter, InPlaceBatchEqualsToIdealOnEveryPath) {
  using Path = PixelUndistorter::Path;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const PinholeCamera& cam : {PinholeCamera::EurocCam0(), PinholeCamera::TumFreiburg1(),
                                   testing::EquidistantTestCamera()}) {
    const PixelUndistorter undistorter(cam);
    // Points inside the image (a lattice that crosses the 64-point runs), a few outside the
    // table (beyond the image, the iterative inverse) and NaN.
    std::vector<Eigen::Vector2f> points;
    for (float v = -0.5f; v < cam.height; v += 13.3f) {
      for (float u = -0.5f; u < cam.width; u += 11.7f) points.emplace_back(u, v);
    }
    points.insert(points.begin() + 70, Eigen::Vector2f(-5.0f, 10.0f));
    points.insert(points.begin() + 130, Eigen::Vector2f(cam.width + 3.0f, 200.0f));
    points.insert(points.begin() + 131, Eigen::Vector2f(nan, 20.0f));
    points.emplace_back(cam.width - 0.5f, cam.height - 0.5f);  // the last table node's edge
    for (Path path : {Path::kAuto, Path::kPortable, Path::kAvx2, Path::kAvx512}) {
      if (!PixelUndistorter::Supported(path)) continue;
      for (int stride : {2, 5}) {
        std::vector<float> xy(points.size() * stride, -7.0f);
        for (size_t i = 0; i < points.size(); ++i) {
          xy[i * stride] = points[i].x();
          xy[i * stride + 1] = points[i].y();
        }
        undistorter.ToIdealInPlace(xy.data(), static_cast<int>(points.size()), stride, path);
        for (size_t i = 0; i < points.size(); ++i) {
          const Eigen::Vector2d want = undistorter.ToIdeal(points[i].cast<double>());
          const Eigen::Vector2d got(xy[i * stride], xy[i * stride + 1]);
          if (!want.allFinite()) {
            EXPECT_FALSE(got.allFinite()) << i;
            continue;
          }
          // Both in double, rounded to float: equal to a float's rounding (1 ulp near 800 px).
          ASSERT_LT((got - want).cwiseAbs().maxCoeff(), 1.2e-4) << points[i].transpose();
          // And the independent truth: the forward model maps it back (float rounding again).
          ASSERT_LT((cam.IdealToPixel(got) - points[i].cast<double>()).norm(), 2e-4);
          for (int k = 2; k < stride; ++k) EXPECT_EQ(xy[i * stride + k], -7.0f);  // untouched
        }
      }
    }
  }
  // Without distortion nothing moves.
  const PixelUndistorter identity(PinholeCamera::KinectDefault());
  float xy[2] = {12.25f, 400.5f};
  identity.ToIdealInPlace(xy, 1, 2);
  EXPECT_EQ(xy[0], 12.25f);
  EXPECT_EQ(xy[1], 400.5f);
}

TEST(PixelUndistorter, AFisheyeWiderThanTheFieldMapsEveryPixelInsideIt) {
  // TUM-VI's lens: the corners lie 108 deg off-axis, the field of view ends at 80 deg.
  const PinholeCamera cam = PinholeCamera::TumViCam0();
  ASSERT_TRUE(cam.WiderThanField());
  const PixelUndistorter undistorter(cam);
  const double field_tan = std::tan(PinholeCamera::kMaxFieldAngleDeg * kDegToRad);
  std::vector<Eigen::Vector2f> in_field;
  int outside = 0;
  for (float v = -0.5f; v < cam.height; v += 3.1f) {
    for (float u = -0.5f; u < cam.width; u += 2.9f) {
      const Eigen::Vector2d uv(u, v);
      if (!cam.InField(uv)) {
        ++outside;
        continue;
      }
      in_field.emplace_back(u, v);
      const Eigen::Vector2d ideal = undistorter.ToIdeal(uv);
      // The independent truth: the forward model maps it back; the ray is within 80 deg.
      ASSERT_LT((cam.IdealToPixel(ideal) - uv).norm(), 1e-5) << uv.transpose();
      const Eigen::Vector2d xy = cam.IdealToNormalized(ideal);
      ASSERT_LE(xy.norm(), field_tan * (1.0 + 1e-9)) << uv.transpose();
      // Inside the bounds the matcher's grid and noise table cover.
      ASSERT_GE(ideal.x(), undistorter.ideal_min_x() - 1e-6);
      ASSERT_LE(ideal.x(), undistorter.ideal_max_x() + 1e-6);
      ASSERT_GE(ideal.y(), undistorter.ideal_min_y() - 1e-6);
      ASSERT_LE(ideal.y(), undistorter.ideal_max_y() + 1e-6);
    }
  }
  EXPECT_GT(outside, 1000);  // the four corners
  // The bounds are the field's, not infinite: within 5.67 focal lengths (tan 80 deg) of the
  // centre, and beyond 5.2 (where the field's circle crosses the image's edges, 16 deg off the
  // axes: 5.67 cos 16 deg = 5.45).
  for (const double reach : {undistorter.ideal_max_x() - cam.cx, cam.cx - undistorter.ideal_min_x(),
                             (undistorter.ideal_max_y() - cam.cy) * cam.fx / cam.fy,
                             (cam.cy - undistorter.ideal_min_y()) * cam.fx / cam.fy}) {
    EXPECT_LE(reach, field_tan * cam.fx + 1e-6);
    EXPECT_GT(reach, 5.2 * cam.fx);
  }
  // The batch equals the one-by-one map on every path, up to the field's edge.
  for (const auto path : {PixelUndistorter::Path::kAuto, PixelUndistorter::Path::kPortable}) {
    std::vector<float> xy;
    for (const Eigen::Vector2f& p : in_field) xy.insert(xy.end(), {p.x(), p.y()});
    undistorter.ToIdealInPlace(xy.data(), static_cast<int>(in_field.size()), 2, path);
    for (size_t i = 0; i < in_field.size(); ++i) {
      const Eigen::Vector2d want = undistorter.ToIdeal(in_field[i].cast<double>());
      // Float rounding of positions up to about 1300 px from the centre.
      ASSERT_LT((Eigen::Vector2d(xy[2 * i], xy[2 * i + 1]) - want).cwiseAbs().maxCoeff(), 3e-4)
          << in_field[i].transpose();
    }
  }
}

TEST(PixelUndistorter, IsTheIdentityWithoutDistortion) {
  const PixelUndistorter undistorter(PinholeCamera::KinectDefault());
  EXPECT_TRUE(undistorter.identity());
  Eigen::Matrix2d jac;
  const Eigen::Vector2d uv(12.25, 400.5);
  EXPECT_EQ(undistorter.ToIdeal(uv, &jac), uv);
  EXPECT_TRUE(jac.isIdentity());
  EXPECT_EQ(undistorter.ideal_max_x(), 639.5);
  EXPECT_EQ(undistorter.ideal_min_y(), -0.5);
}

TEST(PinholeCamera, IdealFromPixelJacobianStretchesTheCornersOfABarrelLens) {
  const PinholeCamera cam = PinholeCamera::EurocCam0();
  // Centre: no stretch. Corner: a barrel lens squeezes the periphery, so one image pixel covers
  // more than one ideal pixel radially.
  EXPECT_TRUE(cam.IdealFromPixelJacobian(Eigen::Vector2d(cam.cx, cam.cy))
                  .isApprox(Eigen::Matrix2d::Identity(), 1e-12));
  const Eigen::Matrix2d corner = cam.IdealFromPixelJacobian(cam.PixelToIdeal({5.0, 5.0}));
  EXPECT_GT(corner.determinant(), 1.3);
}

}  // namespace
}  // namespace imumatch
