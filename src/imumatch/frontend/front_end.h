#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/frontend/motion_refit.h"
#include "imumatch/frontend/pose_estimation.h"
#include "imumatch/frontend/rotation_from_fit.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/imu/gyro_bias_filter.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/imu/imu_params.h"
#include "imumatch/imu/time_offset.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/klt_tracker.h"
#include "imumatch/matching/neighbour_depth.h"
#include "imumatch/matching/patch_matching.h"
#include "imumatch/matching/predictor.h"
#include "imumatch/matching/subpixel_refinement.h"

namespace imumatch {

// A visual-inertial front end that needs no ground truth: fed IMU samples and frames in time
// order, it matches each frame with the previous one (IMU-guided, or the hybrid tracker), fits the
// relative pose, matches again with the fitted pose, and keeps its own state (attitude, velocity,
// gyro bias). It composes the predictor, the matchers and a pose estimator; it owns no I/O.
//
// State without ground truth:
//  - gyro bias and gravity (roll, pitch) from the still start of the IMU stream (or a given bias);
//    the IMU is then propagated from rest to the first frame, the velocity's uncertainty growing
//    with the unobservable accelerometer bias (motion.accel_bias_sigma per second);
//  - with depth in the previous frame: PnP + RANSAC on its 3D points and their matches; the
//    velocity implied by the fitted translation is fused with the IMU's (per axis, inverse
//    variance);
//  - without depth: the rotation is the gyro's, the translation direction comes from the
//    epipolar geometry and its length from the IMU velocity, whose uncertainty keeps growing;
//  - attitude from the gyro (its drift is far below a PnP rotation's noise over a few frames).
struct FrontEndOptions {
  FeatureOptions features;  // ORB, max_keypoints 1000
  // Hybrid: IMU-seeded KLT first, guided matching for the keypoints whose track failed. Otherwise
  // guided descriptor matching only.
  bool hybrid = false;
  PredictionOptions prediction;
  GuidedMatcherOptions guided;
  bool refine_subpixel = true;
  SubpixelOptions subpixel;
  // The queries the guided search left unmatched with candidates in their window are looked at
  // again by the image patch (MatchByPatch): A's patch, warped as predicted, aligned at each
  // candidate. In the final pass only (the second, or the first when there is none): the pose
  // fit between the passes rests on the descriptors' matches. In windows the IMU's motion has
  // misplaced (a synthetic walk coming to a stop with the velocity off by 1 m/s), a textured
  // scene showed a patch at one wrong candidate often enough to spoil that fit.
  bool patch_second_look = true;
  PatchMatchingOptions patch;
  KltOptions klt;
  // Integration mode and the attitude / bias sigmas; velocity_sigma is the front end's own.
  CameraMotionOptions motion;
  // Gravity and gyro bias from the first still_s seconds of the IMU stream.
  double still_s = 1.0;
  std::optional<ImuBias> bias;  // given: used instead of the still estimate
  // The gyro bias learnt from the rotations that the second pass's fits measure (GyroBiasFilter
  // fed by ImuRotationFromFit, as eval does), from zero with gyro_bias_filter.unknown_bias_sigma,
  // when no still period gave it (a MEMS gyro's bias left in the IMU's rotation misplaces every
  // window: MH_05's is 0.23 deg per frame). After a still period only with
  // learn_gyro_bias_after_still: the still estimate (100 samples at rest, +-1.7e-4 rad/s on
  // MH_05) is better than what the fits' rotations, whose stated covariance is optimistic on real
  // images (docs/REAL_FLIGHT.md), move it to: on MH_05 learning from it raised the relative pose
  // error from 11.9 to 21.4 mm per frame (ORB), the bias's y moving 2e-3 rad/s away from the
  // ground truth's batch estimate. Off, or with `bias` given: the bias stays what initialisation
  // set.
  bool learn_gyro_bias = true;
  bool learn_gyro_bias_after_still = false;
  GyroBiasFilterOptions gyro_bias_filter;
  // Keep every rotation the second pass's fits measure (fitted_rotations(), one per frame: for a
  // run of known length), for EstimateTimeOffset: the camera's clock offset from the IMU's,
  // measured over a run (RunTrack turns it on for a recorded IMU). Each fit then solves a second
  // time for the rotation its matches alone show. Off, a live front end keeps only the last
  // time_offset_window of them, and only when estimate_time_offset.
  bool keep_fitted_rotations = false;
  // Estimate that offset as the run goes and read the IMU in the camera's clock: over
  // [t_a + offset, t_b + offset] for frames stamped t_a, t_b (a camera not triggered by the IMU's
  // clock, whose timeshift is not calibrated). EstimateTimeOffset runs over the last
  // time_offset_window fitted rotations each time time_offset_every more have come, and a measured
  // offset replaces the one in use. The IMU must then be fed up to the frame's time plus
  // time_offset.max_offset_s. Off: the IMU is read at the frames' stamps.
  bool estimate_time_offset = false;
  TimeOffsetOptions time_offset;
  int time_offset_window = 100;
  int time_offset_every = 10;  // fitted rotations between two online estimates
  // Velocity uncertainty (m/s per axis) when nothing constrains it: after a loss or an IMU gap.
  double unknown_velocity_sigma = 1.0;
  double min_velocity_sigma = 0.02;
  // Fewer matches than this in the first pass: the frame is matched by brute force instead.
  int min_matches = 20;
  PoseFitOptions pose;
  // Second pass: predict again with the motion RefitMotion finds from the IMU's prior and the
  // first pass's matches, with its covariance (when it fails: the fitted pose, with a covariance
  // from its residual), match, and keep the matches the fitted geometry explains (reprojection
  // with depth, epipolar distance without, within pose.ransac_px). Measured on EuRoC MH_05 (199
  // pairs) against the pose fit's windows: 821.0 -> 826.5 final matches per frame (hybrid 956.6
  // -> 965.8) at the same precision and relative pose error.
  bool second_pass = true;
  MotionRefitOptions refit;
  // Second pass: the segments of keypoints without depth cut to the inverse depths their matched
  // neighbours of the first pass show (NeighbourInverseDepthRanges; KLT tracks are not neighbours).
  NeighbourDepthOptions neighbour_depth;
  void Check() const;  // throws InvalidArgument
};

struct FrontEndFrame {
  int64_t t_ns = 0;
  cv::Mat image;  // 8-bit gray (BGR is converted)
  cv::Mat depth;  // CV_16U raw (camera.depth_scale units per metre, 0 = none) or empty
};

enum class FrameStatus {
  kFirst,       // the first frame: state initialised, nothing to match
  kGuided,      // matched through the IMU's prediction
  kBruteForce,  // fallback: too few matches, an IMU gap or a bad frame
};
const char* ToString(FrameStatus status);

struct FrontEndResult {
  int64_t t_ns = 0;
  FrameStatus status = FrameStatus::kFirst;
  std::string event;  // what happened (fallback reason, initialisation), empty when routine
  std::vector<cv::KeyPoint> keypoints;  // this frame's
  // The previous frame's keypoints (query) to this frame's (train; -1 for a track, its position
  // in refined_uv_b): the final pass, and the first pass's for comparison.
  std::vector<Match> matches;
  std::vector<Match> matches_pass1;
  bool second_pass = false;
  int from_tracks = 0;      // hybrid: correspondences made by tracking (final pass)
  CameraMotion imu_motion;  // the IMU's prediction (first pass)
  PoseFit pose;             // the fit between the passes
  bool pose_from_depth = false;
  // The estimated motion: the second pass's motion fit where the previous frame has depth, else
  // the pose fit; the IMU's when it failed, or when the motion fit did not converge and PnP's pose
  // disagrees with the IMU's motion.
  Rigid3d cam_from_prev;
  bool has_state = false;  // false while waiting for the IMU to initialise (no pose yet)
  Rigid3d world_from_cam;  // the estimated pose (world: gravity-aligned, first IMU pose)
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();  // IMU velocity
  double velocity_sigma = 0.0;
  // Milliseconds per stage.
  double extract_ms = 0.0, motion_ms = 0.0, match1_ms = 0.0, pose_ms = 0.0, match2_ms = 0.0;
  double total_ms = 0.0;
};

class FrontEnd {
 public:
  // camera: the images' intrinsics and lens; cam_from_imu: the extrinsics.
  FrontEnd(const PinholeCamera& camera, const ImuParams& imu_params, const Rigid3d& cam_from_imu,
           const FrontEndOptions& options = FrontEndOptions());

