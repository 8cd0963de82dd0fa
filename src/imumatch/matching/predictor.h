#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/depth_reading.h"
#include "imumatch/matching/match_types.h"

namespace imumatch {

// How the search window around a prediction is sized: from the propagated 2x2 pixel covariance
// (chi-square gate, clamped), or the fixed square of the paper (+- fixed_half_size).
enum class WindowMode { kUncertainty, kFixed };

// How a keypoint's localisation noise grows with its detection scale.
//   kNone:   keypoint_sigma_px for every keypoint.
//   kSize:   the keypoint's scale s = size / reference size, the reference being the smallest
//            keypoint size of the frame (the detector's finest scale). A keypoint found at scale s
//            (ORB level l: s = 1.2^l; SIFT octave o: s = 2^o) sits on a grid of step s px, so its
//            position carries a rounding error of variance s^2 / 12 per axis on top of the base:
//            sigma^2 = keypoint_sigma_px^2 + (s^2 - 1) / 12. Whatever the detector, its sizes say
//            so: no table of detectors. Keypoints without a size (<= 0) get the base sigma.
//            Measured on EuRoC MH_05 with the exact motion: sigma growing linearly with s made
//            the windows of coarse keypoints 3-4x wider and cost 1-2 % of the correct matches and
//            0.5-1.5 points of precision for no window recall (both >= 0.998 pooled).
//   kOctave: keypoint_sigma_px * octave_scale^octave (cv::KeyPoint::octave's low byte as a signed
//            level), for callers that know their detector's pyramid factor.
enum class KeypointSigmaScaling { kNone, kSize, kOctave };

// The near end of the epipolar segments taken from the scene instead of the constant
// segment_min_depth (PredictKeypointsInScene, matching/scene_depth.h; the predictor itself sweeps
// what PredictionOptions says). A segment's pixel length and its capsule's width both grow with
// 1 / z_near (the translation's noise is scaled by the inverse depth): from 0.1 m, a drone at 1 m/s
// and 20 Hz sweeps a 35 px wide capsule across a third of the image for every keypoint without
// depth, although the scene it flies through is metres away. A pilot sample of A's keypoints is
// matched first (with the full segments), and each match gives the depth its partner needs: the
// nearer of the depth at which it lies along the given epipolar line, and the deepest near end on
// a ladder (segment_min_depth x 2^k) whose capsule, predicted without depth, still contains it.
// Both are measured in B's pixels with the given motion, so they hold when the IMU's translation
// is off in length or direction (the ladder covers partners off the line, which only a capsule's
// width reaches). The segments start at near_margin x the near_quantile of these depths.
struct SceneNearDepthOptions {
  bool enabled = true;
  // At most this many of A's keypoints (evenly spread over them) form the pilot, matched with
  // Lowe's ratio at most pilot_ratio: a false pilot match lies anywhere on its long capsule, most
  // likely on its near part, and would hold the near end there for every keypoint. Measured on
  // all 199 pairs of EuRoC MH_05 with pilot ratios 0.8 / 0.7 / 0.6: median near end SIFT 0.10 /
  // 0.15 / 0.63 m (ORB 0.40 / 0.75 / 1.00 m), correct matches SIFT 679.5 / 681.4 / 683.2 (ORB
  // 823.8 / 825.9 / 827.4), false 21.8 / 20.2 / 18.9; window recall >= 0.9993 for all.
  int pilot_queries = 100;
  double pilot_ratio = 0.6;
  // Fewer pilot matches than this: the configured near end is kept.
  int min_samples = 20;
  // The quantile from the near side and the factor below it: a nearer object must hold more than
  // about near_quantile of the pilot's matches to be sampled, and lie at less than near_margin of
  // the sampled depth to fall off its segments. 0: the nearest pilot sample (on MH_05, 0.05, the
  // 4th nearest of about 70, lost up to 9 % of a pair's correct matches where the floor near the
  // landed drone held 4.6 % of the pilot).
  double near_quantile = 0.0;
  double near_margin = 0.5;
  void Check() const;
};

// What PredictKeypointsInScene found and did.
struct SceneNearDepth {
  int pilot_queries = 0;  // keypoints of A matched first, with the configured segments
  int pilot_matches = 0;  // of them, matched with a partner inside their no-depth capsule
  // The near_quantile of the pilot matches' depth samples (metres); NaN when there were fewer
  // than min_samples of them.
  double near_depth_m = std::numeric_limits<double>::quiet_NaN();
  // Where the segments of A's keypoints without depth start (the configured segment_min_depth
  // when nothing was learned).
  double segment_min_depth_m = 0.0;
  bool moved = false;  // segment_min_depth_m lies beyond the configured near end
};

struct PredictionOptions {
  // A measured depth (metres) outside [min_depth, max_depth], 0 or NaN counts as "no depth". The
  // bounds reject garbage, not far points: 10 m (a Kinect's range) threw away 90 % of the EuRoC
  // MH_05 depth readings (a machine hall, median depth 11 m). The depth noise model below already
  // widens the window for far readings.
  double min_depth = 0.1;
  double max_depth = 100.0;
  // Keypoints without depth get the rotation-only prediction plus the epipolar segment swept by
  // the depth range [segment_min_depth, segment_max_depth] (max may be +inf: the segment then ends
  // at the point at infinity, K R K^-1 u). When false they get no prediction.
  // The near end is 0.1 m, as min_depth: measured on EuRoC MH_05, a drone standing on the ground
  // sees the floor at 0.1-0.3 m at the bottom of its image; with 0.3 m, 1.4 % of the ORB matches
  // that the ground truth calls correct fell beyond the segment's near end.
  bool predict_without_depth = true;
  double segment_min_depth = 0.1;
  double segment_max_depth = std::numeric_limits<double>::infinity();
  // Depth sensor noise sigma_z = depth_noise_coeff * z^2 (metres). 1.425e-3 1/m: Kinect v1,
  // Khoshelham & Elberink, Sensors 2012.
  double depth_noise_coeff = 1.425e-3;
  // Keypoint localisation noise (image pixels, 1 sigma) in both frames at the detector's finest
  // scale, grown with the keypoint's scale as sigma_scaling says (see KeypointSigmaScaling).
  double keypoint_sigma_px = 1.0;
  KeypointSigmaScaling sigma_scaling = KeypointSigmaScaling::kSize;
  double octave_scale = 1.2;  // kOctave only
  // Search window.
  WindowMode window_mode = WindowMode::kUncertainty;
  double gate_probability = 0.99;  // chi-square gate on 2 dof: 0.99 -> 9.21
  double min_half_size = 4.0;      // pixels, clamps the uncertainty window's half sizes
  double max_half_size = 64.0;
  double fixed_half_size = 10.0;  // kFixed: the paper's +-10 px square
  // Depth sampling for SampleDepths().
  DepthSampling depth_sampling = DepthSampling::kNearest;
  SceneNearDepthOptions scene_near;

