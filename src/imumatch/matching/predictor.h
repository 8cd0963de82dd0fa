#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/match_types.h"

namespace imumatch {

// How the search window around a prediction is sized: from the propagated 2x2 pixel covariance
// (chi-square gate, clamped), or the fixed square of the paper (+- fixed_half_size).
enum class WindowMode { kUncertainty, kFixed };

// How a keypoint's depth is read from the depth image of frame A.
//   kNearest: the pixel under the keypoint (rounded); when it has no reading, the valid pixel
//             of the 3x3 neighbourhood nearest to the keypoint's sub-pixel position.
//   kMin3x3 / kMedian3x3: the minimum / median of the valid readings of the 3x3 neighbourhood.
enum class DepthSampling { kNearest, kMin3x3, kMedian3x3 };

struct PredictionOptions {
  // A measured depth (metres) outside [min_depth, max_depth], 0 or NaN counts as "no depth".
  double min_depth = 0.1;
  double max_depth = 10.0;
  // Keypoints without depth get the rotation-only prediction plus the epipolar segment swept by
  // the depth range [segment_min_depth, segment_max_depth] (max may be +inf: the segment then ends
  // at the point at infinity, K R K^-1 u). When false they get no prediction.
  bool predict_without_depth = true;
  double segment_min_depth = 0.3;
  double segment_max_depth = std::numeric_limits<double>::infinity();
  // Depth sensor noise sigma_z = depth_noise_coeff * z^2 (metres). 1.425e-3 1/m: Kinect v1,
  // Khoshelham & Elberink, Sensors 2012.
  double depth_noise_coeff = 1.425e-3;
  // Keypoint localisation noise (pixels, 1 sigma) in both frames. When scale_sigma_with_octave,
  // it is multiplied by octave_scale^octave (ORB: octave = pyramid level, scale factor 1.2; SIFT:
  // the low byte of cv::KeyPoint::octave as a signed octave index, factor 2).
  double keypoint_sigma_px = 1.0;
  bool scale_sigma_with_octave = false;
  double octave_scale = 1.2;
  // Search window.
  WindowMode window_mode = WindowMode::kUncertainty;
  double gate_probability = 0.99;  // chi-square gate on 2 dof: 0.99 -> 9.21
  double min_half_size = 4.0;      // pixels, clamps the uncertainty window's half sizes
  double max_half_size = 64.0;
  double fixed_half_size = 10.0;  // kFixed: the paper's +-10 px square
  // Depth sampling for SampleDepths().
  DepthSampling depth_sampling = DepthSampling::kNearest;

  void Check() const;
  // -2 ln(1 - gate_probability): the chi-square quantile for 2 degrees of freedom.
  double GateChiSquare() const;
};

enum class PredictionStatus : uint8_t {
  kWithDepth,     // predicted from the measured depth: window around uv
  kWithoutDepth,  // no valid depth: capsule around the epipolar segment
  kBehindCamera,  // the point (or the whole depth range) lies behind camera B
  kOutsideImage,  // projects outside image B (the segment: no part inside)
  kInvalid,       // non-finite input, or no depth and predict_without_depth is off
};
const char* ToString(PredictionStatus status);

struct KeypointPrediction {
  PredictionStatus status = PredictionStatus::kInvalid;
  // kWithDepth: the predicted position in B. kWithoutDepth: the rotation-only prediction
  // K R K^-1 u (the point at infinity; may lie outside the image; NaN when behind camera B).
  Eigen::Vector2f uv = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  // kWithoutDepth: the search segment in B, clipped to the image (start = the z_min end).
  // kWithDepth: both equal uv.
  Eigen::Vector2f segment_start = uv;
  Eigen::Vector2f segment_end = uv;
  // Pixel covariance of the prediction (kWithoutDepth: at the endpoint with the larger one).
  Eigen::Matrix2f covariance = Eigen::Matrix2f::Zero();
  // kWithoutDepth: half-width of the capsule around the segment.
  float radius = 0.0f;
  // The axis-aligned search box: kWithDepth, the window itself; kWithoutDepth, the capsule's
  // bounding box (candidates inside it are then tested against the capsule).
  float min_x = 0.0f, min_y = 0.0f, max_x = -1.0f, max_y = -1.0f;
  // Predicted in-plane rotation of the image around the point (degrees, same sense as
  // cv::KeyPoint::angle) and apparent size ratio size_b / size_a = |p_a| / |p_b| (the depth ratio
  // z_a / z_b on the optical axis); an interval [scale_min, scale_max] for kWithoutDepth.
  float angle_change_deg = 0.0f;
  float scale_min = 1.0f;
  float scale_max = 1.0f;

