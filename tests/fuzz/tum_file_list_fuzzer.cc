// ReadTumFileList (TUM rgb.txt / depth.txt: "t filename").
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_util.h"
#include "imumatch/io/tum_rgbd.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("tum_file_list", "rgb.txt", data, size);
  return imumatch::fuzz::Expect([&] {
    const std::vector<imumatch::StampedFile> files = imumatch::ReadTumFileList(path);
    std::vector<int64_t> t;
    for (const imumatch::StampedFile& f : files) t.push_back(f.t_ns);
    // The list against itself 15 ms later, as rgb.txt is paired with a depth.txt.
    imumatch::AssociateTimestamps(t, t, 20'000'000, 15'000'000);
  });
}
