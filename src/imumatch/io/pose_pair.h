#pragma once

#include <cstdint>
#include <string>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/io/dataset.h"

namespace imumatch {

// Adapter for a two-frame RGB-D excerpt (like shared/data/tum_fr1_xyz_pair) that io's LoadDataset
// does not read: img_prev.png, img_curr.png, dep_prev.png, dep_curr.png, and pose_prev.txt /
// pose_curr.txt holding one world_from_cam pose "tx ty tz qx qy qz qw" (TUM order) without a
// timestamp. The frames get t = 0 and t = frame_interval_ns; there is no IMU (evaluate with
// MotionSource::kGroundTruth). The camera defaults to the generic Kinect intrinsics that come
// with that excerpt.
bool IsPosePairFolder(const std::string& dir);
// Throws InputError (file, line) for a missing or malformed pose file or missing image.
Dataset LoadPosePairFolder(const std::string& dir,
                           const PinholeCamera& camera = PinholeCamera::KinectDefault(),
                           int64_t frame_interval_ns = 33'333'333);

// What `eval` reads from a path: a two-frame pose-pair folder, or any layout LoadDataset knows
// (options apply to the latter; of them, a pose-pair folder takes only the camera override).
Dataset LoadDatasetOrPosePair(const std::string& path,
                              const DatasetOptions& options = DatasetOptions());

}  // namespace imumatch
