// ReadKalibrImu (Kalibr's imu.yaml / TUM-VI's imu_config.yaml: noise densities, random walks,
// update_rate; flat or under imu0).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("kalibr_imu", "imu_config.yaml", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadKalibrImu(path); });
}
