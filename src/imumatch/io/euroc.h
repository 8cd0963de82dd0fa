#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/core/types.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_params.h"
#include "imumatch/io/tum_rgbd.h"

namespace imumatch {

// EuRoC MAV / ASL folder layout (Burri et al., IJRR 2016):
//   mav0/imu0/data.csv    "timestamp [ns], w x y z [rad/s], a x y z [m/s^2]"
//   mav0/imu0/sensor.yaml noise densities, random walks, rate, T_BS
//   mav0/cam0/data.csv    "timestamp [ns], filename" (images in mav0/cam0/data/)
//   mav0/cam0/sensor.yaml intrinsics, resolution, radial-tangential distortion, rate, T_BS
//   mav0/state_groundtruth_estimate0/data.csv (optional)
//     "timestamp, p x y z, q w x y z, v x y z, bw x y z, ba x y z" (quaternion w first)
// Header lines start with '#'. sensor.yaml files start with "%YAML:1.0" (OpenCV style), which
// yaml-cpp rejects: it is turned into a comment before parsing (line numbers are kept).

// IMU log -> buffer. Throws InputError(path, line, ...) for a missing file, wrong field count,
// non-numeric or non-finite values, duplicate or out-of-order timestamps.
ImuBuffer ReadEurocImu(const std::string& path, const ImuBufferOptions& options = {});

// cam0/data.csv -> (timestamp, filename) list, same errors.
std::vector<StampedFile> ReadEurocImageList(const std::string& path);

// T_BS: pose of the sensor in the body frame, body_from_sensor (p_in_body = T_BS * p_in_sensor).
struct EurocCameraSensor {
  PinholeCamera camera;  // intrinsics, resolution, distortion (k3 = 0 when only four given)
  Rigid3d body_from_sensor;
  double rate_hz = 0.0;
};
struct EurocImuSensor {
  ImuParams params;  // noise densities, random walks, rate; gravity left at the default
  Rigid3d body_from_sensor;
};
// Throw InputError(path, line, ...) for a missing file, YAML syntax errors, missing keys, values of
// the wrong shape, an unsupported camera / distortion model, or a T_BS that is not a rigid
// transform (rotation block not orthonormal within 1e-6 or determinant not +1).
EurocCameraSensor ReadEurocCameraSensor(const std::string& path);
EurocImuSensor ReadEurocImuSensor(const std::string& path);

// One row of state_groundtruth_estimate0/data.csv.
struct EurocGroundTruthState {
  int64_t t_ns = 0;
  Rigid3d world_from_body;
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
};
std::vector<EurocGroundTruthState> ReadEurocGroundTruth(const std::string& path);

// Everything of a EuRoC sequence that the project uses, from the folder holding mav0/ or the mav0
// folder itself. The ground truth folder is optional (empty groundtruth when absent).
struct EurocSequence {
  std::string mav0;  // path of the mav0 folder
  EurocCameraSensor cam0;
  EurocImuSensor imu0;
  std::vector<StampedFile> images;  // paths relative to mav0/cam0/data
  ImuBuffer imu;
  std::vector<EurocGroundTruthState> groundtruth;
  // cam_from_imu = (body_from_cam)^-1 * body_from_imu.
  Rigid3d CamFromImu() const { return cam0.body_from_sensor.Inverse() * imu0.body_from_sensor; }
  std::string ImagePath(const StampedFile& f) const { return mav0 + "/cam0/data/" + f.path; }
};
// Returns the mav0 folder (normalised, no trailing slash) for a path that is mav0 itself or holds
// mav0/; empty when neither.
std::string FindEurocMav0(const std::string& path);
EurocSequence ReadEurocSequence(const std::string& path, const ImuBufferOptions& options = {});

}  // namespace imumatch
