#pragma once

#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

namespace imumatch {

// Base of imumatch's own detectors and extractors (Surf, Brief): detect() and compute() go through
// the subclass's detectAndCompute(), so they throw InvalidArgument on an empty image like it
// (cv::Feature2D's own detect() and compute() return silently).
class StrictFeature2D : public cv::Feature2D {
 public:
  using cv::Feature2D::compute;
  using cv::Feature2D::detect;
  void detect(cv::InputArray image, std::vector<cv::KeyPoint>& keypoints,
              cv::InputArray mask = cv::noArray()) override {
    detectAndCompute(image, mask, keypoints, cv::noArray(), false);
  }
  void compute(cv::InputArray image, std::vector<cv::KeyPoint>& keypoints,
               cv::OutputArray descriptors) override {
    detectAndCompute(image, cv::noArray(), keypoints, descriptors, true);
  }
};

}  // namespace imumatch
