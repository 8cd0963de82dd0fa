// ReadEurocCameraSensor (mav0/cam0/sensor.yaml: intrinsics, resolution, distortion, T_BS).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      imumatch::fuzz::WriteInput("euroc_camera_yaml", "cam0/sensor.yaml", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadEurocCameraSensor(path); });
}
