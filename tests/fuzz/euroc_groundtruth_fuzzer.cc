// ReadEurocGroundTruth (mav0/state_groundtruth_estimate0/data.csv, 17 columns).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput(
      "euroc_groundtruth", "state_groundtruth_estimate0/data.csv", data, size);
  return imumatch::fuzz::Expect([&] { imumatch::ReadEurocGroundTruth(path); });
}
