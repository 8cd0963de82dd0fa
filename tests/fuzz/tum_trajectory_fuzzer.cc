// ReadTumTrajectory (groundtruth.txt: "t tx ty tz qx qy qz qw"), then the ground-truth look-ups
// LoadDataset makes with it (nearest and interpolated, between and at the poses).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_util.h"
#include "imumatch/io/trajectory_io.h"
#include "imumatch/io/tum_rgbd.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path =
      imumatch::fuzz::WriteInput("tum_trajectory", "groundtruth.txt", data, size);
  return imumatch::fuzz::Expect([&] {
    const std::vector<imumatch::StampedPose> poses = imumatch::ReadTumTrajectory(path);
    std::vector<int64_t> t;
    for (const imumatch::StampedPose& p : poses) t.push_back(p.t_ns + 5'000'000);
    imumatch::LookUpGroundTruth(poses, t, imumatch::GroundTruthLookup::kNearest);
    imumatch::LookUpGroundTruth(poses, t, imumatch::GroundTruthLookup::kInterpolate);
    for (const imumatch::StampedPose& p : poses) imumatch::InterpolatePoseAt(poses, p.t_ns, 0);
  });
}
