#include "imumatch/matching/field_of_view.h"

namespace imumatch {

cv::Mat FieldOfViewMask(const PinholeCamera& camera) {
  camera.Check();
  if (!camera.WiderThanField()) return cv::Mat();
  cv::Mat mask(camera.height, camera.width, CV_8UC1);
  for (int v = 0; v < camera.height; ++v) {
    uint8_t* row = mask.ptr<uint8_t>(v);
    for (int u = 0; u < camera.width; ++u) {
      row[u] = camera.InField(Eigen::Vector2d(u, v)) ? 255 : 0;
    }
  }
  return mask;
}

}  // namespace imumatch
