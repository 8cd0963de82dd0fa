#include "imumatch/matching/guided_candidates.h"

#include <cstring>

#include "imumatch/core/error.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

DescriptorView GuidedCandidates::descriptor_view() const {
  DescriptorView v;
  v.data = descriptors.data();
  v.rows = count();
  v.bytes = bytes;
  v.step = static_cast<size_t>(bytes);
  v.norm = norm;
  return v;
}

void PrepareGuidedCandidates(const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
                             const DescriptorView& descriptors_b, GuidedCandidates* out) {
  IMUMATCH_CHECK(out != nullptr, "PrepareGuidedCandidates needs an output");
  const int m = static_cast<int>(keypoints_b.size());
  IMUMATCH_CHECK(descriptors_b.rows == m,
                 descriptors_b.rows << " descriptors for " << m << " keypoints in B");
  IMUMATCH_CHECK(grid_b.size() == m, "grid holds " << grid_b.size() << " points, B has " << m);
  const int bytes = descriptors_b.bytes;
  out->bytes = bytes;
  out->norm = descriptors_b.norm;
  out->grid = &grid_b;
  out->reference_size = ReferenceKeypointSize(keypoints_b);
  // Angles are normalised into [0, 360) once here (no angle: -1), sizes that are not positive
  // numbers become 0 (no size check), as the window tests expect.
  out->x.resize(m);
  out->y.resize(m);
  out->angle_deg.resize(m);
  out->size.resize(m);
  out->descriptors.resize(static_cast<size_t>(m) * bytes);
  constexpr int kPrefetchAhead = 8;  // rows are read in slot order: a random gather over B
  for (int k = 0; k < m; ++k) {
    if (k + kPrefetchAhead < m) {
      const int ahead = grid_b.slot_index(k + kPrefetchAhead);
      __builtin_prefetch(&keypoints_b[ahead]);
      const uint8_t* row = descriptors_b.Row(ahead);
      for (int b = 0; b < bytes; b += 64) __builtin_prefetch(row + b);
    }
    const int j = grid_b.slot_index(k);
    const KeypointInfo& kb = keypoints_b[j];
    out->x[k] = kb.x;
    out->y[k] = kb.y;
    out->angle_deg[k] = kb.angle_deg >= 0.0f && std::isfinite(kb.angle_deg)
                            ? NormalizeDegrees(kb.angle_deg)
                            : -1.0f;
    out->size[k] = kb.size > 0.0f ? kb.size : 0.0f;
    std::memcpy(out->descriptors.data() + static_cast<size_t>(k) * bytes, descriptors_b.Row(j),
                bytes);
  }
}

}  // namespace imumatch
