#pragma once

#include <cstdint>
#include <optional>
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
//     (without the sensor.yaml files: Kalibr's camchain.yaml and imu_config.yaml / imu.yaml in
//     the folder above mav0 or in its dso/ folder, as TUM-VI's exports have them)
//   mav0/cam0/data.csv    "timestamp [ns], filename" (images in mav0/cam0/data/)
//   mav0/cam0/sensor.yaml intrinsics, resolution, radial-tangential distortion, rate, T_BS
//   mav0/state_groundtruth_estimate0/data.csv (optional)
//     "timestamp, p x y z, q w x y z, v x y z, bw x y z, ba x y z" (quaternion w first)
//   else mav0/mocap0/ or mav0/vicon0/ data.csv (optional): "timestamp, p x y z, q w x y z", the
//     poses of a motion-capture body, with its T_BS in that folder's sensor.yaml when there is
//     one (else the body itself, as TUM-VI's mocap0)
//   mav0/depth0/ (optional, not part of the published EuRoC sequences): depth registered to cam0
//     data.csv    "timestamp [ns], filename" (uint16 PNGs in mav0/depth0/data/, cam0's pixel grid,
//                 each timestamp equal to a cam0 timestamp; raw / depth_scale = metres, 0 = none)
//     sensor.yaml depth_scale (raw units per metre), optional registered_to (must be cam0)
// Header lines start with '#'. sensor.yaml files start with "%YAML:1.0" (OpenCV style), which
// yaml-cpp rejects: it is turned into a comment before parsing (line numbers are kept).

// IMU log -> buffer. Throws InputError(path, line, ...) for a missing file, wrong field count,
// non-numeric or non-finite values, duplicate or out-of-order timestamps.
ImuBuffer ReadEurocImu(const std::string& path, const ImuBufferOptions& options = {});

// cam0/data.csv -> (timestamp, filename) list, same errors, and "no images listed" for a list
// without rows.
std::vector<StampedFile> ReadEurocImageList(const std::string& path);
// depth0/data.csv -> (timestamp, filename) list; the same format and errors as ReadEurocImageList.
std::vector<StampedFile> ReadEurocDepthList(const std::string& path);

// T_BS: pose of the sensor in the body frame, body_from_sensor (p_in_body = T_BS * p_in_sensor).
struct EurocCameraSensor {
  PinholeCamera camera;  // intrinsics, resolution, distortion (k3 = 0 when only four given)
  Rigid3d body_from_sensor;
  double rate_hz = 0.0;  // 0 when the file does not say (Kalibr's camchain)
  // Kalibr's timeshift_cam_imu (t_imu = t_cam + shift, seconds; at most 1 s), from a camchain or
  // from the same key added to a EuRoC cam0/sensor.yaml; 0 when not given. LoadDataset moves the
  // frames' timestamps by it.
  double timeshift_cam_imu_s = 0.0;
};
struct EurocImuSensor {
  ImuParams params;  // noise densities, random walks, rate; gravity left at the default
  Rigid3d body_from_sensor;
};
// depth0/sensor.yaml. The depth images share cam0's intrinsics and pose, so there is no T_BS.
struct EurocDepthSensor {
  double depth_scale = 1000.0;         // raw units per metre (metres = raw / depth_scale)
  std::string registered_to = "cam0";  // the only registration supported
};
// Throw InputError(path, line, ...) for a missing file, YAML syntax errors, missing keys, values of
// the wrong shape, an unsupported camera / distortion model, or a T_BS that is not a rigid
// transform (rotation block not orthonormal within 1e-6 or determinant not +1).
EurocCameraSensor ReadEurocCameraSensor(const std::string& path);
EurocImuSensor ReadEurocImuSensor(const std::string& path);

