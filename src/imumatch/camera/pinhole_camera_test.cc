#include "imumatch/camera/pinhole_camera.h"

#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/camera/camera_test_util.h"
#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

TEST(PinholeCamera, ProjectsHandComputedPoint) {
  const PinholeCamera cam = PinholeCamera::KinectDefault();
  // x = (u - cx) z / fx: the point (0.5, -0.25, 2) lands at u = 525*0.25+319.5, v =
  // -525*0.125+239.5.
  const auto uv = cam.Project(Eigen::Vector3d(0.5, -0.25, 2.0));
  ASSERT_TRUE(uv.has_value());
  EXPECT_NEAR(uv->x(), 450.75, 1e-12);
  EXPECT_NEAR(uv->y(), 173.875, 1e-12);
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(0, 0, -1)).has_value());
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(0, 0, 0)).has_value());
}

TEST(PinholeCamera, UnprojectRoundTripWithDepthScale) {
  const PinholeCamera cam = PinholeCamera::KinectDefault();
  const double depth = cam.DepthFromRaw(6000);  // TUM: 6000 / 5000 = 1.2 m
  EXPECT_DOUBLE_EQ(depth, 1.2);
  EXPECT_TRUE(std::isnan(cam.DepthFromRaw(0)));
  const Eigen::Vector2d uv(100.25, 400.75);
  const Eigen::Vector3d p = cam.Unproject(uv, depth);
  EXPECT_NEAR(p.z(), 1.2, 1e-15);
  EXPECT_NEAR(p.x(), (100.25 - 319.5) * 1.2 / 525.0, 1e-12);
  EXPECT_LT((*cam.Project(p) - uv).norm(), 1e-10);
}

TEST(PinholeCamera, DistortedRoundTrip) {
  const PinholeCamera cam = PinholeCamera::TumFreiburg1();
  for (double u = 0; u < 640; u += 79.5) {
    for (double v = 0; v < 480; v += 59.5) {
      const Eigen::Vector2d uv(u, v);
      const Eigen::Vector3d p = cam.Unproject(uv, 2.0);
      EXPECT_LT((*cam.Project(p) - uv).norm(), 1e-6) << u << "," << v;
    }
  }
  // Distortion moves off-centre points: the undistorted bearing differs from the linear one.
  const Eigen::Vector2d corner(10, 10);
  const Eigen::Vector2d linear((10 - cam.cx) / cam.fx, (10 - cam.cy) / cam.fy);
  EXPECT_GT((cam.PixelToNormalized(corner) - linear).norm(), 1e-3);
}

TEST(PinholeCamera, PixelCentreConvention) {
  PinholeCamera cam;
  cam.width = 4;
  cam.height = 3;
  EXPECT_TRUE(cam.IsInside(Eigen::Vector2d(-0.5, -0.5)));
  EXPECT_FALSE(cam.IsInside(Eigen::Vector2d(-0.51, 0)));
  EXPECT_TRUE(cam.IsInside(Eigen::Vector2d(3.49, 2.49)));
  EXPECT_FALSE(cam.IsInside(Eigen::Vector2d(3.5, 1)));
  EXPECT_FALSE(cam.IsInside(Eigen::Vector2d(1, 1), 1.6));
}

TEST(PinholeCamera, ScaledToWidthKeepsTheImageEdges) {
  const PinholeCamera big = PinholeCamera::TumFreiburg1();
  const PinholeCamera half = PinholeCamera::KinectDefault().ScaledToWidth(320);
  // Hand values: Kinect 640x480 (525, 319.5, 239.5) halved.
  EXPECT_EQ(half.width, 320);
  EXPECT_EQ(half.height, 240);
  EXPECT_DOUBLE_EQ(half.fx, 262.5);
  EXPECT_DOUBLE_EQ(half.cx, 159.5);
  EXPECT_DOUBLE_EQ(half.cy, 119.5);
  // The outer edges of the image (pixel corners at -0.5 and width - 0.5) see the same bearings in
  // the resized image, with distortion kept.
  const PinholeCamera small = big.ScaledToWidth(160);
  ASSERT_EQ(small.height, 120);
  for (const auto& [u, v, us, vs] : {std::array<double, 4>{-0.5, -0.5, -0.5, -0.5},
                                     std::array<double, 4>{639.5, 479.5, 159.5, 119.5},
                                     std::array<double, 4>{319.5, 239.5, 79.5, 59.5}}) {
    const Eigen::Vector2d a = big.PixelToNormalized(Eigen::Vector2d(u, v));
    const Eigen::Vector2d b = small.PixelToNormalized(Eigen::Vector2d(us, vs));
    EXPECT_LT((a - b).norm(), 1e-9) << u << " " << v;
  }
  EXPECT_THROW(big.ScaledToWidth(0), InvalidArgument);
}

