#pragma once

// Helpers shared by the dataset loaders of dataset.cc and dataset_synthetic.cc; not installed.

#include <cstdint>
#include <string>
#include <vector>

#include "imumatch/io/dataset.h"
#include "imumatch/io/tum_rgbd.h"

namespace imumatch::dataset_internal {

// The last component of a folder's path ("a/b/" -> "b").
std::string FolderName(const std::string& path);
// Keeps frames [first, first + max) (max 0 = all).
void SelectFrames(std::vector<FrameRecord>& frames, const DatasetOptions& options);
// "the EuRoC ADIS16448 noise model" for "euroc", ... for the loaders' notes.
std::string DescribeModel(const std::string& model);
// Frames from rgb (and depth, associated within max_difference_ns) lists of a TUM style folder;
// check_files: each listed file must exist (InputError naming the list and line). Frames of rgb.txt
// without depth are dropped and said in *warnings.
std::vector<FrameRecord> TumFrames(const TumRgbdFiles& files, int64_t max_difference_ns,
                                   bool check_files, std::vector<std::string>* warnings);
// Throws InvalidArgument when options give a timeshift_cam_imu: it applies to EuRoC/ASL
// recordings, and `why` says what path is instead.
void RefuseTimeshift(const std::string& path, const DatasetOptions& options, const char* why);

}  // namespace imumatch::dataset_internal