  void Check() const;
  // A measured depth the prediction uses: finite and within [min_depth, max_depth].
  bool IsUsableDepth(double depth_m) const {
    return std::isfinite(depth_m) && depth_m >= min_depth && depth_m <= max_depth;
  }
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
  // cv::KeyPoint::angle; kWithoutDepth: at the far end of the segment) and apparent size ratio
  // size_b / size_a = |p_a| / |p_b| (the depth ratio z_a / z_b on the optical axis); an interval
  // [scale_min, scale_max] for kWithoutDepth.
  float angle_change_deg = 0.0f;
  // The local affine map d uv_b / d uv_a (ideal pixels) of a fronto-parallel plane through the
  // point: how the patch around the keypoint is rotated and scaled in B (kWithoutDepth: at the
  // far end of the depth range, where most points without depth are).
  Eigen::Matrix2f local_affine = Eigen::Matrix2f::Identity();
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
// flops per keypoint. One camera model for both frames.
//
// Coordinates: every position the predictor takes and returns (uv_a, uv, the segment, the window)
// is in *ideal pixels*, K times the undistorted bearing (PinholeCamera::PixelToIdeal). For a camera
// without distortion they are the image pixels. In ideal pixels the epipolar segment is straight
// and the projection is the pinhole one, so a distorted lens costs nothing per prediction: the
// keypoints of each frame are mapped once (ToIdealKeypointInfos) and the grid of frame B is built
// on the mapped keypoints. Noise is stated in image pixels (where keypoints are detected) and
// mapped into ideal pixels through the lens's local Jacobian at A and at the prediction in B: a
// barrel lens stretches the periphery, so the same pixel of noise spans more ideal pixels there.
class KeypointPredictor {
 public:
  // The ideal image's bounds are computed from the camera (a few hundred undistortions when the
  // lens has distortion); the second form takes them, and the lens's noise Jacobians, from an
  // undistorter built once per camera, which must outlive the predictor.
  KeypointPredictor(const PinholeCamera& camera, const CameraMotion& motion,
                    const PredictionOptions& options);
  KeypointPredictor(const PixelUndistorter& undistorter, const CameraMotion& motion,
                    const PredictionOptions& options);

