#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "imumatch/eval/evaluation_options.h"
#include "imumatch/eval/pair_selection.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/io/dataset.h"

namespace imumatch {

// The IMU's velocity at a frame: the dataset's value, else a finite difference of the
// ground-truth poses of the neighbouring frames (IMU origin = world_from_cam * cam_from_imu).
std::optional<Eigen::Vector3d> ImuVelocityAt(const Dataset& dataset, size_t index);

// The IMU bias the integration removes. A recorded IMU log that starts at rest (every EuRoC
// sequence: the vehicle stands on the ground) tells the gyro bias: the mean gyro over the still
// period (InitializeFromStill, which also rejects a start that is not still). The accelerometer
// bias is not observable from one still period and stays zero (its sigma goes into the motion's
// covariance). A simulated IMU, or a log that does not start still, keeps a zero bias and the
// note says so.
struct ImuBiasEstimate {
  ImuBias bias;
  bool from_still_start = false;
  // bias.gyro and gyro_bias_sigma hold an estimate at t_ns (from the still start, or learnt from
  // the matches): the sigma the predictor is told grows from there by the gyro random walk.
  bool estimated = false;
  double gyro_bias_sigma = 0.0;  // standard error of the estimate (rad/s)
  int64_t t_ns = 0;              // end of the still period: the bias then walks (random walk)
  std::string note;              // one line for the report
};
// still_s: the length of the still period at the start of the IMU log (seconds; 0 = no estimate).
ImuBiasEstimate EstimateImuBias(const Dataset& dataset, double still_s);

struct PairMotion {
  CameraMotion motion;
  double ms = 0.0;
};

// The motion the predictor is given for a frame pair, or nullopt with a skip reason: the exact
// ground-truth motion (MotionSource::kGroundTruth), or the dataset's IMU integrated from the state
// at frame A (the ground truth perturbed by the stated sigmas, seeded with seed + pair index) with
// the estimated bias removed. With an estimated bias (estimated), the gyro bias sigma the predictor
// is told is the estimate's standard error grown by the gyro random walk since then,
// sqrt(sigma^2 + gyro_random_walk^2 (t_a - t_still)), instead of options.motion.gyro_bias_sigma.
std::optional<PairMotion> ComputePairMotion(const Dataset& dataset, const FramePair& pair,
                                            size_t pair_index, const EvaluationOptions& options,
                                            const ImuBiasEstimate& bias, std::string& reason);

}  // namespace imumatch