  // IMU samples in time order (InputError for a sample not after the previous one).
  void AddImu(const ImuSample& sample);
  // The next frame. Needs IMU samples up to its timestamp for the prediction (otherwise: brute
  // force, with the reason). Throws InvalidArgument for an empty image or one of another size
  // than the camera's; never for what the images or the IMU contain.
  FrontEndResult Process(const FrontEndFrame& frame);

  // Initialisation notes (bias and gravity source), one line each.
  const std::vector<std::string>& notes() const { return notes_; }
  const FrontEndOptions& options() const { return options_; }
  // The gyro bias in use (rad/s, IMU frame), and its filter when the bias is learnt (nullptr before
  // initialisation or when learn_gyro_bias is off): updates(), rejected(), SigmaAt().
  const Eigen::Vector3d& gyro_bias() const { return bias_.gyro; }
  const GyroBiasFilter* gyro_bias_filter() const {
    return gyro_bias_filter_ ? &*gyro_bias_filter_ : nullptr;
  }
  // The offset in use (estimate_time_offset; 0 until one is measured): t_imu = t_cam + offset,
  // and the estimate it came from.
  int64_t imu_time_offset_ns() const { return imu_offset_ns_; }
  const std::optional<TimeOffsetEstimate>& online_time_offset() const { return online_offset_; }
  // The rotations the second pass's fits measured, in frame order: all of them with
  // keep_fitted_rotations, else the last time_offset_window with estimate_time_offset, else none.
  const std::vector<RotationObservation>& fitted_rotations() const { return fitted_rotations_; }

