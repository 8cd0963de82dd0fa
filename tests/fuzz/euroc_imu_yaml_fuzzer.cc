// ReadEurocImuSensor (mav0/imu0/sensor.yaml: noise densities, random walks, rate, T_BS).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      imumatch::fuzz::WriteInput("euroc_imu_yaml", "imu0/sensor.yaml", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadEurocImuSensor(path); });
}
