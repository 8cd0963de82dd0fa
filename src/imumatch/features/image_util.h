#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace imumatch {

// Converts an 8-bit gray, BGR or BGRA image to 8-bit gray (no copy for gray input). Throws
// InvalidArgument, naming `who`, for an empty image or another depth or channel count.
cv::Mat ToGray8(const cv::Mat& image, const std::string& who);

}  // namespace imumatch