 private:
  struct Previous {
    int64_t t_ns = 0;
    cv::Mat image, depth;
    Features features;
    std::vector<KeypointInfo> ideal;
    // Depth at each keypoint (metres, NaN: no reading), sampled once; empty without a depth image.
    std::vector<float> depths;
    Rigid3d world_from_cam;
  };
  // The PnP fit's error (zero without a fit with depth): an angle (rad) and a translation (m).
  struct PoseFitError {
    double angle_sigma = 0.0, translation_sigma = 0.0;
  };
  void Initialise(int64_t t_ns, FrontEndResult& result);
  // Process's stages, in order, each on the frame against previous_ and filling its part of result.
  // The IMU's motion from the previous frame's state (result.imu_motion) and the samples'
  // preintegration; false, with result.event, when the IMU cannot give it (a gap).
  bool MotionFromImu(int64_t t_a_ns, int64_t t_b_ns, FrontEndResult& result,
                     ImuPreintegration& pim) const;
  // Guided matching in the IMU's windows; brute force when the IMU failed, features are too few
  // or the matches fewer than options_.min_matches (result.status says which).
  void FirstPass(const Features& features, const std::vector<KeypointInfo>& ideal,
                 const cv::Mat& gray, bool imu_ok, SceneNearDepth& scene, FrontEndResult& result);
  // PnP on the matches with depth, else the epipolar fit: result.pose, cam_from_prev.
  PoseFitError FitPose(const Features& features, bool imu_ok, FrontEndResult& result) const;
  // The motion refit and the second pass in its windows; false when PnP's pose was refused
  // (it disagrees with the IMU's where the refit did not converge): then no second pass.
  bool SecondPass(const Features& features, const std::vector<KeypointInfo>& ideal,
                  const cv::Mat& gray, int64_t t_ns, const PoseFitError& fit, SceneNearDepth& scene,
                  FrontEndResult& result);
  // The state at this frame: pose, the gyro's attitude, velocity and its sigma.
  void UpdateState(int64_t t_ns, const ImuPreintegration& pim, bool imu_ok, bool pnp_refused,
                   const PoseFitError& fit, FrontEndResult& result);
  // The frame becomes previous_.
  void Remember(const FrontEndFrame& frame, const cv::Mat& gray, Features features,
                std::vector<KeypointInfo> ideal, const Rigid3d& world_from_cam);
  // Feeds the rotation the refit measured between t_a and t_b to the gyro bias filter (when the
  // bias is learnt) and takes its bias for the next frames.
  void UseFittedRotation(const MotionRefit& refit, int64_t t_a_ns, int64_t t_b_ns);
  // patch_look: add MatchByPatch's matches (options_.patch_second_look permitting). first_pass:
  // the first pass's matches, whose depths narrow the segments (options_.neighbour_depth), or null.
  // scene: set to the segments' near end the pass finds (PredictKeypointsInScene); a second pass
  // that narrows the segments keeps the first pass's instead.
  std::vector<Match> MatchPass(const CameraMotion& motion, const Features& features,
                               const std::vector<KeypointInfo>& ideal, const cv::Mat& image,
                               bool patch_look, const std::vector<Match>* first_pass,
                               SceneNearDepth& scene, std::vector<KeypointPrediction>& predictions,
                               int& from_tracks);

  PixelUndistorter undistorter_;
  cv::Mat field_mask_;  // FieldOfViewMask: empty but for a fisheye wider than the field
  ImuParams imu_params_;
  Rigid3d cam_from_imu_;
  FrontEndOptions options_;
  ImuBuffer imu_;
  std::vector<std::string> notes_;
  bool initialised_ = false;
  std::optional<Previous> previous_;
  // State at the previous frame.
  Rigid3d world_from_imu_;
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  double velocity_sigma_ = 1.0;
  // The velocity's last fix (initialisation, a fit with depth, a re-initialisation): its sigma
  // and time. An accelerometer bias error is constant, so the velocity's error grows linearly
  // from there (accel_bias_sigma x time), not as a random walk from frame to frame.
  double velocity_fix_sigma_ = 1.0;
  int64_t velocity_fix_t_ns_ = 0;
  ImuBias bias_;
  double gyro_bias_sigma_ = 0.0;
  int64_t bias_t_ns_ = 0;
  std::optional<GyroBiasFilter> gyro_bias_filter_;
  std::vector<RotationObservation> fitted_rotations_;
  int64_t imu_offset_ns_ = 0;
  size_t rotations_seen_ = 0, rotations_at_estimate_ = 0;
  std::optional<TimeOffsetEstimate> online_offset_;
};

}  // namespace imumatch
