// ReadEurocDepthSensor (mav0/depth0/sensor.yaml: depth_scale, registered_to).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      imumatch::fuzz::WriteInput("euroc_depth_yaml", "depth0/sensor.yaml", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadEurocDepthSensor(path); });
}
