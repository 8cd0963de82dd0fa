// imumatch synth: render a synthetic RGB-D + IMU sequence along a named motion and write it as a
// TUM RGB-D style folder (see imumatch/io/synthetic_io.h) that 'imumatch' commands can load.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/euroc_writer.h"
#include "imumatch/io/output_files.h"
#include "imumatch/io/synthetic_io.h"
#include "imumatch/sim/motions.h"
#include "imumatch/sim/synthetic_sequence.h"
#include "number_checks.h"

namespace imumatch::apps {
namespace {

struct SynthArgs {
  std::string motion;
  std::string out;
  double fps = 30.0;
  std::string imu = "euroc";
  uint64_t seed = 42;
  bool depth_noise = false;
  bool depth_holes = false;
  int width = 640;
  double duration_s = -1.0;  // < 0: the motion's default
  double still_s = -1.0;
  double t0_s = 0.0;
  double texel_m = 0.005;
  double gain = 1.0;
  bool overwrite = false;
  std::string camera = "kinect";
  std::string format = "tum";
  CLI::Option* width_option = nullptr;
};

// The camera to render with: a named one or a text intrinsics file (ReadCameraFromText).
PinholeCamera SynthCamera(const SynthArgs& a) {
  if (a.camera == "kinect") {
    // Kinect-like camera scaled to the requested width (4:3).
    IMUMATCH_REQUIRE(a.width >= 16 && a.width <= 4096, "--width must be in [16, 4096]");
    return PinholeCamera::KinectDefault().ScaledToWidth(a.width);
  }
  if (a.width_option != nullptr && a.width_option->count() > 0) {
    throw InvalidArgument("--width applies to --camera kinect only; '" + a.camera +
                          "' sets its own size");
  }
  if (a.camera == "euroc") return PinholeCamera::EurocCam0();
  if (a.camera == "tum-fr1") return PinholeCamera::TumFreiburg1();
  if (a.camera == "tum-vi") return PinholeCamera::TumViCam0();
  if (!std::filesystem::is_regular_file(a.camera)) {
    throw InvalidArgument("--camera '" + a.camera +
                          "': not kinect, euroc, tum-fr1 or tum-vi, and no such file");
  }
  return ReadCameraFile(a.camera);
}

void RunSynth(const SynthArgs& a) {
  // Fail fast, before rendering: unknown motion, or an output folder that is in use.
  const std::vector<std::string> names = MotionNames();
  if (std::find(names.begin(), names.end(), a.motion) == names.end()) {
    std::string valid;
    for (const std::string& n : names) valid += " " + n;
    throw InvalidArgument("unknown motion '" + a.motion + "'; valid names:" + valid);
  }
  // Writable, and empty unless --overwrite (a synthetic folder is a dataset: its files are not
  // recorded as replaceable outputs).
  const OutputFolderCheck check = PrepareOutputFolder(a.out, a.overwrite);
  if (!check.note.empty()) std::cerr << "imumatch: note: " << check.note << "\n";
  SyntheticSequenceOptions options;
  options.motion = a.motion;
  options.frame_rate_hz = a.fps;
  options.imu_model = a.imu;
  options.imu_seed = a.seed;
  options.render.depth_noise.add_noise = a.depth_noise;
  options.render.depth_noise.add_holes = a.depth_holes;
  options.render.depth_noise.seed = a.seed;
  options.odd_frame_gain = a.gain;
  if (a.duration_s >= 0.0) options.motion_options.duration_s = a.duration_s;
  if (a.still_s >= 0.0) {
    options.motion_options.still_before_s = a.still_s;
    options.motion_options.still_after_s = a.still_s;
  }
  options.t0_ns = SecondsToNs(a.t0_s);
  options.camera = SynthCamera(a);
  SceneOptions scene_options;
  scene_options.texel_size_m = a.texel_m;
  options.Check();

  std::cout << "rendering '" << a.motion << "' at " << a.fps << " fps, camera "
            << options.camera.ToString() << ", IMU model " << a.imu << ", seed " << a.seed << " ..."
            << std::endl;
  const Scene scene(scene_options);
  const SyntheticSequence sequence = MakeSyntheticSequence(options, scene);
  SyntheticWriteOptions write_options;
  write_options.overwrite = a.overwrite;
  if (a.format == "euroc") {
    WriteSyntheticSequenceAsEuroc(sequence, a.out, write_options);
  } else {
    WriteSyntheticSequence(sequence, options, a.out, write_options);
  }
  std::cout << "wrote " << sequence.frames.size() << " frames and " << sequence.imu.size()
            << " IMU samples (" << FormatNsAsSeconds(sequence.imu.front().t_ns) << " - "
            << FormatNsAsSeconds(sequence.imu.back().t_ns) << " s) to " << a.out << "\n";
}

}  // namespace

void AddSynthCommand(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* sub = app.add_subcommand(
      "synth",
      "Render a synthetic RGB-D sequence with a simulated IMU and write it as a TUM RGB-D style "
      "folder (rgb/, depth/, rgb.txt, depth.txt, groundtruth.txt, imu.txt, camera.txt, "
      "sequence.json) or, with --format euroc, in the EuRoC / ASL layout (mav0/...).");
  std::string motions;
  for (const std::string& m : MotionNames()) motions += (motions.empty() ? "" : ", ") + m;
  sub->add_option("--motion", args->motion, "Motion: " + motions)->required();
  sub->add_option("--out", args->out, "Output folder (created; must be empty unless --overwrite)")
      ->required();
  sub->add_option("--fps", args->fps, "Frame rate (Hz)")
      ->capture_default_str()
      ->check(NumberIn(0.0, true, 1000.0, false));
  sub->add_option("--imu", args->imu, "IMU noise model: euroc, mems or ideal")
      ->capture_default_str();
  sub->add_option("--seed", args->seed, "Seed of the IMU noise (and depth noise)")
      ->capture_default_str();
  sub->add_flag("--depth-noise", args->depth_noise, "Add Kinect-like depth noise");
  sub->add_flag("--depth-holes", args->depth_holes, "Add depth holes (dropouts, range, grazing)");
  args->width_option =
      sub->add_option("--width", args->width,
                      "Image width in pixels of the kinect camera (4:3, Kinect-like intrinsics)")
          ->capture_default_str();
  sub->add_option(
         "--camera", args->camera,
         "Camera to render with: kinect (pinhole, scaled to --width), euroc (EuRoC MAV "
         "cam0: 752x480, radial-tangential lens, k1 = -0.28), tum-fr1 (TUM fr1 "
         "calibration with its lens), tum-vi (TUM-VI 512x512 fisheye, equidistant, "
         "black beyond 80 deg off-axis), or a camera file: a Kalibr/EuRoC camera sensor.yaml "
         "or a text line as camera.txt ('[radtan|equidistant] fx fy cx cy width height "
         "k...'); the images are rendered through the lens, the depth and poses stay "
         "exact")
      ->capture_default_str();
  sub->add_option("--duration", args->duration_s, "Duration of the motion (s), default per motion")
      ->check(PositiveFinite());
  sub->add_option("--still", args->still_s, "Still time before and after the motion (s)")
      ->check(NonNegativeFinite());
  sub->add_option("--t0", args->t0_s, "Timestamp of the start (s)")
      ->capture_default_str()
      ->check(NonNegativeFinite());
  sub->add_option("--texel", args->texel_m, "Texture resolution of the room (m per texel)")
      ->capture_default_str()
      ->check(PositiveFinite());
  sub->add_option("--gain", args->gain,
                  "Exposure flicker: every odd frame's intensities times this gain (1 = off)")
      ->capture_default_str()
      ->check(NumberIn(0.01, false, 100.0, false));
  sub->add_option("--format", args->format,
                  "Folder layout: tum (rgb/, depth/, *.txt, sequence.json) or euroc (mav0/cam0, "
                  "imu0, depth0, state_groundtruth_estimate0 with sensor.yaml files, as EuRoC "
                  "readers take it; gray images, ground truth at the frame times)")
      ->capture_default_str()
      ->check(CLI::IsMember({"tum", "euroc"}));
  sub->add_flag("--overwrite", args->overwrite, "Write into a non-empty folder");
  sub->callback([args] { RunSynth(*args); });
}

}  // namespace imumatch::apps