// Kalibr's calibration files (github.com/ethz-asl/kalibr/wiki/yaml-formats), the same errors.
// camchain.yaml: the named camera's camera_model (pinhole), intrinsics, resolution,
// distortion_model, distortion_coeffs and T_cam_imu (four rows of four numbers, IMU to camera
// coordinates; the body is the IMU: body_from_sensor = T_cam_imu^-1), timeshift_cam_imu if given.
EurocCameraSensor ReadKalibrCamchain(const std::string& path, const std::string& camera = "cam0");
// imu.yaml (Kalibr's IMU noise file; also under a top-level imu0 key as in an imu-camera chain):
// the four noise densities and random walks and update_rate; body_from_sensor identity.
EurocImuSensor ReadKalibrImu(const std::string& path);
// The camera of a yaml calibration file of either kind: a Kalibr camchain (a top-level cam0) or
// a EuRoC camera sensor.yaml.
PinholeCamera ReadYamlCamera(const std::string& path);
// Also InputError(path, line, ...) when depth_scale is not a finite number > 0, or registered_to is
// given and is not "cam0" (depth on another camera's grid would be silently misread).
EurocDepthSensor ReadEurocDepthSensor(const std::string& path);

// One row of state_groundtruth_estimate0/data.csv.
struct EurocGroundTruthState {
  int64_t t_ns = 0;
  Rigid3d world_from_body;
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
};
std::vector<EurocGroundTruthState> ReadEurocGroundTruth(const std::string& path);

// A pose sensor's data.csv (mav0/mocap0 as in TUM-VI, mav0/vicon0 as in EuRoC's Vicon rooms):
// "timestamp [ns], p x y z [m], q w x y z" (quaternion w first), the sensor's pose in its world,
// world_from_sensor. Throws InputError(path, line, ...) as ReadEurocGroundTruth does.
std::vector<StampedPose> ReadEurocPoses(const std::string& path);
// Body states from such poses: world_from_body = world_from_sensor * (body_from_sensor)^-1, and
// the velocity as the least-squares slope of the body's positions over the samples within
// half_window_ns of each (a straight line: at 120 Hz and +-50 ms, 13 samples, a 1 mm position
// noise gives about 0.01 m/s); NaN (no velocity) where the samples do not reach both sides (the
// ends, and the edges of gaps: TUM-VI's motion capture covers only parts of its longer
// sequences). Biases zero.
std::vector<EurocGroundTruthState> GroundTruthFromPoses(
    const std::vector<StampedPose>& world_from_sensor, const Rigid3d& body_from_sensor,
    int64_t half_window_ns = 50'000'000);

// Everything of a EuRoC sequence that the project uses, from the folder holding mav0/ or the mav0
// folder itself. The ground truth and depth0 folders are optional (empty groundtruth, no depth0 and
// no depth_images when absent).
struct EurocSequence {
  std::string mav0;  // path of the mav0 folder
  EurocCameraSensor cam0;
  EurocImuSensor imu0;
  std::optional<EurocDepthSensor> depth0;  // set when mav0/depth0/ exists
  std::vector<StampedFile> images;         // paths relative to mav0/cam0/data
  // Paths relative to mav0/depth0/data; every timestamp is that of an entry of images (checked),
  // but frames may lack depth.
  std::vector<StampedFile> depth_images;
  ImuBuffer imu;
  std::vector<EurocGroundTruthState> groundtruth;
  // Where groundtruth comes from: "state_groundtruth_estimate0", "mocap0", "vicon0" or empty.
  std::string groundtruth_source;
  // The files cam0 and imu0 were read from: their sensor.yaml, or Kalibr's files in their place.
  std::string cam0_calibration_file, imu0_calibration_file;
  bool kalibr_calibration = false;  // either is a Kalibr file
  // cam_from_imu = (body_from_cam)^-1 * body_from_imu.
  Rigid3d CamFromImu() const { return cam0.body_from_sensor.Inverse() * imu0.body_from_sensor; }
  std::string ImagePath(const StampedFile& f) const { return mav0 + "/cam0/data/" + f.path; }
  std::string DepthPath(const StampedFile& f) const { return mav0 + "/depth0/data/" + f.path; }
};
// Returns the mav0 folder (normalised, no trailing slash) for a path that is mav0 itself or holds
// mav0/; empty when neither.
std::string FindEurocMav0(const std::string& path);
// Reads the folders above. When mav0/depth0/ exists its sensor.yaml and data.csv are required, and
// a depth row whose timestamp is not exactly that of a cam0 row is an InputError(depth0/data.csv,
// line, "depth image at t=... has no cam0 frame"): the depth is registered to one cam0 image, so a
// nearest-frame match would pair it with the wrong view.
EurocSequence ReadEurocSequence(const std::string& path, const ImuBufferOptions& options = {});

}  // namespace imumatch
