// ReadKalibrCamchain (Kalibr's camchain.yaml: cam0's camera, distortion, T_cam_imu as four rows,
// timeshift) and ReadYamlCamera (either kind of camera yaml, as `--camera FILE` reads it).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      imumatch::fuzz::WriteInput("kalibr_camchain", "camchain.yaml", data, size);
  return imumatch::fuzz::Expect([&] {
    imumatch::ReadKalibrCamchain(path);
    imumatch::ReadYamlCamera(path);
  });
}