  // uv_a: keypoint in A (ideal pixels); depth_m: its depth (NaN/0/out of range -> no depth);
  // sigma_scale multiplies options.keypoint_sigma_px.
  KeypointPrediction Predict(const Eigen::Vector2d& uv_a, double depth_m,
                             double sigma_scale = 1.0) const;
  // A keypoint without depth searched along the part of its epipolar segment between the inverse
  // depths rho_far <= rho_near (1/m; 0 is infinity) that lies within the configured segment
  // [1 / segment_max_depth, 1 / segment_min_depth]: for a depth range the scene around the
  // keypoint shows (PredictKeypointsInRanges). Inverse depths are in the units of the motion's
  // translation. When its sign is open (TranslationSignOpen), a range may reach below zero,
  // beyond the rotation-only point, where the matches of a motion fitted without depth then put
  // partners: down to the configured segment mirrored beyond that point (-1 / segment_min_depth).
  // A range outside these bounds (or NaN): the configured segment, as Predict without depth. Runs
  // even when predict_without_depth is off.
  KeypointPrediction PredictInInverseDepthRange(const Eigen::Vector2d& uv_a, double rho_far,
                                                double rho_near, double sigma_scale = 1.0) const;

  // K R K^-1 applied to uv_a (ideal pixels in and out); NaN when the direction points behind
  // camera B.
  Eigen::Vector2d RotationOnly(const Eigen::Vector2d& uv_a) const;
  // The infinite homography K R K^-1 (the pinhole part).
  Eigen::Matrix3d InfiniteHomography() const;
  // The inverse depth rho = 1 / z_a (1/m, z along A's optical axis) at which keypoint uv_a of A
  // would be seen at uv_b in B (both ideal pixels): the least-squares solution of
  // (R x_a + rho t) x x_b = 0, so uv_b off the epipolar line counts only by its component along
  // it. 0 or negative: at infinity or beyond it (within noise, unless TranslationSignOpen); NaN
  // without translation.
  double InverseDepthOf(const Eigen::Vector2d& uv_a, const Eigen::Vector2d& uv_b) const;
  // True when the motion's translation may point the other way: its length lies within the
  // windows' gate (sqrt(chi2) sigmas, options.gate_probability) of zero, sigma being the
  // covariance's extent along the translation (a fit without depth leaves it the IMU's). Partners
  // can then lie beyond the rotation-only point (InverseDepthOf < 0) by more than noise.
  bool TranslationSignOpen() const { return sign_open_; }

  // 2x2 pixel covariance of the projection of q = R x + rho t (x = [x, y, 1] the undistorted
  // bearing in A, rho the inverse depth), see the .cc for the Jacobians.
  // pixel_cov_a / pixel_cov_b: the keypoint noise of A and of B in ideal pixels.
  Eigen::Matrix2d Covariance(const Eigen::Vector3d& rx, double rho, double rho_variance,
                             const Eigen::Matrix2d& pixel_cov_a,
                             const Eigen::Matrix2d& pixel_cov_b) const;

  const PredictionOptions& options() const { return options_; }
  // The same predictor with the segments' near end at min_depth (> 0, < segment_max_depth).
  KeypointPredictor WithSegmentMinDepth(double min_depth) const;
  // The same predictor with the segments' near end where PredictKeypointsInScene put it (this one
  // when it did not move it).
  KeypointPredictor WithSceneNearEnd(const SceneNearDepth& scene) const {
    return scene.moved ? WithSegmentMinDepth(scene.segment_min_depth_m) : *this;
  }

 private:
  void Init(const CameraMotion& motion);
  // Predict, with the segment of a keypoint without depth (whatever predict_without_depth says)
  // spanning the inverse depths [rho_lo, rho_hi].
  KeypointPrediction PredictWithSegment(const Eigen::Vector2d& uv_a, double depth_m,
                                        double sigma_scale, double rho_lo, double rho_hi) const;
  Eigen::Vector2d PinholeProject(const Eigen::Vector3d& q) const;
  // Isotropic image-pixel variance -> covariance in ideal pixels at the ideal position uv.
  Eigen::Matrix2d PixelNoise(const Eigen::Vector2d& uv, double pixel_variance) const;
  void SetWindow(const Eigen::Matrix2d& cov, KeypointPrediction& p) const;
  void SetOrientation(const Eigen::Vector3d& q, KeypointPrediction& p) const;