// Kannala-Brandt by hand: a ray at theta = 45 deg (the point (1, 0) on the z=1 plane) lands at
// radius theta (1 + k1 theta^2) = (pi/4)(1 + 0.1 pi^2/16) = 0.83384547071 on the normalised plane;
// off-axis points keep their direction (r = 0.5, theta = atan 0.5, with k2 = -0.02 too).
TEST(PinholeCamera, EquidistantMapsTheRayAngleToTheRadius) {
  PinholeCamera cam;
  cam.model = DistortionModel::kEquidistant;
  cam.distortion = {0.1, 0.0, 0.0, 0.0, 0.0};
  EXPECT_TRUE(cam.HasDistortion());
  EXPECT_NEAR(cam.DistortNormalized(Eigen::Vector2d(1.0, 0.0)).x(), 0.8338454707104168, 1e-14);
  EXPECT_NEAR(cam.DistortNormalized(Eigen::Vector2d(1.0, 0.0)).y(), 0.0, 1e-15);
  cam.distortion = {0.1, -0.02, 0.0, 0.0, 0.0};
  const Eigen::Vector2d d = cam.DistortNormalized(Eigen::Vector2d(0.3, 0.4));
  EXPECT_NEAR(d.x(), 0.28391164868131097, 1e-14);
  EXPECT_NEAR(d.y(), 0.37854886490841466, 1e-14);
  // All coefficients zero is still a lens (theta, not tan theta): 45 deg at radius pi/4.
  cam.distortion = {0, 0, 0, 0, 0};
  EXPECT_TRUE(cam.HasDistortion());
  EXPECT_NEAR(cam.DistortNormalized(Eigen::Vector2d(0.0, -1.0)).y(), -0.7853981633974483, 1e-15);
  // On the axis: the identity.
  EXPECT_EQ(cam.DistortNormalized(Eigen::Vector2d(0.0, 0.0)), Eigen::Vector2d(0.0, 0.0));
}

