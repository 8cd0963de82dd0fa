#pragma once

#include <string>
#include <vector>

#include "imumatch/core/types.h"

namespace imumatch {

// TUM trajectory files: one pose per line, "t tx ty tz qx qy qz qw" with t in (float) seconds,
// world_from_body (camera-to-world for a camera trajectory), Hamilton quaternion in x y z w order.
// '#' starts a comment line.

// Reads a trajectory. Throws InputError(path, line, ...) for a missing file, a wrong field count, a
// non-numeric or non-finite value, a duplicate or out-of-order timestamp, or a quaternion whose
// norm is off by more than 1e-3 (smaller deviations, e.g. from 4-decimal files, are normalised
// away).
std::vector<StampedPose> ReadTumTrajectory(const std::string& path);

// Writes poses in the same format: seconds with nine decimals (exact in ns), the other numbers with
// 17 significant digits, so ReadTumTrajectory returns the same poses. Throws InvalidArgument for
// non-increasing timestamps, Error when the file cannot be written.
void WriteTumTrajectory(const std::string& path, const std::vector<StampedPose>& poses,
                        const std::string& header_comment = "");

// Parses "tx ty tz qx qy qz qw" (no timestamp), e.g. the pose files of the TUM pair excerpt.
Rigid3d ReadTumPose(const std::string& path);

}  // namespace imumatch
