#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/core/types.h"
#include "imumatch/imu/imu_params.h"
#include "imumatch/sim/motions.h"
#include "imumatch/sim/renderer.h"
#include "imumatch/sim/scene.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {

struct SyntheticSequenceOptions {
  // Bounds on the work a sequence may ask for (checked before simulating or rendering): frames
  // (about 0.1 s and 1 MB of PNG each at 640 x 480) and the trajectory's span (the IMU is
  // simulated over all of it).
  static constexpr int kMaxFrames = 20000;
  static constexpr double kMaxDurationS = 3600.0;
  std::string motion = "front1m";  // a MotionNames() entry
  MotionOptions motion_options;
  // Frames at t = k / frame_rate_hz over the whole trajectory, unless frame_times_s is given:
  // then exactly those trajectory times (strictly increasing, within the trajectory), e.g.
  // {motion_options.MotionStartTime(), motion_options.MotionEndTime()} for a seed pair.
  double frame_rate_hz = 30.0;
  std::vector<double> frame_times_s;
  PinholeCamera camera = PinholeCamera::KinectDefault();  // either lens model
  Rigid3d cam_from_imu = SyntheticCamFromImu();
  std::string imu_model = "euroc";  // ImuParams::FromName: "euroc", "mems", "ideal"
  uint64_t imu_seed = 42;
  ImuBias imu_initial_bias;  // constant bias at t = 0 (the random walk starts from it)
  int64_t t0_ns = 0;         // timestamp of trajectory time 0
  SceneOptions scene;
  // Rendering and depth noise. Frame k uses depth_noise.seed + k, so noise differs between frames.
  RenderOptions render;
  // Exposure flicker (auto-exposure): frames with an odd index are rendered with their intensities
  // multiplied by this gain (saturated to 8 bits), so consecutive frames differ by it. 1 = off.
  double odd_frame_gain = 1.0;
  void Check() const;
};

struct SyntheticFrame {
  int64_t t_ns = 0;
  cv::Mat rgb;             // CV_8UC3, OpenCV BGR order
  cv::Mat depth;           // CV_16U, camera.depth_scale units per metre (5000), 0 = no depth
  Rigid3d world_from_cam;  // exact
  Rigid3d world_from_imu;  // exact
  Eigen::Vector3d imu_velocity_in_world = Eigen::Vector3d::Zero();  // exact
};

struct SyntheticSequence {
  std::string motion;
  PinholeCamera camera;
  std::vector<SyntheticFrame> frames;
  std::vector<ImuSample> imu;  // from SimulateImu at imu_params.rate_hz, starting at t0_ns
  ImuParams imu_params;
  ImuBias imu_initial_bias;
  Rigid3d cam_from_imu;
};

// Renders the named motion through the default synthetic room and simulates its IMU. No file I/O.
// Throws InvalidArgument for bad options (unknown motion or IMU model, an invalid camera, frame
// times outside the trajectory or not increasing).
SyntheticSequence MakeSyntheticSequence(const SyntheticSequenceOptions& options);
// Same with a prebuilt scene (options.scene is ignored), e.g. to share its textures.
SyntheticSequence MakeSyntheticSequence(const SyntheticSequenceOptions& options,
                                        const Scene& scene);
// Same for any trajectory of the IMU (e.g. a SplineTrajectory); options.motion and
// options.motion_options are ignored, options.motion names the result.
SyntheticSequence MakeSyntheticSequence(const Trajectory& world_from_imu,
                                        const SyntheticSequenceOptions& options,
                                        const Scene& scene);

}  // namespace imumatch
