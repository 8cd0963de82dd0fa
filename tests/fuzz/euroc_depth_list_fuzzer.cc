// ReadEurocDepthList (mav0/depth0/data.csv: "timestamp [ns], filename").
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      imumatch::fuzz::WriteInput("euroc_depth_list", "depth0/data.csv", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadEurocDepthList(path); });
}
