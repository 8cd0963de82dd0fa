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
#include "imumatch/io/image_io.h"
#include "imumatch/io/tum_rgbd.h"
#include "imumatch/sim/spline_trajectory.h"

namespace imumatch {

enum class DatasetKind { kTumRgbd, kEuroc, kSynthetic };
const char* ToString(DatasetKind kind);  // "tum_rgbd" | "euroc" | "synthetic"

// One camera frame of a dataset.
struct FrameRecord {
  int64_t t_ns = 0;
  std::string image_path;  // full path (root joined with the list's relative name)
  // Empty if none: EuRoC without mav0/depth0 or a cam0 frame without a depth0 row, TUM rgb frames
  // without associated depth.
  std::string depth_path;
  std::optional<Rigid3d> world_from_cam;  // ground truth at t_ns, when known
  // Ground-truth velocity of the IMU in the world at t_ns, when known (synthetic: exact; EuRoC:
  // interpolated from state_groundtruth_estimate0, body = IMU; TUM: from the spline fit used to
  // simulate the IMU). Lets an evaluation seed the integrator's velocity.
  std::optional<Eigen::Vector3d> imu_velocity_in_world;
};

struct Dataset {
  std::string name;  // folder name, e.g. "rgbd_dataset_freiburg1_xyz" or "V1_01_easy"
  std::string root;  // the folder holding the data (mav0 for EuRoC)
  DatasetKind kind = DatasetKind::kTumRgbd;
  PinholeCamera camera;
  std::vector<FrameRecord> frames;  // time-ordered
  ImuBuffer imu;
  bool imu_simulated = false;
  std::string imu_source_note;  // one human-readable line: where the IMU data comes from
  ImuParams imu_params;         // noise model of the IMU (recorded: sensor.yaml; simulated: model)
  Rigid3d cam_from_imu;         // p_in_cam = cam_from_imu * p_in_imu
  double timeshift_cam_imu_s = 0.0;  // moved the frames into the IMU's clock (EuRoC)
  std::vector<StampedPose> groundtruth_world_from_cam;  // full-rate ground truth (may be empty)
  // 16-bit gray camera images: scaled to 8 bits in the EuRoC layout (TUM-VI's are 16-bit),
  // refused elsewhere (there a depth PNG listed as an image is the likelier cause).
  SixteenBitImages sixteen_bit_images = SixteenBitImages::kRefuse;
  // What the loader assumed or dropped that the user should know (frames without a depth
  // partner, a layout read as another, an unused file that could not be read), one line each.
  std::vector<std::string> warnings;
};

struct DatasetOptions {
  // Intrinsics override. Otherwise: EuRoC cam0/sensor.yaml; synthetic sequence.json; TUM a
  // camera.txt beside rgb.txt (ReadCameraFromText format), else the published calibration for
  // folders named *freiburg1* / *freiburg2* / *freiburg3*, else PinholeCamera::KinectDefault().
  // A EuRoC depth0/sensor.yaml sets depth_scale even when this is given.
  std::optional<PinholeCamera> camera;

  // TUM RGB-D association (associate.py): rgb-depth pairs and ground truth within this difference.
  int64_t max_time_difference_ns = 20'000'000;
  GroundTruthLookup groundtruth_lookup = GroundTruthLookup::kInterpolate;
  int64_t groundtruth_max_difference_ns = 20'000'000;

  // TUM RGB-D records no gyroscope: the IMU is simulated from the ground truth (a SplineTrajectory
  // fitted to world_from_cam, then SimulateImu) with this named model (ImuParams::FromName), seed
  // and extrinsic. simulate_imu = false leaves the buffer empty.
  bool simulate_imu = true;
  std::string imu_model = "euroc";
  uint64_t imu_seed = 42;
  Rigid3d tum_cam_from_imu;  // identity: the simulated IMU sits at the camera
  SplineFitOptions spline;

  // Bounded work: the IMU is simulated over the ground truth's whole span (200 Hz: an hour is
  // 720 000 samples, 40 MB); a longer span is an InputError (a timestamp jump?). At most
  // kMaxSimulatedImuSpanNs (1 h, far longer than any TUM sequence: the longest is 2.5 min).
  static constexpr int64_t kMaxSimulatedImuSpanNs = 3'600'000'000'000;
  int64_t max_simulated_imu_span_ns = kMaxSimulatedImuSpanNs;

  ImuBufferOptions imu_buffer;
  // EuRoC/ASL: the offset between the camera's and the IMU's clocks (t_imu = t_cam + shift, s,
  // |shift| <= 1), replacing the calibration's timeshift_cam_imu (Kalibr's camchain; 0 when it
  // has none). eval and track measure the residual offset from the fitted rotations
  // (EstimateTimeOffset) and say when it is worth setting. Other layouts refuse it.
  std::optional<double> timeshift_cam_imu_s;
  // Keep frames [first_frame, first_frame + max_frames) after association (0 = all).
  size_t first_frame = 0;
  size_t max_frames = 0;
  // Check that every listed image (and depth image) file exists while loading (InputError naming
  // the list file and line otherwise). Images are not decoded.
  bool check_files_exist = true;

  void Check() const;  // throws InvalidArgument
};

// Detects the layout and loads the dataset:
//  - a folder with sequence.json written by WriteSyntheticSequence (synthetic_io.h);
//  - a TUM RGB-D folder (rgb.txt);
//  - a EuRoC folder holding mav0/, or the mav0 folder itself.
// Throws InputError (file and line) for missing or malformed files, InvalidArgument for bad
// options.
Dataset LoadDataset(const std::string& path, const DatasetOptions& options = DatasetOptions());

// Loaders for one layout each (LoadDataset dispatches to them).
Dataset LoadTumRgbdDataset(const std::string& root, const DatasetOptions& options);
Dataset LoadEurocDataset(const std::string& path, const DatasetOptions& options);
Dataset LoadSyntheticDataset(const std::string& root, const DatasetOptions& options);

// The intrinsics LoadDataset uses for a TUM folder without camera.txt, chosen by its name: TUM's
// published calibrations of freiburg1 (fx=517.3 fy=516.5 cx=318.6 cy=255.3, d = 0.2624 -0.9531
// -0.0054 0.0026 1.1633), freiburg2 (520.9 521.0 325.1 249.7, d = 0.2312 -0.7849 -0.0033 -0.0001
// 0.9172) and freiburg3 (535.4 539.2 320.1 247.6, no distortion), else the Kinect default.
PinholeCamera TumCameraForFolderName(const std::string& folder_name);

// A camera's intrinsics and lens from a file, for DatasetOptions::camera: a EuRoC camera
// sensor.yaml or a Kalibr camchain.yaml's cam0 (*.yaml, *.yml: ReadYamlCamera; their extrinsics
// are not used) or a text line
// (ReadCameraFromText: "[radtan|equidistant] fx fy cx cy [width height [k...]]"). Throws
// InputError naming the file (and line) when it is missing or malformed.
PinholeCamera ReadCameraFile(const std::string& path);

}  // namespace imumatch
