// ReadTumPose (a single "tx ty tz qx qy qz qw" line, e.g. pose_prev.txt of the TUM pair).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/trajectory_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("tum_pose", "pose.txt", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadTumPose(path); });
}
