#include "imumatch/features/image_util.h"

#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"

namespace imumatch {

cv::Mat ToGray8(const cv::Mat& image, const std::string& who) {
  if (image.empty()) throw InvalidArgument(who + ": empty image");
  if (image.depth() != CV_8U) {
    throw InvalidArgument(who + ": expected an 8-bit image, got depth " +
                          std::to_string(image.depth()));
  }
  switch (image.channels()) {
    case 1:
      return image;
    case 3: {
      cv::Mat gray;
      cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
      return gray;
    }
    case 4: {
      cv::Mat gray;
      cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
      return gray;
    }
    default:
      throw InvalidArgument(who + ": expected 1, 3 or 4 channels, got " +
                            std::to_string(image.channels()));
  }
}

}  // namespace imumatch
