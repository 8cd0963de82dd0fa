// ReadTumRgbdFolder on a folder of rgb.txt and depth.txt, then their association (associate.py)
// as LoadDataset does it. Input: rgb.txt, a line "%%", depth.txt (no "%%": depth.txt is empty).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_util.h"
#include "imumatch/io/tum_rgbd.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const size_t sep = text.find("\n%%\n");
  const std::string dir = imumatch::fuzz::FreshDir("tum_association");
  imumatch::fuzz::WriteFile(dir, "rgb.txt", text.substr(0, sep));
  imumatch::fuzz::WriteFile(dir, "depth.txt", sep == std::string::npos ? "" : text.substr(sep + 4));
  return imumatch::fuzz::Expect([&] {
    const imumatch::TumRgbdFiles files = imumatch::ReadTumRgbdFolder(dir);
    std::vector<int64_t> rgb_t, depth_t;
    for (const imumatch::StampedFile& f : files.rgb) rgb_t.push_back(f.t_ns);
    for (const imumatch::StampedFile& f : files.depth) depth_t.push_back(f.t_ns);
    imumatch::AssociateTimestamps(rgb_t, depth_t);
    imumatch::AssociateTimestamps(depth_t, rgb_t, 20'000'000, -5'000'000);
  });
}
