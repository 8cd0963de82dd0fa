#include "imumatch/sim/synthetic_sequence.h"

#include <cmath>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/sim/imu_simulator.h"

namespace imumatch {

void SyntheticSequenceOptions::Check() const {
  motion_options.Check();
  IMUMATCH_CHECK(
      std::isfinite(frame_rate_hz) && frame_rate_hz > 0.0 && frame_rate_hz <= 1000.0,
      "SyntheticSequenceOptions.frame_rate_hz must be in (0, 1000], got " << frame_rate_hz);
  for (size_t i = 0; i < frame_times_s.size(); ++i) {
    IMUMATCH_CHECK(std::isfinite(frame_times_s[i]) && frame_times_s[i] >= 0.0,
                   "SyntheticSequenceOptions.frame_times_s[" << i << "] must be finite and >= 0");
    IMUMATCH_CHECK(
        i == 0 || frame_times_s[i] > frame_times_s[i - 1],
        "SyntheticSequenceOptions.frame_times_s must be strictly increasing (index " << i << ")");
  }
  camera.Check();
  IMUMATCH_CHECK(cam_from_imu.rotation.coeffs().allFinite() && cam_from_imu.translation.allFinite(),
                 "SyntheticSequenceOptions.cam_from_imu must be finite");
  IMUMATCH_CHECK(imu_initial_bias.gyro.allFinite() && imu_initial_bias.accel.allFinite(),
                 "SyntheticSequenceOptions.imu_initial_bias must be finite");
  ImuParams::FromName(imu_model).Check();
  scene.Check();
  render.Check();
  IMUMATCH_CHECK(std::isfinite(odd_frame_gain) && odd_frame_gain > 0.0 && odd_frame_gain <= 100.0,
                 "odd_frame_gain = " << odd_frame_gain);
}

SyntheticSequence MakeSyntheticSequence(const SyntheticSequenceOptions& options) {
  options.Check();
  const Scene scene(options.scene);
  return MakeSyntheticSequence(options, scene);
}

SyntheticSequence MakeSyntheticSequence(const SyntheticSequenceOptions& options,
                                        const Scene& scene) {
  options.Check();
  const std::unique_ptr<Trajectory> trajectory = MakeMotion(options.motion, options.motion_options);
  return MakeSyntheticSequence(*trajectory, options, scene);
}

SyntheticSequence MakeSyntheticSequence(const Trajectory& trajectory,
                                        const SyntheticSequenceOptions& options,
                                        const Scene& scene) {
  options.Check();
  const double t_start = trajectory.StartTime(), t_end = trajectory.EndTime();
  IMUMATCH_CHECK(t_end > t_start, "MakeSyntheticSequence: the trajectory has an empty time span");
  // Bounded work, checked before anything is simulated or rendered.
  const double frames_needed = options.frame_times_s.empty()
                                   ? std::floor((t_end - t_start) * options.frame_rate_hz) + 1.0
                                   : static_cast<double>(options.frame_times_s.size());
  IMUMATCH_CHECK(frames_needed <= SyntheticSequenceOptions::kMaxFrames,
                 "MakeSyntheticSequence: "
                     << frames_needed << " frames (" << (t_end - t_start) << " s at "
                     << options.frame_rate_hz << " Hz) is more than the "
                     << SyntheticSequenceOptions::kMaxFrames << " a synthetic sequence may have");
  IMUMATCH_CHECK(t_end - t_start <= SyntheticSequenceOptions::kMaxDurationS,
                 "MakeSyntheticSequence: " << (t_end - t_start) << " s is longer than the "
                                           << SyntheticSequenceOptions::kMaxDurationS
                                           << " s a synthetic sequence may last");
  std::vector<double> times = options.frame_times_s;
  if (times.empty()) {
    for (int k = 0;; ++k) {
      const double t = t_start + k / options.frame_rate_hz;
      if (t > t_end + 1e-9) break;
      times.push_back(t);
    }
  }
  for (double t : times) {
    IMUMATCH_CHECK(t >= t_start - 1e-9 && t <= t_end + 1e-9,
                   "MakeSyntheticSequence: frame time " << t << " s is outside the trajectory ["
                                                        << t_start << ", " << t_end << "] s");
  }

  SyntheticSequence seq;
  seq.motion = options.motion;
  seq.camera = options.camera;
  seq.cam_from_imu = options.cam_from_imu;
  seq.imu_params = ImuParams::FromName(options.imu_model);
  seq.imu_initial_bias = options.imu_initial_bias;

  ImuSimulatorOptions imu_options;
  imu_options.rate_hz = seq.imu_params.rate_hz;
  imu_options.seed = options.imu_seed;
  imu_options.initial_bias = options.imu_initial_bias;
  imu_options.t0_ns = options.t0_ns;
  seq.imu = SimulateImu(trajectory, seq.imu_params, imu_options);

  const Rigid3d imu_from_cam = options.cam_from_imu.Inverse();
  RenderOptions render = options.render;
  const LensRayMap lens_rays(options.camera);  // once for all frames
  for (size_t k = 0; k < times.size(); ++k) {
    SyntheticFrame frame;
    frame.t_ns = options.t0_ns + SecondsToNs(times[k]);
    frame.world_from_imu = trajectory.WorldFromBody(times[k]);
    frame.world_from_cam = frame.world_from_imu * imu_from_cam;
    frame.imu_velocity_in_world = trajectory.VelocityInWorld(times[k]);
    render.depth_noise.seed = options.render.depth_noise.seed + k;
    RenderedView view = RenderView(scene, options.camera, frame.world_from_cam, render, &lens_rays);
    if (options.odd_frame_gain != 1.0 && k % 2 == 1) {
      view.rgb.convertTo(frame.rgb, -1, options.odd_frame_gain);
    } else {
      frame.rgb = std::move(view.rgb);
    }
    frame.depth = std::move(view.depth);
    seq.frames.push_back(std::move(frame));
  }
  return seq;
}

}  // namespace imumatch
