#include "imumatch/eval/pair_motion.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/eval/pipelined.h"
#include "imumatch/imu/imu_integrator.h"

namespace imumatch {

std::optional<Eigen::Vector3d> ImuVelocityAt(const Dataset& dataset, size_t index) {
  const auto& frames = dataset.frames;
  if (frames[index].imu_velocity_in_world) return frames[index].imu_velocity_in_world;
  const size_t lo = index > 0 ? index - 1 : index;
  const size_t hi = index + 1 < frames.size() ? index + 1 : index;
  if (lo == hi || !frames[lo].world_from_cam || !frames[hi].world_from_cam) return std::nullopt;
  const double dt = NsToSeconds(frames[hi].t_ns - frames[lo].t_ns);
  if (!(dt > 0.0)) return std::nullopt;
  const Eigen::Vector3d p_hi =
      (*frames[hi].world_from_cam * dataset.cam_from_imu.Inverse()).translation;
  const Eigen::Vector3d p_lo =
      (*frames[lo].world_from_cam * dataset.cam_from_imu.Inverse()).translation;
  return (p_hi - p_lo) / dt;
}

ImuBiasEstimate EstimateImuBias(const Dataset& dataset, double still_s) {
  ImuBiasEstimate out;
  if (dataset.imu.empty()) return out;
  if (dataset.imu_simulated) {
    out.note = "IMU bias: simulated IMU, integrated without a bias estimate";
    return out;
  }
  if (!(still_s > 0.0)) {
    out.note = "IMU bias: not estimated (still period 0 s), assumed zero";
    return out;
  }
  const int64_t t0 = dataset.imu.begin_ns();
  const int64_t t1 = std::min(dataset.imu.end_ns(), t0 + SecondsToNs(still_s));
  std::ostringstream note;
  note << std::scientific << std::setprecision(2);
  try {
    const StillInitialization init = InitializeFromStill(dataset.imu, t0, t1, dataset.imu_params);
    out.bias = init.bias;
    out.from_still_start = true;
    out.estimated = true;
    out.gyro_bias_sigma = init.gyro_bias_sigma;
    out.t_ns = init.end_ns;
    note << "IMU gyro bias from the still start of the log (" << init.num_samples
         << " samples): " << init.bias.gyro.x() << " " << init.bias.gyro.y() << " "
         << init.bias.gyro.z() << " rad/s (+- " << init.gyro_bias_sigma << ")";
    if (init.end_ns < t1) note << "; the still period ends at an IMU gap";
  } catch (const InvalidArgument& e) {
    note << "IMU bias: the first " << still_s << " s of the IMU log are not still (" << e.what()
         << "): gyro bias assumed zero";
  }
  out.note = note.str();
  return out;
}

std::optional<PairMotion> ComputePairMotion(const Dataset& dataset, const FramePair& pair,
                                            size_t pair_index, const EvaluationOptions& options,
                                            const ImuBiasEstimate& bias, std::string& reason) {
  const FrameRecord& fa = dataset.frames[pair.a];
  const FrameRecord& fb = dataset.frames[pair.b];
  PairMotion out;
  const auto t0 = SteadyClock::now();
  if (options.motion_source == MotionSource::kGroundTruth) {
    out.motion = CameraMotionFromPoses(fa.t_ns, *fa.world_from_cam, fb.t_ns, *fb.world_from_cam);
    out.ms = MsSince(t0);
    return out;
  }
  if (dataset.imu.empty()) {
    reason = "no IMU data in the dataset (use --motion-source gt)";
    return std::nullopt;
  }
  const std::optional<Eigen::Vector3d> velocity = ImuVelocityAt(dataset, pair.a);
  if (!velocity) {
    reason = "no ground-truth velocity at frame A to seed the IMU integration";
    return std::nullopt;
  }
  // The state a VIO back-end would supply: ground truth perturbed by the stated sigmas.
  const double v_sigma = options.velocity_perturbation_sigma >= 0.0
                             ? options.velocity_perturbation_sigma
                             : options.motion.velocity_sigma;
  const double a_sigma = options.attitude_perturbation_sigma >= 0.0
                             ? options.attitude_perturbation_sigma
                             : options.motion.attitude_sigma;
  std::mt19937_64 rng(options.seed + 1000003ULL * pair_index);
  std::normal_distribution<double> normal(0.0, 1.0);
  ImuStateAtFrame state;
  const Rigid3d world_from_imu = *fa.world_from_cam * dataset.cam_from_imu;
  const Eigen::Vector3d tilt(a_sigma * normal(rng), a_sigma * normal(rng), 0.0);
  state.world_from_imu = Rigid3d(Eigen::Quaterniond(ExpSO3(tilt)) * world_from_imu.rotation,
                                 world_from_imu.translation);
  state.velocity_in_world =
      *velocity + v_sigma * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  state.bias = bias.bias;
  CameraMotionOptions motion_options = options.motion;
  if (bias.estimated) {
    const double since_s = std::max(0.0, NsToSeconds(fa.t_ns - bias.t_ns));
    const double walk = dataset.imu_params.gyro_random_walk;
    motion_options.gyro_bias_sigma =
        std::sqrt(bias.gyro_bias_sigma * bias.gyro_bias_sigma + walk * walk * since_s);
  }
  try {
    out.motion = ComputeCameraMotion(dataset.imu, fa.t_ns, fb.t_ns, state, dataset.imu_params,
                                     dataset.cam_from_imu, motion_options);
  } catch (const OutOfRange& e) {
    reason = std::string("IMU interval not available: ") + e.what();
    return std::nullopt;
  }
  out.ms = MsSince(t0);
  return out;
}

}  // namespace imumatch
