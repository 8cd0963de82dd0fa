// LoadDataset on a tiny synthetic folder (imumatch synth, synthetic_io.h) with sequence.json, or
// one of the other files when the input's first line names it ("velocity.txt\n<content>"),
// replaced by the input.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_util.h"
#include "imumatch/io/dataset.h"

namespace {

const char* const kNames[] = {"sequence.json", "velocity.txt",    "imu.txt",
                              "rgb.txt",       "groundtruth.txt", "camera.txt"};

const char kSequenceJson[] = R"({
  "generator": "imumatch synth",
  "format_version": 1,
  "motion": "left30",
  "seed": 42,
  "imu_model": "mems",
  "imu_simulated": true,
  "imu_params": {"gyro_noise_density": 0.0002, "gyro_random_walk": 2e-05,
                 "accel_noise_density": 0.002, "accel_random_walk": 0.0003, "rate_hz": 200.0,
                 "gravity_in_world": [0.0, 0.0, -9.81]},
  "imu_initial_bias": {"gyro": [0.01, -0.02, 0.003], "accel": [0.0, 0.0, 0.0]},
  "cam_from_imu": [[1.0, 0.0, 0.0, 0.05], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, -0.02],
                   [0.0, 0.0, 0.0, 1.0]],
  "cam_from_imu_quaternion_wxyz": [1.0, 0.0, 0.0, 0.0],
  "camera": {"width": 80, "height": 60, "fx": 65.625, "fy": 65.625, "cx": 39.5, "cy": 29.5,
             "distortion": [0.0, 0.0, 0.0, 0.0, 0.0], "depth_scale": 5000.0},
  "frame_rate_hz": 10.0,
  "depth_noise": true,
  "depth_holes": false,
  "t0_ns": 1000000123,
  "num_frames": 4,
  "num_imu_samples": 81
}
)";

// Valid defaults: 4 frames at 10 Hz from t0 = 1.000000123 s, the IMU at 200 Hz over them.
std::string DefaultFile(int index) {
  std::string out;
  char line[200];
  switch (index) {
    case 0:
      return kSequenceJson;
    case 1:
    case 3:
    case 4:
      for (int i = 0; i < 4; ++i) {
        const double t = 1.000000123 + 0.1 * i;
        if (index == 1) std::snprintf(line, sizeof(line), "%.9f 0.1 0.0 0.0\n", t);
        if (index == 3) std::snprintf(line, sizeof(line), "%.9f rgb/%.9f.png\n", t, t);
        if (index == 4) {
          std::snprintf(line, sizeof(line), "%.9f %.3f 0.0 0.0 0.0 0.0 0.0 1.0\n", t, 0.01 * i);
        }
        out += line;
      }
      return out;
    case 2:
      for (int i = 0; i <= 80; ++i) {
        std::snprintf(line, sizeof(line), "%.9f 0.001 -0.002 0.0003 0.01 0.02 9.81\n",
                      1.000000123 + 0.005 * i);
        out += line;
      }
      return out;
    default:
      return "65.625 65.625 39.5 29.5 80 60 0 0 0 0 0\n";
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto [fuzzed, content] = imumatch::fuzz::SplitNamedInput(
      data, size, {kNames[0], kNames[1], kNames[2], kNames[3], kNames[4], kNames[5]});
  if (fuzzed < 0) {
    fuzzed = 0;
    content.assign(reinterpret_cast<const char*>(data), size);
  }
  const std::string dir = imumatch::fuzz::FreshDir("synthetic_sequence/left30");
  for (int i = 0; i < 6; ++i) {
    imumatch::fuzz::WriteFile(dir, kNames[i], i == fuzzed ? content : DefaultFile(i));
  }
  return imumatch::fuzz::Expect([&] {
    imumatch::DatasetOptions options;
    options.check_files_exist = false;  // the folder holds the lists only, no images
    imumatch::LoadDataset(dir, options);
  });
}
