// imumatch imu: IMU demo on a recorded (EuRoC) or simulated (TUM, synthetic) IMU log. Initialises
// the gyro bias and gravity direction from the still start, then integrates over consecutive
// camera frame intervals and prints the camera's delta rotation per interval (with and without
// the bias removed) next to the ground truth when the dataset has it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/io/dataset.h"
#include "number_checks.h"

namespace imumatch::apps {
namespace {

struct ImuArgs {
  std::string path;
  double still_s = 1.0;
  size_t max_frames = 20;
  std::string mode = "so3";
};

// One line of the table: the IMU's delta rotation between frames i and i + 1 with the bias
// removed and raw, the ground truth's, the stated sigma; then nav moves on to frame i + 1.
// Throws OutOfRange when the IMU log has a gap between the frames.
void PrintPair(const Dataset& d, size_t i, NavState& nav, const ImuBias& bias,
               const CameraMotionOptions& motion_options) {
  const int64_t ta = d.frames[i].t_ns, tb = d.frames[i + 1].t_ns;
  ImuStateAtFrame state;
  state.world_from_imu = nav.world_from_imu;
  state.velocity_in_world = nav.velocity_in_world;
  state.bias = bias;
  const CameraMotion m =
      ComputeCameraMotion(d.imu, ta, tb, state, d.imu_params, d.cam_from_imu, motion_options);
  ImuStateAtFrame raw_state = state;
  raw_state.bias = ImuBias();
  const CameraMotion raw =
      ComputeCameraMotion(d.imu, ta, tb, raw_state, d.imu_params, d.cam_from_imu, motion_options);
  char gt[32] = "-";
  if (d.frames[i].world_from_cam && d.frames[i + 1].world_from_cam) {
    const CameraMotion truth =
        CameraMotionFromPoses(ta, *d.frames[i].world_from_cam, tb, *d.frames[i + 1].world_from_cam);
    std::snprintf(gt, sizeof(gt), "%.4f",
                  RotationAngle(truth.cam_b_from_cam_a.rotation) * kRadToDeg);
  }
  const double sigma = std::sqrt(std::max(0.0, m.covariance.topLeftCorner<3, 3>().trace()));
  std::printf("%5zu %18s %7.2f %12.4f %12.4f %12s %10.4f\n", i, FormatNsAsSeconds(ta).c_str(),
              NsToSeconds(tb - ta) * 1e3, RotationAngle(m.cam_b_from_cam_a.rotation) * kRadToDeg,
              RotationAngle(raw.cam_b_from_cam_a.rotation) * kRadToDeg, gt, sigma * kRadToDeg);
  const ImuPreintegration pim = Preintegrate(d.imu.Slice(ta, tb), bias, d.imu_params);
  nav = Propagate(nav, pim, d.imu_params.gravity_in_world);
}

void RunImu(const ImuArgs& a) {
  IMUMATCH_REQUIRE(a.still_s >= 0.0, "--still must be >= 0");
  IMUMATCH_REQUIRE(a.max_frames != 1,
                   "--frames must be 0 (all) or at least 2: one frame has "
                   "no interval to integrate over");
  DatasetOptions options;
  options.max_frames = a.max_frames;
  const Dataset d = LoadDataset(a.path, options);
  std::cout << "dataset " << d.name << " (" << ToString(d.kind) << "): " << d.frames.size()
            << " frames, " << d.imu.size() << " IMU samples\n"
            << d.imu_source_note << "\n";
  if (d.imu.empty()) throw InvalidArgument("the dataset has no IMU data");
  if (d.frames.size() < 2) {
    throw InputError(a.path, d.name + " has " + std::to_string(d.frames.size()) +
                                 (d.frames.size() == 1 ? " frame" : " frames") +
                                 ": the camera's frame intervals need at least two");
  }

  const int64_t t_still0 = d.imu.begin_ns();
  const int64_t t_still1 = std::min(d.imu.end_ns(), t_still0 + SecondsToNs(a.still_s));
  StillInitialization init;
  init.end_ns = t_still0;  // no still start: no bias estimate, the attitude starts level
  std::string no_still = "--still 0";
  if (a.still_s > 0.0) {
    try {
      init = InitializeFromStill(d.imu, t_still0, t_still1, d.imu_params);
      no_still.clear();
    } catch (const InvalidArgument& e) {
      // A log that starts in motion (hand-held, an excerpt): the rotations are still integrated,
      // with the bias left in (the two rotation columns then agree).
      no_still = e.what();
    }
  }
  if (no_still.empty()) {
    std::printf(
        "still start %.3f s (%d samples): gyro bias %+.5f %+.5f %+.5f rad/s (+- %.1e), "
        "gravity in IMU %+.3f %+.3f %+.3f m/s^2\n",
        NsToSeconds(init.end_ns - t_still0), init.num_samples, init.bias.gyro.x(),
        init.bias.gyro.y(), init.bias.gyro.z(), init.gyro_bias_sigma, init.gravity_in_imu.x(),
        init.gravity_in_imu.y(), init.gravity_in_imu.z());
    if (init.end_ns < t_still1) {
      std::printf("(the still period ends at an IMU gap at %s s)\n",
                  FormatNsAsSeconds(init.end_ns).c_str());
    }
  } else {
    std::printf("no still start (%s): gyro bias not estimated (zero)\n", no_still.c_str());
  }

  CameraMotionOptions motion_options;
  motion_options.mode = ParseIntegrationMode(a.mode);
  NavState nav;
  nav.world_from_imu = init.world_from_imu;
  std::printf("%5s %18s %7s %12s %12s %12s %10s\n", "pair", "t_a [s]", "dt[ms]", "rot[deg]",
              "raw_rot[deg]", "gt_rot[deg]", "sigma[deg]");
  bool nav_valid = false;
  int printed = 0, skipped = 0;
  for (size_t i = 0; i + 1 < d.frames.size(); ++i) {
    const int64_t ta = d.frames[i].t_ns, tb = d.frames[i + 1].t_ns;
    if (ta < d.imu.begin_ns() || tb > d.imu.end_ns()) continue;
    if (!nav_valid) {
      // Propagate from the start of the still period (at rest) to the first frame; across a gap
      // in the log the attitude stays the still period's (the rotations printed do not use it).
      nav.t_ns = t_still0;
      if (ta > t_still0) {
        try {
          const ImuPreintegration pim =
              Preintegrate(d.imu.Slice(t_still0, ta), init.bias, d.imu_params);
          nav = Propagate(nav, pim, d.imu_params.gravity_in_world);
        } catch (const OutOfRange& e) {
          std::printf("attitude not propagated to the first frame: %s\n", e.what());
          nav.t_ns = ta;
        }
      }
      if (d.frames[i].imu_velocity_in_world)
        nav.velocity_in_world = *d.frames[i].imu_velocity_in_world;
      nav_valid = true;
    }
    try {
      PrintPair(d, i, nav, init.bias, motion_options);
      ++printed;
    } catch (const OutOfRange& e) {
      // A gap in the log: the pair is skipped and the state restarts after it (velocity from the
      // ground truth when the dataset has it; the attitude as before the gap).
      std::printf("%5zu %18s skipped: %s\n", i, FormatNsAsSeconds(ta).c_str(), e.what());
      ++skipped;
      nav.t_ns = tb;
      if (d.frames[i + 1].imu_velocity_in_world)
        nav.velocity_in_world = *d.frames[i + 1].imu_velocity_in_world;
    }
  }
  if (printed == 0) {
    throw InvalidArgument("no frame interval lies inside the IMU log" +
                          std::string(skipped > 0 ? " without a gap" : ""));
  }
  const size_t intervals = d.frames.size() - 1;
  if (static_cast<size_t>(printed) < intervals) {
    std::printf(
        "note: %d of %zu frame intervals printed; of the others %d cross a gap in the IMU log and "
        "%zu lie outside it (%s .. %s s)\n",
        printed, intervals, skipped, intervals - printed - skipped,
        FormatNsAsSeconds(d.imu.begin_ns()).c_str(), FormatNsAsSeconds(d.imu.end_ns()).c_str());
  }
  for (const std::string& w : d.warnings) std::printf("warning: %s\n", w.c_str());
}

}  // namespace

void AddImuCommand(CLI::App& app) {
  auto args = std::make_shared<ImuArgs>();
  CLI::App* sub = app.add_subcommand(
      "imu",
      "IMU demo: initialise from the still start, integrate between consecutive camera frames and "
      "print the camera's delta rotations (bias removed, raw, ground truth).");
  auto* euroc = sub->add_option("--euroc", args->path, "EuRoC folder (holding mav0/, or mav0)");
  auto* dataset = sub->add_option("--dataset", args->path,
                                  "Any dataset folder (TUM RGB-D, EuRoC, imumatch synth)");
  euroc->excludes(dataset);
  sub->add_option("--still", args->still_s,
                  "Length of the still start (s; 0 = none: the gyro bias is not estimated, as when "
                  "the log does not start still)")
      ->capture_default_str()
      ->check(NonNegativeFinite());
  sub->add_option("--frames", args->max_frames, "Number of frames to use (0 = all)")
      ->capture_default_str();
  sub->add_option("--mode", args->mode, "Integration mode: so3 or paper")->capture_default_str();
  sub->callback([args] {
    if (args->path.empty()) throw InvalidArgument("give --euroc DIR or --dataset DIR");
    RunImu(*args);
  });
}

}  // namespace imumatch::apps
