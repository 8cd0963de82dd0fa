#include "imumatch/camera/pinhole_camera.h"

#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

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

}  // namespace
}  // namespace imumatch
