// ReadEurocImu (mav0/imu0/data.csv: "timestamp [ns], w x y z, a x y z").
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("euroc_imu", "imu0/data.csv", data, size);
  return imumatch::fuzz::Expect([&] {
    const imumatch::ImuBuffer imu = imumatch::ReadEurocImu(path);
    imumatch::fuzz::Query([&] { imu.Interpolate(imu.samples()[imu.size() / 2].t_ns - 1); });
  });
}