  PinholeCamera camera_;
  const PixelUndistorter* undistorter_ = nullptr;
  bool distorted_ = false;
  double min_x_ = -0.5, min_y_ = -0.5, max_x_ = 0.0, max_y_ = 0.0;  // ideal image bounds
  PredictionOptions options_;
  Eigen::Matrix3d r_;
  Eigen::Vector3d t_;
  Eigen::Vector3d r_col0_fx_, r_col1_fy_;  // R e1 / fx, R e2 / fy: dq/du_a, dq/dv_a
  Eigen::Matrix<double, 6, 6> motion_cov_;
  bool has_motion_cov_ = false;
  bool sign_open_ = false;
  double chi2_ = 9.21;
};

// The smallest positive keypoint size (0 when none has a size): the reference of kSize.
float ReferenceKeypointSize(const std::vector<KeypointInfo>& keypoints);
// The factor on options.keypoint_sigma_px for one keypoint (see KeypointSigmaScaling).
double KeypointSigmaScale(const PredictionOptions& options, const KeypointInfo& keypoint,
                          float reference_size);
// The grid-rounding model of KeypointSigmaScaling::kSize: the factor on a base sigma of
// base_sigma_px for a keypoint of the given size, sqrt(1 + (s^2 - 1) / (12 base^2)) with
// s = max(1, size / reference_size). 1 when the size, the reference or the base is not positive.
double SizeSigmaFactor(float size, float reference_size, double base_sigma_px);

// Keypoints in ideal pixels (PredictKeypoints and the guided matcher work in them): positions
// mapped through the undistorter, angle, size and octave kept. Through a fisheye wider than the
// field of view (PinholeCamera::WiderThanField) a keypoint beyond it gets NaN: not predicted,
// never a candidate (FieldOfViewMask keeps the detectors from finding such keypoints).
std::vector<KeypointInfo> ToIdealKeypointInfos(const std::vector<cv::KeyPoint>& keypoints,
                                               const PixelUndistorter& undistorter);
void ToIdealKeypointInfos(const std::vector<cv::KeyPoint>& keypoints,
                          const PixelUndistorter& undistorter, std::vector<KeypointInfo>* out);

// Predicts every keypoint of A with the predictor into *out (its capacity reused), each with its
// KeypointSigmaScale. depths_m: one per keypoint (metres, NaN = none) or empty.
void PredictKeypoints(const KeypointPredictor& predictor,
                      const std::vector<KeypointInfo>& keypoints,
                      const std::vector<float>& depths_m, std::vector<KeypointPrediction>* out);
// Predicts every keypoint of A (ideal pixels, see KeypointPredictor). depths_m: one per keypoint
// (metres, NaN = none) or empty (no depth for any). Throws InvalidArgument on size mismatch or bad
// options.
std::vector<KeypointPrediction> PredictKeypoints(const PinholeCamera& camera,
                                                 const CameraMotion& motion,
                                                 const std::vector<KeypointInfo>& keypoints,
                                                 const std::vector<float>& depths_m,
                                                 const PredictionOptions& options);
std::vector<KeypointPrediction> PredictKeypoints(const PixelUndistorter& undistorter,
                                                 const CameraMotion& motion,
                                                 const std::vector<KeypointInfo>& keypoints,
                                                 const std::vector<float>& depths_m,
                                                 const PredictionOptions& options);

// An inverse-depth interval (1/m); NaN ends: none. (NeighbourInverseDepthRanges,
// neighbour_depth.h, finds them from a first pass's matches.)
struct InverseDepthRange {
  double rho_far = std::numeric_limits<double>::quiet_NaN();
  double rho_near = std::numeric_limits<double>::quiet_NaN();
  bool valid() const { return rho_far <= rho_near; }
};

// PredictKeypoints, except that a keypoint without a usable depth and with a valid range is
// predicted along it (KeypointPredictor::PredictInInverseDepthRange), unless that leaves it no
// window (then as PredictKeypoints). Each keypoint is predicted once. Returns how many were
// predicted along their range. ranges: one per keypoint, or empty (= PredictKeypoints).
int PredictKeypointsInRanges(const KeypointPredictor& predictor,
                             const std::vector<KeypointInfo>& keypoints,
                             const std::vector<float>& depths_m,
                             const std::vector<InverseDepthRange>& ranges,
                             std::vector<KeypointPrediction>* predictions);

}  // namespace imumatch
