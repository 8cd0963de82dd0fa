// LoadDataset on a tiny EuRoC folder (mav0/ with cam0, imu0, state_groundtruth_estimate0 and
// depth0) with one of its files replaced by the input: cam0/depth0 pairing, ground-truth look-up
// and velocity interpolation. Input: "<file name>\n<content>" with a name of kNames; an input
// whose first line is no such name is the content of state_groundtruth_estimate0/data.csv.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_util.h"
#include "imumatch/io/dataset.h"

namespace {

const char* const kNames[] = {"cam0/sensor.yaml",
                              "imu0/sensor.yaml",
                              "cam0/data.csv",
                              "imu0/data.csv",
                              "depth0/sensor.yaml",
                              "depth0/data.csv",
                              "state_groundtruth_estimate0/data.csv"};
constexpr int kNumFiles = 7;

const char kCameraYaml[] = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [0.0, -1.0, 0.0, -0.02,
         1.0, 0.0, 0.0, -0.06,
         0.0, 0.0, 1.0, 0.01,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.0, 457.0, 367.0, 248.0]
distortion_model: radial-tangential
distortion_coefficients: [-0.28, 0.07, 0.0002, 0.00002]
)";

const char kImuYaml[] = R"(sensor_type: imu
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
rate_hz: 200
gyroscope_noise_density: 1.7e-04
gyroscope_random_walk: 1.9e-05
accelerometer_noise_density: 2.0e-3
accelerometer_random_walk: 3.0e-3
)";

const char kDepthYaml[] = "depth_scale: 1000\nregistered_to: cam0\n";

// 5 frames at 20 Hz from t0, depth for the first 3, IMU at 200 Hz and ground truth at 200 Hz
// from 10 ms before the first frame to 10 ms after the last.
constexpr int64_t kT0 = 1403638538577829376;

std::string DefaultFile(int index) {
  std::string out;
  char line[300];
  switch (index) {
    case 0:
      return kCameraYaml;
    case 1:
      return kImuYaml;
    case 4:
      return kDepthYaml;
    case 2:
    case 5:
      out = "#timestamp [ns],filename\n";
      for (int i = 0; i < (index == 2 ? 5 : 3); ++i) {
        const long long t = kT0 + 50'000'000LL * i;
        std::snprintf(line, sizeof(line), "%lld,%lld.png\n", t, t);
        out += line;
      }
      return out;
    case 3:
      out = "#timestamp [ns],w x,w y,w z,a x,a y,a z\n";
      for (int i = 0; i < 45; ++i) {
        std::snprintf(line, sizeof(line), "%lld,0.001,0.02,0.078,9.08,-0.057,-3.82\n",
                      static_cast<long long>(kT0 - 10'000'000 + 5'000'000LL * i));
        out += line;
      }
      return out;
    default:
      out = "#timestamp,p x,p y,p z,q w,q x,q y,q z,v x,v y,v z,bw x,bw y,bw z,ba x,ba y,ba z\n";
      for (int i = 0; i < 45; ++i) {
        std::snprintf(line, sizeof(line),
                      "%lld,%.4f,-1.68,0.58,0.238261,-0.757610,-0.348629,-0.497711,0.2,0.0,0.0,"
                      "-0.0018,0.021,0.077,-0.02,0.12,0.06\n",
                      static_cast<long long>(kT0 - 10'000'000 + 5'000'000LL * i), 4.46 + 0.001 * i);
        out += line;
      }
      return out;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto [fuzzed, content] = imumatch::fuzz::SplitNamedInput(
      data, size, {kNames[0], kNames[1], kNames[2], kNames[3], kNames[4], kNames[5], kNames[6]});
  if (fuzzed < 0) {
    fuzzed = 6;
    content.assign(reinterpret_cast<const char*>(data), size);
  }
  const std::string root = imumatch::fuzz::FreshDir("euroc_dataset/MH_05_fuzz");
  for (int i = 0; i < kNumFiles; ++i) {
    imumatch::fuzz::WriteFile(root, std::string("mav0/") + kNames[i],
                              i == fuzzed ? content : DefaultFile(i));
  }
  return imumatch::fuzz::Expect([&] {
    imumatch::DatasetOptions options;
    options.check_files_exist = false;  // the folder holds the lists only, no images
    imumatch::LoadDataset(root, options);
    options.groundtruth_lookup = imumatch::GroundTruthLookup::kNearest;
    imumatch::LoadDataset(root + "/mav0", options);
  });
}
