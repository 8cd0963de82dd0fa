// LoadImage (8-bit images through cv::imread, gray and colour) and LoadRgbd with a fixed 32x32
// depth image (the size of the seed images: pairs both of that size and of other sizes).
#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>

#include "fuzz_util.h"
#include "imumatch/io/image_io.h"

namespace {
std::string depth_path;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::setNumThreads(0);  // no worker threads: deterministic, leak-checkable runs
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // decoder chatter
  depth_path = (imumatch::fuzz::ScratchDir() / "depth_32x32.png").string();
  imumatch::WriteImage(depth_path, cv::Mat(32, 32, CV_16UC1, cv::Scalar(1000)));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("load_image", "image.png", data, size);
  imumatch::fuzz::Expect([&] { imumatch::LoadImage(path, imumatch::ImageColor::kGray); });
  return imumatch::fuzz::Expect([&] { imumatch::LoadRgbd(path, depth_path); });
}
