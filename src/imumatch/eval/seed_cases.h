#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/eval/evaluation.h"

namespace imumatch {

// The seed paper's synthetic comparison, generated in memory: for each motion (front1m, back1m,
// left30, right30) a sequence rendered through sim's synthetic room with frames at the start and
// the end of the 2 s motion; the case compares those two frames. With intermediate_frames > 0,
// that many evenly spaced frames are rendered in between and a second case "<motion>-steps"
// compares consecutive frames (start, i1), (i1, i2), ..., (ik, end).
struct SeedCaseOptions {
  std::vector<std::string> motions = {"front1m", "back1m", "left30", "right30"};
  int intermediate_frames = 0;
  PinholeCamera camera = PinholeCamera::KinectDefault();
  std::string imu_model = "euroc";
  uint64_t seed = 42;
  bool depth_noise = false;  // Kinect-like depth noise and holes in the rendered depth
  int render_threads = 2;
  void Check() const;
};

struct SeedCase {
  std::string name;
  EvalSource source;
  std::vector<FramePair> pairs;
};

// Throws InvalidArgument for an unknown motion or bad options.
std::vector<SeedCase> MakeSeedCases(const SeedCaseOptions& options);

}  // namespace imumatch
