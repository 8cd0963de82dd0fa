#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "imumatch/core/rigid3.h"

namespace imumatch {

// The relative pose error of the TUM RGB-D benchmark (Sturm et al., IROS 2012) at a fixed frame
// delta: for estimated poses P_i and ground truth Q_i (world_from_cam, the camera-to-world
// convention of TUM trajectory files),
//   E_i = (Q_i^-1 Q_{i+delta})^-1 (P_i^-1 P_{i+delta}),
// its translation norm (metres) and rotation angle (degrees). Pairs where either pose is missing
// are left out. Independent of the estimate's world frame (only relative motions enter).
struct RelativePoseError {
  std::vector<double> translation_m;
  std::vector<double> rotation_deg;
  double rmse_translation_m = 0.0;
  double mean_translation_m = 0.0;
  double rmse_rotation_deg = 0.0;
  double mean_rotation_deg = 0.0;
  size_t pairs() const { return translation_m.size(); }
};
RelativePoseError ComputeRelativePoseError(const std::vector<std::optional<Rigid3d>>& estimated,
                                           const std::vector<std::optional<Rigid3d>>& truth,
                                           size_t delta = 1);

}  // namespace imumatch
