#include "imumatch/eval/seed_cases.h"

#include "imumatch/core/error.h"
#include "imumatch/sim/motions.h"
#include "imumatch/sim/scene.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch {

void SeedCaseOptions::Check() const {
  IMUMATCH_CHECK(!motions.empty(), "no motion selected");
  IMUMATCH_CHECK(intermediate_frames >= 0 && intermediate_frames <= 1000,
                 "intermediate_frames = " << intermediate_frames);
  IMUMATCH_CHECK(render_threads >= 1, "render_threads = " << render_threads);
  camera.Check();
  IMUMATCH_CHECK(!camera.HasDistortion(), "the synthetic camera must have no distortion");
}

std::vector<SeedCase> MakeSeedCases(const SeedCaseOptions& options) {
  options.Check();
  const Scene scene;  // default room, shared by every motion
  std::vector<SeedCase> cases;
  for (const std::string& motion : options.motions) {
    SyntheticSequenceOptions so;
    so.motion = motion;
    so.camera = options.camera;
    so.imu_model = options.imu_model;
    so.imu_seed = options.seed;
    so.render.num_threads = options.render_threads;
    so.render.depth_noise.add_noise = options.depth_noise;
    so.render.depth_noise.add_holes = options.depth_noise;
    so.render.depth_noise.seed = options.seed;
    const double t0 = so.motion_options.MotionStartTime();
    const double t1 = so.motion_options.MotionEndTime();
    const int k = options.intermediate_frames;
    for (int i = 0; i <= k + 1; ++i) so.frame_times_s.push_back(t0 + (t1 - t0) * i / (k + 1));
    const SyntheticSequence sequence = MakeSyntheticSequence(so, scene);
    EvalSource source = MakeSyntheticSource(sequence, motion);
    const size_t last = sequence.frames.size() - 1;
    cases.push_back({motion, source, {{0, last}}});
    if (k > 0) {
      SeedCase steps{motion + "-steps", source, {}};
      steps.source.dataset.name = steps.name;
      for (size_t i = 0; i < last; ++i) steps.pairs.push_back({i, i + 1});
      cases.push_back(std::move(steps));
    }
  }
  return cases;
}

}  // namespace imumatch