// Pixel -> ray -> pixel over the whole image of a strong equidistant lens (corners near 60 deg).
TEST(PinholeCamera, EquidistantRoundTrip) {
  const PinholeCamera cam = testing::EquidistantTestCamera();
  cam.Check();
  const double k1 = cam.distortion[0], k2 = cam.distortion[1], k3 = cam.distortion[2],
               k4 = cam.distortion[3];
  double worst = 0.0;
  for (double v = -0.5; v <= 479.5; v += 23.9) {
    for (double u = -0.5; u <= 751.5; u += 18.7) {
      const Eigen::Vector2d uv(u, v);
      const Eigen::Vector2d xy = cam.PixelToNormalized(uv);
      ASSERT_TRUE(xy.allFinite()) << uv.transpose();
      worst = std::max(worst, (cam.NormalizedToPixel(xy) - uv).norm());
      // The ray's angle is the model's inverse: radius(theta) = |normalised distorted point|.
      const double theta = std::atan(xy.norm());
      const double radius = std::hypot((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy);
      const double t2 = theta * theta;
      EXPECT_NEAR(theta * (1 + k1 * t2 + k2 * t2 * t2 + k3 * t2 * t2 * t2 + k4 * t2 * t2 * t2 * t2),
                  radius, 1e-12);
    }
  }
  EXPECT_LT(worst, 1e-9);
  // And 3-D: a point projected and unprojected with its depth.
  const Eigen::Vector3d p(-1.2, 0.7, 1.5);
  const auto uv = cam.Project(p);
  ASSERT_TRUE(uv.has_value());
  EXPECT_LT((cam.Unproject(*uv, 1.5) - p).norm(), 1e-9);
}

TEST(PinholeCamera, EquidistantCheckRefusesAFoldingLensAndBoundsAFisheyesField) {
  PinholeCamera cam = testing::EquidistantTestCamera();
  cam.distortion = {0, 0, 0, 0, 0};
  EXPECT_NO_THROW(cam.Check());
  EXPECT_FALSE(cam.WiderThanField());
  // A fisheye: corners sqrt(376^2 + 240^2) / 150 = 2.97 rad (170 deg) from the axis. Accepted;
  // its field of view ends at 80 deg, radius 80 pi / 180 = 1.396 (x 150 px) from the centre.
  PinholeCamera wide = cam;
  wide.fx = wide.fy = 150.0;
  EXPECT_NO_THROW(wide.Check());
  EXPECT_TRUE(wide.WiderThanField());
  const double edge_px = 150.0 * 80.0 * kDegToRad;
  EXPECT_TRUE(wide.InField(Eigen::Vector2d(370.0, 245.0)));
  EXPECT_TRUE(wide.InField(Eigen::Vector2d(370.0 + edge_px * 0.999, 245.0)));
  EXPECT_FALSE(wide.InField(Eigen::Vector2d(370.0 + edge_px * 1.001, 245.0)));
  EXPECT_TRUE(wide.InField(Eigen::Vector2d(370.0, 245.0 - edge_px * 0.999)));
  EXPECT_FALSE(wide.InField(Eigen::Vector2d(-0.5, -0.5)));
  EXPECT_TRUE(cam.InField(Eigen::Vector2d(-0.5, -0.5)));
  // k1 = -0.5: theta - 0.5 theta^3 stops growing at theta = 47 deg (radius 0.54), short of the
  // corners' radius 1.18; and for the fisheye, short of the field's edge.
  PinholeCamera folding = cam;
  folding.distortion = {-0.5, 0.0, 0.0, 0.0, 0.0};
  EXPECT_THROW(folding.Check(), InvalidArgument);
  folding.fx = folding.fy = 150.0;
  EXPECT_THROW(folding.Check(), InvalidArgument);
  // k1 = -0.1515: theta (1 + k1 theta^2) grows up to 85 deg and folds back beyond: accepted, as
  // the field ends at 80 deg, where the radius (0.9839) is already above the one at 90 deg
  // (0.9836). A ray at 79 deg (radius 0.9817, below both) must come back from its pixel as
  // itself, not as its fold beyond 80 deg.
  PinholeCamera folds_beyond = wide;
  folds_beyond.distortion = {-0.1515, 0.0, 0.0, 0.0, 0.0};
  EXPECT_NO_THROW(folds_beyond.Check());
  const double theta = 79.0 * kDegToRad;
  const Eigen::Vector2d ray = std::tan(theta) * Eigen::Vector2d(0.6, 0.8);
  const Eigen::Vector2d back = folds_beyond.PixelToNormalized(folds_beyond.NormalizedToPixel(ray));
  EXPECT_NEAR((back - ray).norm() / ray.norm(), 0.0, 1e-9) << back.transpose();
  // Four coefficients only.
  PinholeCamera five = cam;
  five.distortion = {0.0, 0.0, 0.0, 0.0, 0.01};
  EXPECT_THROW(five.Check(), InvalidArgument);
  // Beyond 90 deg no ray of the z=1 plane lands: NaN, not a folded point.
  PinholeCamera beyond = cam;
  beyond.width = 100;
  beyond.height = 100;
  beyond.cx = beyond.cy = 49.5;
  beyond.Check();
  EXPECT_FALSE(beyond.PixelToNormalized(Eigen::Vector2d(49.5 + 380.0 * 1.7, 49.5)).allFinite());
  EXPECT_TRUE(beyond.PixelToNormalized(Eigen::Vector2d(49.5 + 380.0 * 1.5, 49.5)).allFinite());
}

TEST(PinholeCamera, ParsesTextIntrinsics) {
  const PinholeCamera c =
      ParseCameraFromText("# TUM fr1\n\n517.3 516.5 318.6 255.3 640 480\n", "x");
  EXPECT_DOUBLE_EQ(c.fx, 517.3);
  EXPECT_DOUBLE_EQ(c.cy, 255.3);
  EXPECT_EQ(c.width, 640);
  EXPECT_FALSE(c.HasDistortion());
  const PinholeCamera d =
      ParseCameraFromText("500 500 320 240 640 480 0.1 -0.2 0.001 0.002 0.05", "x");
  EXPECT_DOUBLE_EQ(d.distortion[4], 0.05);
  EXPECT_EQ(d.model, DistortionModel::kRadialTangential);
  const PinholeCamera e =
      ParseCameraFromText("equidistant 380 380 370 245 752 480 -0.02 0.01 -0.004 0.0005", "x");
  EXPECT_EQ(e.model, DistortionModel::kEquidistant);
  EXPECT_DOUBLE_EQ(e.distortion[3], 0.0005);
  EXPECT_NE(e.ToString().find("equidistant d=[-0.02 0.01 -0.004 0.0005]"), std::string::npos)
      << e.ToString();
  // An equidistant lens needs its size and all four coefficients; a fifth is refused.
  EXPECT_THROW(ParseCameraFromText("equidistant 380 380 370 245", "x"), InputError);
  EXPECT_THROW(ParseCameraFromText("equidistant 380 380 370 245 752 480 0 0 0 0 0", "x"),
               InputError);
  // The calibration tools' aliases name the same models (Kalibr "equi", OpenCV "fisheye").
  EXPECT_EQ(
      ParseCameraFromText("fisheye 380 380 370 245 752 480 -0.02 0.01 -0.004 0.0005", "x").model,
      DistortionModel::kEquidistant);
  EXPECT_EQ(ParseCameraFromText("plumb_bob 380 380 370 245 752 480 -0.2", "x").model,
            DistortionModel::kRadialTangential);
  // A fisheye is read (its field of view ends at 80 deg); a lens that folds back before it
  // cannot be used: the error names the line.
  EXPECT_TRUE(
      ParseCameraFromText("equidistant 150 150 370 245 752 480 0 0 0 0", "x").WiderThanField());
  try {
    ParseCameraFromText("\nequidistant 150 150 370 245 752 480 -0.5 0 0 0", "cam.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& err) {
    EXPECT_EQ(err.line(), 2);
    EXPECT_NE(std::string(err.what()).find("stops growing"), std::string::npos) << err.what();
  }
}

TEST(PinholeCamera, TextErrorsNameFileAndLine) {
  try {
    ParseCameraFromText("# header\n517.3 516.5 318.6\n", "intr.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("intr.txt:2:"), std::string::npos);
  }
  EXPECT_THROW(ParseCameraFromText("517 516 318 nan", "x"), InputError);
  EXPECT_THROW(ParseCameraFromText("-5 516 318 255", "x"), InputError);
  EXPECT_THROW(ParseCameraFromText("", "x"), InputError);
  EXPECT_THROW(ReadCameraFromText("/nonexistent/intrinsics.txt"), InputError);
}

TEST(PinholeCameraTest, DistortionModelNames) {
  for (const char* name : {"radial-tangential", "radtan", "plumb_bob"}) {
    EXPECT_EQ(DistortionModelFromName(name), DistortionModel::kRadialTangential) << name;
  }
  for (const char* name : {"equidistant", "equi", "fisheye"}) {
    EXPECT_EQ(DistortionModelFromName(name), DistortionModel::kEquidistant) << name;
  }
  for (const char* name : {"", "Equidistant", "kb4", "radial", "pinhole"}) {
    EXPECT_FALSE(DistortionModelFromName(name).has_value()) << name;
  }
  // ToString's names read back as their models.
  for (const DistortionModel m :
       {DistortionModel::kRadialTangential, DistortionModel::kEquidistant}) {
    EXPECT_EQ(DistortionModelFromName(ToString(m)), m);
  }
}

}  // namespace
}  // namespace imumatch
