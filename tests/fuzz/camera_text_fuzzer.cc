// ParseCameraFromText and ReadCameraFromText (camera.txt: "fx fy cx cy [w h [k1 k2 p1 p2 [k3]]]").
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "imumatch/camera/pinhole_camera.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  imumatch::fuzz::Expect([&] { imumatch::ParseCameraFromText(text, "camera.txt"); });
  const std::string path = imumatch::fuzz::WriteInput("camera_text", "camera.txt", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadCameraFromText(path); });
}
