#pragma once

#include <string>

#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch {

// Writes a synthetic sequence as a TUM RGB-D style folder that LoadDataset reads back:
//   rgb/<t>.png      8-bit colour (lossless PNG), <t> = seconds with nine decimals
//   depth/<t>.png    16-bit depth, camera.depth_scale units per metre, 0 = no depth
//   rgb.txt, depth.txt   "t filename"
//   groundtruth.txt  "t tx ty tz qx qy qz qw", world_from_cam at every frame (exact, 17 digits)
//   velocity.txt     "t vx vy vz", the IMU's velocity in the world at every frame
//   imu.txt          "t_s gx gy gz ax ay az" (imu_io.h), bit exact
//   camera.txt       "fx fy cx cy width height k1 k2 p1 p2 k3" (ReadCameraFromText)
//   sequence.json    {"generator": "imumatch synth", motion, seed, imu_model, imu_params,
//                     imu_initial_bias, cam_from_imu (4x4), "imu_simulated": true, camera, ...}
// Creates dir (and parents) when missing; refuses a non-empty dir unless overwrite is set (then
// the files above are replaced; other files are left alone). Throws Error when writing fails.
struct SyntheticWriteOptions {
  bool overwrite = false;
};

// What every writer of a synthetic sequence checks first: frames, increasing timestamps, and an
// output folder that is absent, empty or allowed to be overwritten. Throws InvalidArgument / Error.
void CheckSyntheticWrite(const SyntheticSequence& sequence, const std::string& dir,
                         const SyntheticWriteOptions& write_options);

// The options (when known) record how the sequence was made: imu model name, seed, frame rate,
// depth noise. Without them those fields of sequence.json are null.
void WriteSyntheticSequence(const SyntheticSequence& sequence, const std::string& dir,
                            const SyntheticWriteOptions& write_options = SyntheticWriteOptions());
void WriteSyntheticSequence(const SyntheticSequence& sequence,
                            const SyntheticSequenceOptions& generated_with, const std::string& dir,
                            const SyntheticWriteOptions& write_options = SyntheticWriteOptions());

}  // namespace imumatch
