// LoadDepth (16-bit single-channel depth through cv::imread) and DepthToMetres.
#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>

#include "fuzz_util.h"
#include "imumatch/io/image_io.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::setNumThreads(0);  // no worker threads: deterministic, leak-checkable runs
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // decoder chatter
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("load_depth", "depth.png", data, size);
  imumatch::fuzz::Expect([&] { imumatch::LoadDepth(path, cv::Size(32, 32)); });
  return imumatch::fuzz::Expect([&] {
    const cv::Mat raw = imumatch::LoadDepth(path);
    imumatch::DepthToMetres(raw, 5000.0);
  });
}
