#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/rigid3.h"

namespace imumatch {

// Relative pose of camera B from correspondences with camera A (p_in_cam_b = cam_b_from_cam_a *
// p_in_cam_a). Image positions are image pixels, mapped through the lens to ideal pixels here.
struct PoseFitOptions {
  double ransac_px = 2.0;  // inlier threshold: reprojection (PnP) or epipolar distance, ideal px
  int iterations = 200;
  int min_inliers = 12;  // fewer: the fit fails
  uint64_t seed = 7;     // RANSAC sampling
  void Check() const;    // throws InvalidArgument
};

struct PoseFit {
  bool ok = false;
  Rigid3d cam_b_from_cam_a;
  int correspondences = 0;
  int inliers = 0;
  double rms_px = 0.0;               // residual of the inliers (ideal px)
  std::vector<uint8_t> inlier_mask;  // one per correspondence
  std::string reason;                // why it failed
};

// With depth: 3D points of A (camera A frame, metres) and their positions in B. RANSAC over
// OpenCV's P3P, then Levenberg-Marquardt on the inliers (cv::solvePnPRansac in ideal pixels),
// started from `guess` (the IMU's motion).
PoseFit FitPosePnp(const std::vector<Eigen::Vector3d>& points_a,
                   const std::vector<Eigen::Vector2d>& pixels_b,
                   const PixelUndistorter& undistorter, const Rigid3d& guess,
                   const PoseFitOptions& options);

// Without depth: the rotation is the gyro's (guess.rotation); the translation direction t solves
// t . (R x_a  x  x_b) = 0 for the inliers (two correspondences give it: a 2-point RANSAC on the
// epipolar distance), its sign by the points lying in front of both cameras, and its length is
// the guess's (the scale comes from the IMU's velocity). A guess translation under 1 mm is kept
// as is (no baseline to estimate a direction from).
PoseFit FitPoseEpipolar(const std::vector<Eigen::Vector2d>& pixels_a,
                        const std::vector<Eigen::Vector2d>& pixels_b,
                        const PixelUndistorter& undistorter, const Rigid3d& guess,
                        const PoseFitOptions& options);

}  // namespace imumatch
