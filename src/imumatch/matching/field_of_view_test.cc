#include "imumatch/matching/field_of_view.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/so3.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {
namespace {

TEST(FieldOfView, MaskHoldsThePixelsWithin80DegOfTheAxis) {
  const PinholeCamera cam = PinholeCamera::TumViCam0();
  const cv::Mat mask = FieldOfViewMask(cam);
  ASSERT_EQ(mask.size(), cv::Size(512, 512));
  ASSERT_EQ(mask.type(), CV_8UC1);
  // Against the lens model's own forward map: a pixel is in the mask when the ray at 80 deg in
  // its direction lands farther from the centre (on the normalised distorted plane) than it.
  const double edge = cam.EquidistantRadius(PinholeCamera::kMaxFieldAngleDeg * kDegToRad);
  int inside = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const double r = std::hypot((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy);
      ASSERT_EQ(mask.at<uint8_t>(v, u), r <= edge ? 255 : 0) << u << "," << v;
      inside += r <= edge;
    }
  }
  // The field's disc (radius 1.3961 x 1.0002 x 191 = 267 px) cut by the 512 px square: about 85 %.
  EXPECT_NEAR(inside / (512.0 * 512.0), 0.85, 0.03);
  EXPECT_EQ(mask.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(mask.at<uint8_t>(256, 256), 255);
  // Cameras whose whole image is in the field need no mask.
  EXPECT_TRUE(FieldOfViewMask(PinholeCamera::EurocCam0()).empty());
  EXPECT_TRUE(FieldOfViewMask(PinholeCamera::KinectDefault()).empty());
}

TEST(FieldOfView, KeypointsBeyondTheFieldHaveNoIdealPositionAndNoPrediction) {
  const PinholeCamera cam = PinholeCamera::TumViCam0();
  const PixelUndistorter undistorter(cam);
  // Centre, inside near the edge of the field (70 deg), a corner (beyond 100 deg) and a point
  // between 80 and 90 deg (whose ideal pixel would exist but is not matched).
  const double r70 = cam.EquidistantRadius(70.0 * kDegToRad) * cam.fx;
  const double r85 = cam.EquidistantRadius(85.0 * kDegToRad) * cam.fx;
  const std::vector<cv::KeyPoint> keypoints = {
      cv::KeyPoint(256.0f, 256.0f, 7.0f),
      cv::KeyPoint(static_cast<float>(cam.cx + r70 * 0.6), static_cast<float>(cam.cy - r70 * 0.8),
                   7.0f),
      cv::KeyPoint(2.0f, 3.0f, 7.0f),
      cv::KeyPoint(static_cast<float>(cam.cx - r85 * 0.8), static_cast<float>(cam.cy + r85 * 0.6),
                   7.0f)};
  const std::vector<KeypointInfo> ideal = ToIdealKeypointInfos(keypoints, undistorter);
  ASSERT_EQ(ideal.size(), 4u);
  EXPECT_TRUE(std::isfinite(ideal[0].x) && std::isfinite(ideal[1].y));
  // The keypoint at 70 deg: its ideal pixel is the model's (float rounding at 500 px), its ray
  // 70 deg off the axis.
  const Eigen::Vector2d want =
      cam.PixelToIdeal(Eigen::Vector2d(keypoints[1].pt.x, keypoints[1].pt.y));
  EXPECT_NEAR(ideal[1].x, want.x(), 1e-3);
  EXPECT_NEAR(ideal[1].y, want.y(), 1e-3);
  EXPECT_NEAR(std::atan(cam.IdealToNormalized(want).norm()) / kDegToRad, 70.0, 0.01);
  EXPECT_TRUE(std::isnan(ideal[2].x) && std::isnan(ideal[2].y));
  EXPECT_TRUE(std::isnan(ideal[3].x) && std::isnan(ideal[3].y));
  // The predictor gives them no window.
  CameraMotion motion;
  motion.cam_b_from_cam_a = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.01, 0, 0));
  motion.covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-8;
  const KeypointPredictor predictor(undistorter, motion, PredictionOptions());
  std::vector<KeypointPrediction> predictions;
  PredictKeypoints(predictor, ideal, {}, &predictions);
  ASSERT_EQ(predictions.size(), 4u);
  EXPECT_TRUE(predictions[0].HasWindow());
  EXPECT_TRUE(predictions[1].HasWindow());
  EXPECT_EQ(predictions[2].status, PredictionStatus::kInvalid);
  EXPECT_EQ(predictions[3].status, PredictionStatus::kInvalid);
}

}  // namespace
}  // namespace imumatch
