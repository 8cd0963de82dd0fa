// ReadEurocPoses (mav0/mocap0 or vicon0 data.csv: timestamp, p x y z, q w x y z) and
// GroundTruthFromPoses (the velocities from their slope) on what it accepts.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "imumatch/io/euroc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = imumatch::fuzz::WriteInput("euroc_poses", "mocap0/data.csv", data, size);
  return imumatch::fuzz::Expect(
      [&] { imumatch::GroundTruthFromPoses(imumatch::ReadEurocPoses(path), imumatch::Rigid3d()); });
}
