#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/grid_index.h"
#include "imumatch/matching/match_types.h"

namespace imumatch {

// Frame B as the window search reads it: its keypoints (one array per field) and descriptors
// copied into the grid's slot order, so that a window's candidates are contiguous runs of slots.
// Prepare it once per frame B (O(m): a gather of B's rows, a cache miss per row once B outgrows
// L2) and pass it to every search against that frame: the scene's pilot, the first and the second
// pass. It holds copies of B's keypoint fields and descriptors but refers to the grid it was
// prepared with: keep that grid unchanged while using it, and prepare again after rebuilding it.
struct GuidedCandidates {
  std::vector<float> x, y;           // by slot, ideal pixels as in the grid
  std::vector<float> angle_deg;      // in [0, 360), or -1: no angle
  std::vector<float> size;           // > 0, or 0: no size check
  std::vector<uint8_t> descriptors;  // by slot, `bytes` each
  int bytes = 0;
  DescriptorNorm norm = DescriptorNorm::kHamming;
  float reference_size = 0.0f;  // ReferenceKeypointSize of B's keypoints
  const GridIndex* grid = nullptr;

  int count() const { return static_cast<int>(x.size()); }
  // The slot-order descriptors as a view (rows = count()).
  DescriptorView descriptor_view() const;
};
// Fills *out from B's keypoints (ideal pixels), the grid built over them and their descriptors
// (its buffers reused). Throws InvalidArgument when the grid or the descriptors do not hold one
// entry per keypoint.
void PrepareGuidedCandidates(const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
                             const DescriptorView& descriptors_b, GuidedCandidates* out);

// An angle in degrees mapped into [0, 360) (NaN stays NaN), as the window tests compare angles.
inline float NormalizeDegrees(float a) {
  if (a >= 360.0f || a < 0.0f) a -= 360.0f * std::floor(a / 360.0f);
  return a < 360.0f ? a : 0.0f;  // a tiny negative a rounds up to 360
}

}  // namespace imumatch
