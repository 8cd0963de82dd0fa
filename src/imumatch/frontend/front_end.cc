#include "imumatch/frontend/front_end.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/matching/depth_reading.h"
#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/field_of_view.h"

namespace imumatch {

void FrontEndOptions::Check() const {
  features.Check();
  prediction.Check();
  guided.Check();
  subpixel.Check();
  patch.Check();
  klt.Check();
  motion.Check();
  pose.Check();
  refit.Check();
  neighbour_depth.Check();
  gyro_bias_filter.Check();
  time_offset.Check();
  IMUMATCH_CHECK(time_offset_window >= time_offset.min_observations,
                 "time_offset_window=" << time_offset_window << " (at least "
                                       << time_offset.min_observations << ")");
  IMUMATCH_CHECK(time_offset_every >= 1 && time_offset_every <= time_offset_window,
                 "time_offset_every=" << time_offset_every << " (in [1, time_offset_window = "
                                      << time_offset_window << "])");
  IMUMATCH_CHECK(std::isfinite(still_s) && still_s >= 0.0 && still_s <= 3600.0,
                 "still_s=" << still_s);
  IMUMATCH_CHECK(std::isfinite(unknown_velocity_sigma) && unknown_velocity_sigma > 0.0,
                 "unknown_velocity_sigma=" << unknown_velocity_sigma);
  IMUMATCH_CHECK(std::isfinite(min_velocity_sigma) && min_velocity_sigma > 0.0 &&
                     min_velocity_sigma <= unknown_velocity_sigma,
                 "min_velocity_sigma=" << min_velocity_sigma);
  IMUMATCH_CHECK(min_matches >= 0, "min_matches=" << min_matches);
  if (bias) {
    IMUMATCH_CHECK(bias->gyro.allFinite() && bias->accel.allFinite(), "bias must be finite");
  }
}

const char* ToString(FrameStatus status) {
  switch (status) {
    case FrameStatus::kFirst:
      return "first";
    case FrameStatus::kGuided:
      return "guided";
    case FrameStatus::kBruteForce:
      return "brute_force";
  }
  return "?";
}

FrontEnd::FrontEnd(const PinholeCamera& camera, const ImuParams& imu_params,
                   const Rigid3d& cam_from_imu, const FrontEndOptions& options)
    : undistorter_(camera),
      field_mask_(FieldOfViewMask(camera)),
      imu_params_(imu_params),
      cam_from_imu_(cam_from_imu),
      options_(options) {
  camera.Check();
  imu_params.Check();
  options.Check();
  velocity_sigma_ = options.unknown_velocity_sigma;
  // The fits' rotations are a second solve: only when something reads them.
  if (options_.keep_fitted_rotations || options_.estimate_time_offset) {
    options_.refit.measure_rotation = true;
  }
}

void FrontEnd::AddImu(const ImuSample& sample) { imu_.Push(sample, "front end IMU stream"); }

namespace {

// Roll and pitch from a mean specific force f (the accelerometer at rest reads -g in the IMU
// frame, i.e. points up): the rotation taking f's direction to world +z, yaw zero.
Eigen::Quaterniond AttitudeFromGravity(const Eigen::Vector3d& specific_force) {
  return Eigen::Quaterniond::FromTwoVectors(specific_force.normalized(), Eigen::Vector3d::UnitZ());
}

}  // namespace

void FrontEnd::Initialise(int64_t t_ns, FrontEndResult& result) {
  std::ostringstream note;
  note << std::scientific << std::setprecision(2);
  // The still period must lie before the frame: frames before it only wait.
  if (imu_.empty() || imu_.end_ns() < t_ns ||
      t_ns - imu_.begin_ns() < SecondsToNs(options_.still_s)) {
    result.event = "waiting for " + std::to_string(options_.still_s) +
                   " s of IMU before a frame to initialise gravity and the gyro bias";
    return;
  }
  // The still window: the still_s seconds just before the frame when the IMU is still there, so
  // that the state starts at rest at the frame itself; else the log's first still_s seconds, and
  // the state is propagated from there to the frame. Over a long wait that propagation tilts the
  // attitude by the gyro's noise and drifts the velocity by the accelerometer's bias: MH_05's
  // first frame comes 20 s into its log, where the drone still stands, and the velocity
  // propagated to it read 1.9 m/s; the tilt stays in every later frame's gravity (the relative
  // pose error without depth, frames 100-199, 64 mm RMSE per frame from the log's start, 14 mm
  // from the frame's). Still means at rest here as at the log's start: an IMU cannot tell rest
  // from a constant velocity.
  const int64_t still_ns = SecondsToNs(options_.still_s);
  const int64_t log_start = imu_.begin_ns();
  std::optional<StillInitialization> still;  // the window's, when one was still
  bool before_frame = false;
  int64_t t1 = std::min(t_ns, log_start + still_ns);  // the still window's end
  if (still_ns > 0 && t_ns - still_ns > log_start) {
    try {
      still = InitializeFromStill(imu_, t_ns - still_ns, t_ns, imu_params_);
      before_frame = true;
      t1 = t_ns;
    } catch (const Error&) {
      // Not still before the frame: the log's start is tried.
    }
  }
  std::string not_still;  // why the log's start is not a still window either
  if (!still) {
    try {
      still = InitializeFromStill(imu_, log_start, t1, imu_params_);
    } catch (const Error& e) {
      not_still = e.what();
    }
  }
  const bool bias_from_still = still.has_value();
  // Where the state starts: at rest at the end of the still window, propagated to the frame; or,
  // when there is none, at the frame itself with the velocity unknown.
  const int64_t state_t_ns = bias_from_still ? t1 : t_ns;
  Rigid3d world_from_imu;
  if (still) {
    world_from_imu = still->world_from_imu;
    bias_ = still->bias;
    gyro_bias_sigma_ = still->gyro_bias_sigma;
    note << "gravity and gyro bias from the still "
         << (before_frame ? "IMU just before the first frame" : "start of the IMU") << " ("
         << still->num_samples << " samples): bias " << bias_.gyro.x() << " " << bias_.gyro.y()
         << " " << bias_.gyro.z() << " rad/s";
    if (still->end_ns < t1) note << " (the still period ends at an IMU gap)";
  } else {
    // Not still (or too short): the state starts at the frame, gravity from the mean specific
    // force of the IMU just before it (still_s, at least 0.2 s), no bias estimate, the velocity
    // unknown. "At rest" at the log's start, propagated to a frame that may come many seconds
    // later (MH_05's first frame comes 20 s into its log), would be a guess that every second of
    // integration makes worse. The recorded samples are averaged directly: a gap in the log does
    // not matter to a mean.
    const int64_t from = std::max(log_start, t_ns - std::max(still_ns, SecondsToNs(0.2)));
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    for (const ImuSample& s : imu_.samples()) {
      if (s.t_ns > t_ns) break;
      if (s.t_ns >= from) f += s.accel_m_s2;
    }
    world_from_imu = Rigid3d(AttitudeFromGravity(f), Eigen::Vector3d::Zero());
    bias_ = ImuBias();
    gyro_bias_sigma_ = options_.motion.gyro_bias_sigma;
    note << "the IMU's start is not still (" << not_still
         << "): gravity from its mean before the frame, gyro bias assumed zero";
  }
  if (options_.bias) {
    bias_ = *options_.bias;
    gyro_bias_sigma_ = options_.motion.gyro_bias_sigma;
    note << "; the given bias is used";
  }
  bias_t_ns_ = state_t_ns;
  if (options_.learn_gyro_bias && !options_.bias &&
      (!bias_from_still || options_.learn_gyro_bias_after_still)) {
    if (!bias_from_still) gyro_bias_sigma_ = options_.gyro_bias_filter.unknown_bias_sigma;
    // The filter is fed the rotation the matches alone measure: a second solve of each fit.
    options_.refit.measure_rotation = true;
    gyro_bias_filter_.emplace(bias_.gyro, gyro_bias_sigma_, imu_params_.gyro_random_walk,
                              state_t_ns, options_.gyro_bias_filter);
    note << "; the gyro bias is then learnt from the rotations the fitted motions measure";
  }
  // After a still start, from rest at t1 to the frame: the velocity's error grows with the
  // accelerometer bias, which a still start does not reveal. Without one, nothing to propagate.
  NavState state;
  state.t_ns = state_t_ns;
  state.world_from_imu = world_from_imu;
  if (t_ns > state_t_ns) {
    try {
      const ImuPreintegration pim = Preintegrate(imu_.Slice(state_t_ns, t_ns), bias_, imu_params_);
      state = Propagate(state, pim, imu_params_.gravity_in_world);
    } catch (const Error& e) {
      note << "; IMU not propagated to the first frame (" << e.what() << ")";
    }
  }
  world_from_imu_ = Rigid3d(state.world_from_imu.rotation, Eigen::Vector3d::Zero());
  velocity_ = state.velocity_in_world;
  if (bias_from_still) {
    const double since = NsToSeconds(t_ns - t1);
    velocity_sigma_ =
        std::max(options_.min_velocity_sigma,
                 std::hypot(options_.min_velocity_sigma, options_.motion.accel_bias_sigma * since));
    velocity_fix_sigma_ = options_.min_velocity_sigma;  // at rest at t1
    velocity_fix_t_ns_ = t1;
    note << "; velocity propagated from rest over " << std::fixed << std::setprecision(2) << since
         << " s (sigma " << velocity_sigma_ << " m/s)";
  } else {
    velocity_sigma_ = options_.unknown_velocity_sigma;
    velocity_fix_sigma_ = options_.unknown_velocity_sigma;
    velocity_fix_t_ns_ = t_ns;
    note << "; velocity unknown (zero, sigma " << std::fixed << std::setprecision(2)
         << velocity_sigma_ << " m/s)";
  }
  notes_.push_back(note.str());
  result.event = notes_.back();
  initialised_ = true;
}

void FrontEnd::UseFittedRotation(const MotionRefit& refit, int64_t t_a_ns, int64_t t_b_ns) {
  const size_t window = static_cast<size_t>(options_.time_offset_window);
  if (options_.keep_fitted_rotations || options_.estimate_time_offset) {
    if (std::optional<RotationObservation> observed =
            RotationObservationFromFit(refit, cam_from_imu_, t_a_ns, t_b_ns)) {
      fitted_rotations_.push_back(*observed);
      ++rotations_seen_;
      if (!options_.keep_fitted_rotations && fitted_rotations_.size() > window) {
        fitted_rotations_.erase(fitted_rotations_.begin());  // a live feed keeps its window only
      }
    }
  }
  if (options_.estimate_time_offset &&
      rotations_seen_ >= rotations_at_estimate_ + static_cast<size_t>(options_.time_offset_every) &&
      static_cast<int>(fitted_rotations_.size()) >= options_.time_offset.min_observations) {
    rotations_at_estimate_ = rotations_seen_;
    const std::vector<RotationObservation> recent(
        fitted_rotations_.end() -
            static_cast<std::ptrdiff_t>(std::min(window, fitted_rotations_.size())),
        fitted_rotations_.end());
    TimeOffsetEstimate estimate =
        TryEstimateTimeOffset(imu_, imu_params_, bias_.gyro, recent, options_.time_offset);
    if (estimate.measured) imu_offset_ns_ = SecondsToNs(estimate.offset_s);  // else kept
    online_offset_ = std::move(estimate);
  }
  if (!gyro_bias_filter_) return;
  UpdateGyroBiasFromFit(refit, cam_from_imu_, imu_, imu_params_, t_a_ns + imu_offset_ns_,
                        t_b_ns + imu_offset_ns_, &*gyro_bias_filter_);
  bias_.gyro = gyro_bias_filter_->bias();
  gyro_bias_sigma_ = gyro_bias_filter_->SigmaAt(t_b_ns);
  bias_t_ns_ = t_b_ns;
}

namespace {

// The frame's image as 8-bit gray; InvalidArgument for an empty image, one of another size than
// the camera's, a depth image not 16-bit or of another size, a time not after the previous frame.
cv::Mat CheckedGray(const FrontEndFrame& frame, const PinholeCamera& camera,
                    const std::optional<int64_t>& previous_t_ns) {
  IMUMATCH_CHECK(!frame.image.empty(), "empty image at t = " << frame.t_ns << " ns");
  IMUMATCH_CHECK(frame.image.cols == camera.width && frame.image.rows == camera.height,
                 "image of " << frame.image.cols << "x" << frame.image.rows
                             << " at t = " << frame.t_ns << " ns; the camera is " << camera.width
                             << "x" << camera.height);
  IMUMATCH_CHECK(frame.depth.empty() ||
                     (frame.depth.type() == CV_16UC1 && frame.depth.size() == frame.image.size()),
                 "depth at t = " << frame.t_ns << " ns must be 16-bit and of the image's size");
  IMUMATCH_CHECK(!previous_t_ns || frame.t_ns > *previous_t_ns,
                 "frame at t = " << frame.t_ns << " ns is not after the previous one");
  cv::Mat gray = frame.image;
  if (gray.channels() == 3) {
    cv::cvtColor(frame.image, gray, cv::COLOR_BGR2GRAY);
  }
  IMUMATCH_CHECK(gray.type() == CV_8UC1, "image at t = " << frame.t_ns << " ns must be 8-bit");
  return gray;
}

}  // namespace

FrontEndResult FrontEnd::Process(const FrontEndFrame& frame) {
  const auto start = SteadyClock::now();
  const cv::Mat gray =
      CheckedGray(frame, undistorter_.camera(),
                  previous_ ? std::optional<int64_t>(previous_->t_ns) : std::nullopt);
  FrontEndResult result;
  result.t_ns = frame.t_ns;

  auto t0 = SteadyClock::now();
  Features features = ExtractFeatures(gray, options_.features, field_mask_);
  features.descriptors = PadBinaryDescriptors(features.descriptors);
  std::vector<KeypointInfo> ideal = ToIdealKeypointInfos(features.keypoints, undistorter_);
  result.extract_ms = MsSince(t0);
  result.keypoints = features.keypoints;

  if (!initialised_ || !previous_) {
    result.status = FrameStatus::kFirst;
    if (!initialised_) Initialise(frame.t_ns, result);
    result.has_state = initialised_;
    result.world_from_cam = world_from_imu_ * cam_from_imu_.Inverse();
    result.velocity_in_world = velocity_;
    result.velocity_sigma = velocity_sigma_;
    Remember(frame, gray, std::move(features), std::move(ideal), result.world_from_cam);
    result.total_ms = MsSince(start);
    return result;
  }
  const Previous& prev = *previous_;

  t0 = SteadyClock::now();
  ImuPreintegration pim;
  const bool imu_ok = MotionFromImu(prev.t_ns, frame.t_ns, result, pim);
  result.motion_ms = MsSince(t0);

  t0 = SteadyClock::now();
  SceneNearDepth scene;  // where the first pass's segments start, kept by the second
  FirstPass(features, ideal, gray, imu_ok, scene, result);
  result.match1_ms = MsSince(t0);

  t0 = SteadyClock::now();
  const PoseFitError fit = FitPose(features, imu_ok, result);
  result.pose_ms = MsSince(t0);

  bool pnp_refused = false;  // PnP's pose not used (SecondPass)
  if (options_.second_pass && result.pose.ok && result.status == FrameStatus::kGuided) {
    t0 = SteadyClock::now();
    pnp_refused = !SecondPass(features, ideal, gray, frame.t_ns, fit, scene, result);
    result.match2_ms = MsSince(t0);
  }

  UpdateState(frame.t_ns, pim, imu_ok, pnp_refused, fit, result);
  Remember(frame, gray, std::move(features), std::move(ideal), result.world_from_cam);
  result.total_ms = MsSince(start);
  return result;
}

void FrontEnd::Remember(const FrontEndFrame& frame, const cv::Mat& gray, Features features,
                        std::vector<KeypointInfo> ideal, const Rigid3d& world_from_cam) {
  Previous p;
  p.t_ns = frame.t_ns;
  p.image = gray.data == frame.image.data ? gray.clone() : gray;  // the caller may reuse buffers
  p.depth = frame.depth.clone();
  if (!frame.depth.empty()) {
    p.depths = SampleDepths(frame.depth, undistorter_.camera().depth_scale, features.keypoints,
                            options_.prediction.depth_sampling);
  }
  p.features = std::move(features);
  p.ideal = std::move(ideal);
  p.world_from_cam = world_from_cam;
  previous_ = std::move(p);
}

bool FrontEnd::MotionFromImu(int64_t t_a_ns, int64_t t_b_ns, FrontEndResult& result,
                             ImuPreintegration& pim) const {
  try {
    ImuStateAtFrame state;
    state.world_from_imu = world_from_imu_;
    state.velocity_in_world = velocity_;
    state.bias = bias_;
    CameraMotionOptions mo = options_.motion;
    mo.velocity_sigma = velocity_sigma_;
    const double since = std::max(0.0, NsToSeconds(t_a_ns - bias_t_ns_));
    mo.gyro_bias_sigma =
        std::sqrt(gyro_bias_sigma_ * gyro_bias_sigma_ +
                  imu_params_.gyro_random_walk * imu_params_.gyro_random_walk * since);
    // The frames' stamps in the IMU's clock (estimate_time_offset; else the same).
    const int64_t imu_a_ns = t_a_ns + imu_offset_ns_, imu_b_ns = t_b_ns + imu_offset_ns_;
    result.imu_motion =
        ComputeCameraMotion(imu_, imu_a_ns, imu_b_ns, state, imu_params_, cam_from_imu_, mo);
    pim = Preintegrate(imu_.Slice(imu_a_ns, imu_b_ns), bias_, imu_params_);
  } catch (const Error& e) {
    result.event = std::string("IMU gap: ") + e.what();
    return false;
  }
  return true;
}

void FrontEnd::UpdateState(int64_t t_ns, const ImuPreintegration& pim, bool imu_ok,
                           bool pnp_refused, const PoseFitError& fit, FrontEndResult& result) {
  const Previous& prev = *previous_;
  const double dt = NsToSeconds(t_ns - prev.t_ns);
  result.world_from_cam = prev.world_from_cam * result.cam_from_prev.Inverse();
  const Rigid3d world_from_imu_b = result.world_from_cam * cam_from_imu_;
  Eigen::Vector3d v = velocity_;
  double sigma = options_.unknown_velocity_sigma;
  Eigen::Quaterniond attitude = world_from_imu_b.rotation;
  if (imu_ok) {
    NavState a;
    a.t_ns = pim.t0_ns;  // the previous frame in the IMU's clock (estimate_time_offset)
    a.world_from_imu = world_from_imu_;
    a.velocity_in_world = velocity_;
    const NavState b = Propagate(a, pim, imu_params_.gravity_in_world);
    attitude = b.world_from_imu.rotation;  // the gyro's
    v = b.velocity_in_world;
    // Since the last fix: the accelerometer bias's error integrated (linear in time) and the
    // white noise's (a random walk). Summed per frame as a random walk, the bias's share was
    // sqrt(dt / t) of this: 12x too small after 8 s without depth at 20 Hz.
    const double since_fix = std::max(0.0, NsToSeconds(t_ns - velocity_fix_t_ns_));
    sigma =
        std::sqrt(velocity_fix_sigma_ * velocity_fix_sigma_ +
                  std::pow(options_.motion.accel_bias_sigma * since_fix, 2) +
                  imu_params_.accel_noise_density * imu_params_.accel_noise_density * since_fix);
    if (result.pose_from_depth && !pnp_refused) {
      // The velocity that explains the fitted translation, given the IMU's increments.
      const Eigen::Matrix3d ra = world_from_imu_.rotation.toRotationMatrix();
      const Eigen::Vector3d& g = imu_params_.gravity_in_world;
      const Eigen::Vector3d pa = (prev.world_from_cam * cam_from_imu_).translation;
      const Eigen::Vector3d va =
          (world_from_imu_b.translation - pa - ra * pim.delta_position - 0.5 * g * dt * dt) / dt;
      const Eigen::Vector3d vb = va + ra * pim.delta_velocity + g * dt;
      const double sm = std::max(0.002, fit.translation_sigma) / dt;
      const double wp = 1.0 / (sigma * sigma), wm = 1.0 / (sm * sm);
      v = (wp * v + wm * vb) / (wp + wm);
      sigma = std::sqrt(1.0 / (wp + wm));
      velocity_fix_sigma_ = std::max(options_.min_velocity_sigma, sigma);
      velocity_fix_t_ns_ = t_ns;
    }
  }
  if (result.status == FrameStatus::kBruteForce || !imu_ok) {
    sigma = std::max(sigma, options_.unknown_velocity_sigma);  // re-initialised
    velocity_fix_sigma_ = sigma;
    velocity_fix_t_ns_ = t_ns;
  }
  world_from_imu_ = Rigid3d(attitude, world_from_imu_b.translation);
  velocity_ = v;
  velocity_sigma_ = std::max(options_.min_velocity_sigma, sigma);
  result.velocity_in_world = velocity_;
  result.velocity_sigma = velocity_sigma_;
  result.has_state = true;
}

}  // namespace imumatch