  bool HasWindow() const {
    return status == PredictionStatus::kWithDepth || status == PredictionStatus::kWithoutDepth;
  }
  // True when (x, y) lies in the search region (the box, and for kWithoutDepth the capsule).
  bool Contains(float x, float y) const {
    if (!(x >= min_x && x <= max_x && y >= min_y && y <= max_y)) return false;
    return status != PredictionStatus::kWithoutDepth ||
           SegmentDistanceSquared(x, y) <= radius * radius;
  }
  float SegmentDistanceSquared(float x, float y) const;
};

// Precomputes everything that depends on the camera and the motion; Predict() is then a few dozen
// flops per keypoint. One camera model for both frames. The Jacobians use the undistorted pinhole
// model (distortion is applied to the predicted positions themselves; the epipolar segment is
// straight, i.e. computed without distortion).
class KeypointPredictor {
 public:
  KeypointPredictor(const PinholeCamera& camera, const CameraMotion& motion,
                    const PredictionOptions& options);

  // uv_a: keypoint in A; depth_m: its depth (NaN/0/out of range -> no depth); sigma_scale
  // multiplies options.keypoint_sigma_px.
  KeypointPrediction Predict(const Eigen::Vector2d& uv_a, double depth_m,
                             double sigma_scale = 1.0) const;

  // K R K^-1 applied to uv_a (through the undistorted bearing); nullopt-like NaN when the
  // direction points behind camera B.
  Eigen::Vector2d RotationOnly(const Eigen::Vector2d& uv_a) const;
  // The infinite homography K R K^-1 (the pinhole part).
  Eigen::Matrix3d InfiniteHomography() const;

  // 2x2 pixel covariance of the projection of q = R x + rho t (x = [x, y, 1] the undistorted
  // bearing in A, rho the inverse depth), see the .cc for the Jacobians.
  Eigen::Matrix2d Covariance(const Eigen::Vector3d& rx, double rho, double rho_variance,
                             double pixel_variance) const;

  const PredictionOptions& options() const { return options_; }

 private:
  Eigen::Vector2d PinholeProject(const Eigen::Vector3d& q) const;
  void SetWindow(const Eigen::Matrix2d& cov, KeypointPrediction& p) const;
  void SetOrientation(const Eigen::Vector3d& q, KeypointPrediction& p) const;

  PinholeCamera camera_;
  PredictionOptions options_;
  Eigen::Matrix3d r_;
  Eigen::Vector3d t_;
  Eigen::Vector3d r_col0_fx_, r_col1_fy_;  // R e1 / fx, R e2 / fy: dq/du_a, dq/dv_a
  Eigen::Matrix<double, 6, 6> motion_cov_;
  bool has_motion_cov_ = false;
  double chi2_ = 9.21;
};

// Predicts every keypoint of A. depths_m: one per keypoint (metres, NaN = none) or empty (no
// depth for any). Throws InvalidArgument on size mismatch or bad options.
std::vector<KeypointPrediction> PredictKeypoints(const PinholeCamera& camera,
                                                 const CameraMotion& motion,
                                                 const std::vector<KeypointInfo>& keypoints,
                                                 const std::vector<float>& depths_m,
                                                 const PredictionOptions& options);

// Depth (metres) at sub-pixel position (x, y) of a depth image: CV_16U raw (divided by
// depth_scale, 0 = no reading) or CV_32F metres (0 / NaN / negative = no reading). NaN when there
// is no valid reading. Throws InvalidArgument for other types.
float SampleDepth(const cv::Mat& depth, double depth_scale, float x, float y, DepthSampling mode);
std::vector<float> SampleDepths(const cv::Mat& depth, double depth_scale,
                                const std::vector<KeypointInfo>& keypoints, DepthSampling mode);
std::vector<float> SampleDepths(const cv::Mat& depth, double depth_scale,
                                const std::vector<cv::KeyPoint>& keypoints, DepthSampling mode);

}  // namespace imumatch
