// ReadImuText (imu.txt of a synthetic sequence: "t_s gx gy gz ax ay az"), then a query of the
// buffer as the matcher makes it.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/imu_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("imu_text", "imu.txt", data, size);
  return imumatch::fuzz::Expect([&] {
    const imumatch::ImuBuffer imu = imumatch::ReadImuText(path);
    imumatch::fuzz::Query([&] { imu.Interpolate(imu.samples()[imu.size() / 2].t_ns - 1); });
  });
}
