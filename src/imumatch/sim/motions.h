#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "imumatch/core/rigid3.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {

// The synthetic rig: the trajectories below describe the body = IMU frame (x forward, y left,
// z up when level). The camera (x right, y down, z forward = optical axis) looks along the IMU's
// x axis: cam_from_imu maps imu x -> cam z, imu y -> cam -x, imu z -> cam -y, and the IMU origin
// sits at (0.02, 0.005, -0.01) m in the camera frame (a 2 cm lever arm).
Rigid3d SyntheticCamFromImu();

// Default start pose of the body in the synthetic room (see scene.h): level, at (-1.0, 0.0, 1.4) m,
// facing world +x, so the camera looks horizontally into the room.
Rigid3d SyntheticStartWorldFromBody();

struct MotionOptions {
  // Every motion is still for still_before_s, moves for duration_s, then is still for
  // still_after_s (so an IMU can be initialised from the still start). The seed cases compare
  // the frames at t = still_before_s and t = still_before_s + duration_s.
  double duration_s = 2.0;
  double still_before_s = 0.5;
  double still_after_s = 0.5;
  // "front1m"/"back1m": translation along the body x axis (= the optical axis), metres.
  double distance_m = 1.0;
  // "left30"/"right30": rotation about the world vertical axis, degrees (left = counter-clockwise
  // seen from above).
  double angle_deg = 30.0;
  // "shake": scale of the handheld shake (1 = a few cm and a few degrees).
  double shake_scale = 1.0;
  // "fast_rotation": peak yaw rate (deg/s), with a roll wobble of roll_amplitude_deg.
  double yaw_rate_deg_s = 180.0;
  double roll_amplitude_deg = 10.0;
  // "roll45": roll rate about the optical axis (deg/s), ramped up and down over 0.2 s.
  double roll_rate_deg_s = 45.0;
  // "walk": peak forward speed (m/s), plus step bobbing, sway and head rotation.
  double walk_speed_m_s = 0.8;
  Rigid3d world_from_body_start = SyntheticStartWorldFromBody();

  // Throws InvalidArgument for negative times, a non-positive duration or non-finite values.
  void Check() const;
  double MotionStartTime() const { return still_before_s; }
  double MotionEndTime() const { return still_before_s + duration_s; }
};

// "front1m", "back1m", "left30", "right30", "shake", "fast_rotation", "walk", "roll45".
std::vector<std::string> MotionNames();

// A trajectory with analytic pose, velocity, acceleration and body angular velocity, defined on
// [0, still_before + duration + still_after]. Throws InvalidArgument for an unknown name (the
// message lists the valid ones) or bad options.
//  - front1m/back1m: minimum-jerk translation s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 of
//    +-distance_m along the start body x axis (the camera's optical axis), no rotation;
//  - left30/right30: minimum-jerk yaw of +-angle_deg about the world z axis through the body
//  origin;
//  - shake: sums of sinusoids, about 2-3 cm in translation and 2-3 deg in rotation, faded in/out;
//  - fast_rotation: yaw rate ramped to yaw_rate_deg_s and back, with a roll wobble;
//  - roll45: roll about the optical axis at roll_rate_deg_s (45 deg/s), ramped over 0.2 s: the
//    image turns in its plane;
//  - walk: forward speed ramped to walk_speed_m_s and back, with vertical bobbing (2 Hz), lateral
//    sway (1 Hz), and small head yaw/pitch/roll.
std::unique_ptr<Trajectory> MakeMotion(std::string_view name, const MotionOptions& options);

// The minimum-jerk step s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 (clamped to [0,1] outside), and its
// first and second derivatives with respect to tau.
double MinimumJerk(double tau, int derivative = 0);

}  // namespace imumatch
