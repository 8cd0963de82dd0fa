// LoadDataset on a tiny TUM RGB-D folder (rgb.txt, depth.txt, groundtruth.txt, accelerometer.txt,
// camera.txt) with one of its files replaced by the input: association, ground-truth look-up,
// spline fit and IMU simulation from the ground truth. Input: "<file name>\n<content>"; an input
// whose first line is no file name of the folder is the content of groundtruth.txt.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_util.h"
#include "imumatch/io/dataset.h"

namespace {

const char* const kNames[] = {"rgb.txt", "depth.txt", "groundtruth.txt", "accelerometer.txt",
                              "camera.txt"};

// Valid defaults: 6 frames at 30 Hz, depth 4 ms later, ground truth at 100 Hz around them.
std::string DefaultFile(int index) {
  std::string out;
  char line[160];
  switch (index) {
    case 0:
    case 1:
      out = index == 0 ? "# color images\n" : "# depth images\n";
      for (int i = 0; i < 6; ++i) {
        const double t = 100.0 + i / 30.0 + (index == 1 ? 0.004 : 0.0);
        std::snprintf(line, sizeof(line), "%.6f %s/%.6f.png\n", t, index == 0 ? "rgb" : "depth", t);
        out += line;
      }
      return out;
    case 2:
      out = "# timestamp tx ty tz qx qy qz qw\n";
      for (int i = 0; i < 25; ++i) {
        const double t = 99.99 + 0.01 * i;
        std::snprintf(line, sizeof(line), "%.4f %.4f %.4f %.4f 0.0 %.6f 0.0 %.6f\n", t,
                      1.0 + 0.01 * i, 0.5, 1.5 - 0.005 * i, 0.001 * i, 1.0 - 0.0000005 * i * i);
        out += line;
      }
      return out;
    case 3:
      out = "# timestamp ax ay az\n";
      for (int i = 0; i < 10; ++i) {
        std::snprintf(line, sizeof(line), "%.6f -0.05 -9.79 0.2\n", 100.0 + 0.02 * i);
        out += line;
      }
      return out;
    default:
      return "# fx fy cx cy width height k1 k2 p1 p2 k3\n517.3 516.5 318.6 255.3 640 480 0.2624 "
             "-0.9531 -0.0054 0.0026 1.1633\n";
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto [fuzzed, content] = imumatch::fuzz::SplitNamedInput(
      data, size, {kNames[0], kNames[1], kNames[2], kNames[3], kNames[4]});
  if (fuzzed < 0) {
    fuzzed = 2;
    content.assign(reinterpret_cast<const char*>(data), size);
  }
  const std::string dir = imumatch::fuzz::FreshDir("tum_dataset/rgbd_dataset_freiburg1_fuzz");
  for (int i = 0; i < 5; ++i) {
    imumatch::fuzz::WriteFile(dir, kNames[i], i == fuzzed ? content : DefaultFile(i));
  }
  return imumatch::fuzz::Expect([&] {
    imumatch::DatasetOptions options;
    options.check_files_exist = false;  // the folder holds the lists only, no images
    // The bound's check is the same at any value; a minute instead of the default hour keeps
    // every input fast (an hour of simulated IMU takes 20-30 s under the sanitizers).
    options.max_simulated_imu_span_ns = 60'000'000'000;
    imumatch::LoadDataset(dir, options);
    options.groundtruth_lookup = imumatch::GroundTruthLookup::kNearest;
    options.simulate_imu = false;
    imumatch::LoadDataset(dir, options);
  });
}
