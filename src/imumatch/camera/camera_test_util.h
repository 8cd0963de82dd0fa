#pragma once

#include "imumatch/camera/pinhole_camera.h"

namespace imumatch::testing {

// An equidistant lens as strong as EuRoC's on EuRoC's image size (corners about 60 deg from the
// axis), for the camera tests.
inline PinholeCamera EquidistantTestCamera() {
  PinholeCamera cam;
  cam.width = 752;
  cam.height = 480;
  cam.fx = 380.0;
  cam.fy = 379.0;
  cam.cx = 370.0;
  cam.cy = 245.0;
  cam.model = DistortionModel::kEquidistant;
  cam.distortion = {-0.02, 0.01, -0.004, 0.0005, 0.0};
  return cam;
}

}  // namespace imumatch::testing
