#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "imumatch/core/rigid3.h"
#include "imumatch/core/types.h"

namespace imumatch {

// TUM RGB-D benchmark folders (Sturm et al., IROS 2012):
//   rgb.txt, depth.txt       "t filename"            (filename relative to the folder)
//   accelerometer.txt        "t ax ay az"            (Kinect accelerometer, m/s^2)
//   groundtruth.txt          "t tx ty tz qx qy qz qw" (world_from_cam, see trajectory_io.h)
// '#' lines are comments; float seconds are converted once to int64 ns (exact).

// One line of rgb.txt / depth.txt (or EuRoC cam0/data.csv).
struct StampedFile {
  int64_t t_ns = 0;
  std::string path;  // as written in the list (relative to the list's folder)
  int line = 0;      // line in the list file, for error messages
};

struct StampedAccel {
  int64_t t_ns = 0;
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

// Readers. Each throws InputError(path, line, ...) for a missing file, a wrong field count, a
// non-numeric or non-finite number, or a duplicate / out-of-order timestamp.
std::vector<StampedFile> ReadTumFileList(const std::string& path);
std::vector<StampedAccel> ReadTumAccelerometer(const std::string& path);
// Same as ReadTumTrajectory (trajectory_io.h).
std::vector<StampedPose> ReadTumGroundTruth(const std::string& path);

// Pairs of indices (into first, into second) whose timestamps differ by less than
// max_difference_ns, following TUM's associate.py: candidate pairs are sorted by |dt| (ties by the
// first then the second index), taken greedily, each element used at most once; the result is
// sorted by the first index. Both inputs must be sorted. offset_ns is added to the second list.
struct Association {
  size_t first = 0;
  size_t second = 0;
  int64_t difference_ns = 0;  // |t_first - (t_second + offset)|
};
std::vector<Association> AssociateTimestamps(const std::vector<int64_t>& first,
                                             const std::vector<int64_t>& second,
                                             int64_t max_difference_ns = 20'000'000,
                                             int64_t offset_ns = 0);

// Pose at t_ns interpolated between the two ground-truth poses that bracket it (slerp for the
// rotation, linear for the translation) when both are within max_difference_ns of t_ns; the exact
// pose when one has timestamp t_ns. nullopt otherwise. poses must be sorted by time.
std::optional<Rigid3d> InterpolatePoseAt(const std::vector<StampedPose>& poses, int64_t t_ns,
                                         int64_t max_difference_ns = 20'000'000);

// How a frame gets its ground-truth pose.
enum class GroundTruthLookup {
  kNearest,      // associate.py: greedy nearest timestamp within the tolerance (no interpolation)
  kInterpolate,  // slerp between the two neighbours, both within the tolerance
};
const char* ToString(GroundTruthLookup lookup);
GroundTruthLookup ParseGroundTruthLookup(const std::string& name);  // "nearest" | "interpolate"

// Ground truth for each query timestamp (sorted), nullopt where none fits.
std::vector<std::optional<Rigid3d>> LookUpGroundTruth(const std::vector<StampedPose>& poses,
                                                      const std::vector<int64_t>& t_ns,
                                                      GroundTruthLookup lookup,
                                                      int64_t max_difference_ns = 20'000'000);

// A TUM RGB-D folder's text files, read but not associated. rgb.txt is required; a missing
// depth.txt, accelerometer.txt or groundtruth.txt leaves that list empty.
struct TumRgbdFiles {
  std::string root;
  std::vector<StampedFile> rgb;
  std::vector<StampedFile> depth;
  std::vector<StampedAccel> accelerometer;
  std::vector<StampedPose> groundtruth;  // world_from_cam
  // What was read with a problem that does not stop the run (e.g. an unused accelerometer.txt
  // with a bad row), one line each.
  std::vector<std::string> warnings;
};
TumRgbdFiles ReadTumRgbdFolder(const std::string& root);

}  // namespace imumatch
