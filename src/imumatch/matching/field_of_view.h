#pragma once

#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"

namespace imumatch {

// The detection mask of a camera's field of view (PinholeCamera::InField at each pixel centre):
// 255 where the pixel's ray lies within PinholeCamera::kMaxFieldAngleDeg of the optical axis, 0
// beyond. Empty (no mask: every pixel is in the field) for a camera that is not WiderThanField,
// so a caller passes it to ExtractFeatures as it is. Throws InvalidArgument for a camera failing
// Check().
cv::Mat FieldOfViewMask(const PinholeCamera& camera);

}  // namespace imumatch
