// ReadTumAccelerometer (accelerometer.txt: "t ax ay az").
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/tum_rgbd.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      imumatch::fuzz::WriteInput("tum_accelerometer", "accelerometer.txt", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadTumAccelerometer(path); });
}
