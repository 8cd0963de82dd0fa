#include "imumatch/io/dataset.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/io/euroc.h"
#include "imumatch/io/image_io.h"
#include "imumatch/io/io_test_util.h"
#include "imumatch/io/pose_pair.h"
#include "imumatch/io/trajectory_io.h"
#include "imumatch/sim/trajectory.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

namespace fs = std::filesystem;
using testing::DataPath;
using testing::ExpectInputError;
using testing::TempDir;

constexpr int64_t kT0 = 1305031102'000000000LL;  // a TUM-like epoch

TEST(Dataset, LoadsEurocExcerptFromEitherFolder) {
  for (const std::string& path :
       {DataPath("euroc_v101_excerpt"), DataPath("euroc_v101_excerpt/mav0/")}) {
    const Dataset d = LoadDataset(path);
    EXPECT_EQ(d.kind, DatasetKind::kEuroc);
    EXPECT_EQ(d.name, "euroc_v101_excerpt");
    ASSERT_EQ(d.frames.size(), 20u);
    EXPECT_EQ(d.frames[0].t_ns, 1403715273262142976LL);
    EXPECT_EQ(d.frames[0].image_path,
              DataPath("euroc_v101_excerpt/mav0/cam0/data/1403715273262142976.png"));
    EXPECT_TRUE(d.frames[0].depth_path.empty());
    EXPECT_FALSE(d.frames[0].world_from_cam.has_value());  // no ground truth in the excerpt
    EXPECT_TRUE(d.groundtruth_world_from_cam.empty());
    EXPECT_EQ(d.imu.size(), 29120u);
    EXPECT_FALSE(d.imu_simulated);
    EXPECT_NE(d.imu_source_note.find("recorded"), std::string::npos);
    EXPECT_DOUBLE_EQ(d.camera.fx, 458.654);
    EXPECT_EQ(d.camera.width, 752);
    EXPECT_DOUBLE_EQ(d.imu_params.gyro_noise_density, 1.6968e-4);
    // The camera looks along the body's x axis rotated by T_BS: the camera's z axis expressed in
    // the IMU frame is the third column of (cam_from_imu)^-1 = T_BS (imu0 T_BS = identity).
    const Eigen::Vector3d cam_z_in_imu =
        d.cam_from_imu.Inverse().rotation * Eigen::Vector3d::UnitZ();
    EXPECT_NEAR(cam_z_in_imu.x(), 0.00414029679422, 1e-6);
    EXPECT_NEAR(cam_z_in_imu.z(), 0.999660727178, 1e-6);
    // The first frames lie inside the IMU log.
    EXPECT_GE(d.frames.front().t_ns, d.imu.begin_ns());
    EXPECT_LE(d.frames.back().t_ns, d.imu.end_ns());
  }
  DatasetOptions options;
  options.first_frame = 5;
  options.max_frames = 3;
  const Dataset sub = LoadDataset(DataPath("euroc_v101_excerpt"), options);
  ASSERT_EQ(sub.frames.size(), 3u);
  EXPECT_EQ(sub.frames[0].t_ns, 1403715273512143104LL);
}

TEST(Dataset, EurocGroundTruthBecomesWorldFromCam) {
  TempDir dir;
  const std::string mav0 = DataPath("euroc_v101_excerpt/mav0");
  // A small EuRoC folder: the real sensor files, two frames, and a hand-made ground truth.
  fs::create_directories(dir.Path("seq/mav0/cam0/data"));
  fs::create_directories(dir.Path("seq/mav0/imu0"));
  fs::copy_file(mav0 + "/cam0/sensor.yaml", dir.Path("seq/mav0/cam0/sensor.yaml"));
  fs::copy_file(mav0 + "/imu0/sensor.yaml", dir.Path("seq/mav0/imu0/sensor.yaml"));
  dir.Write("seq/mav0/cam0/data.csv",
            "#timestamp [ns],filename\n1000000000,a.png\n1005000000,b.png\n");
  WriteImage(dir.Path("seq/mav0/cam0/data/a.png"), cv::Mat(48, 64, CV_8UC1, cv::Scalar(9)));
  WriteImage(dir.Path("seq/mav0/cam0/data/b.png"), cv::Mat(48, 64, CV_8UC1, cv::Scalar(9)));
  std::string imu;
  for (int i = 0; i <= 40; ++i) {
    imu += std::to_string(950000000 + 5000000 * i) + ",0,0,0.1,0,0,9.81\n";
  }
  dir.Write("seq/mav0/imu0/data.csv", imu);
  // Body at (1,2,3), yawed 90 degrees, moving at 0.5 m/s along x, at 1.00 s and 1.01 s.
  dir.Write(
      "seq/mav0/state_groundtruth_estimate0/data.csv",
      "#timestamp,p,p,p,q,q,q,q,v,v,v,bw,bw,bw,ba,ba,ba\n"
      "1000000000,1,2,3,0.70710678118654752,0,0,0.70710678118654752,0.5,0,0,0,0,0,0,0,0\n"
      "1010000000,1.005,2,3,0.70710678118654752,0,0,0.70710678118654752,0.5,0,0,0,0,0,0,0,0\n");
  const Dataset d = LoadDataset(dir.Path("seq"));
  EXPECT_EQ(d.name, "seq");
  ASSERT_EQ(d.frames.size(), 2u);
  ASSERT_EQ(d.groundtruth_world_from_cam.size(), 2u);
  const EurocCameraSensor cam0 = ReadEurocCameraSensor(mav0 + "/cam0/sensor.yaml");
  const Rigid3d world_from_body(ExpSO3(Eigen::Vector3d(0, 0, M_PI / 2)), Eigen::Vector3d(1, 2, 3));
  const Rigid3d expected0 = world_from_body * cam0.body_from_sensor;
  ASSERT_TRUE(d.frames[0].world_from_cam.has_value());
  EXPECT_LT((d.frames[0].world_from_cam->translation - expected0.translation).norm(), 1e-12);
  EXPECT_LT(RotationDistance(d.frames[0].world_from_cam->rotation, expected0.rotation), 1e-12);
  // Frame 1 at 1.005 s: halfway, interpolated.
  ASSERT_TRUE(d.frames[1].world_from_cam.has_value());
  EXPECT_LT((d.frames[1].world_from_cam->translation -
             (expected0.translation + Eigen::Vector3d(0.0025, 0, 0)))
                .norm(),
            1e-12);
  ASSERT_TRUE(d.frames[1].imu_velocity_in_world.has_value());
  EXPECT_NEAR(d.frames[1].imu_velocity_in_world->x(), 0.5, 1e-12);
}

TEST(Dataset, EurocMh05DepthOnFirst36Frames) {
  const Dataset d = LoadDataset(DataPath("euroc_mh05_flight"));
  EXPECT_EQ(d.kind, DatasetKind::kEuroc);
  ASSERT_EQ(d.frames.size(), 200u);
  EXPECT_DOUBLE_EQ(d.camera.depth_scale, 1000.0);
  size_t with_depth = 0;
  for (size_t i = 0; i < d.frames.size(); ++i) {
    const FrameRecord& f = d.frames[i];
    if (i < 36) {
      EXPECT_EQ(f.depth_path,
                DataPath("euroc_mh05_flight/mav0/depth0/data/" + std::to_string(f.t_ns) + ".png"))
          << i;
    } else {
      EXPECT_TRUE(f.depth_path.empty()) << i << ": " << f.depth_path;
    }
    with_depth += f.depth_path.empty() ? 0 : 1;
  }
  EXPECT_EQ(with_depth, 36u);

  // Frame 0's depth decodes on cam0's grid with metric values of a room-sized scene.
  const cv::Mat raw = LoadDepth(d.frames[0].depth_path, cv::Size(d.camera.width, d.camera.height));
  EXPECT_EQ(raw.type(), CV_16UC1);
  EXPECT_EQ(raw.size(), cv::Size(752, 480));
  const cv::Mat metres = DepthToMetres(raw, d.camera.depth_scale);
  std::vector<float> valid;
  for (int r = 0; r < metres.rows; ++r) {
    for (int c = 0; c < metres.cols; ++c) {
      if (std::isfinite(metres.at<float>(r, c))) valid.push_back(metres.at<float>(r, c));
    }
  }
  ASSERT_GT(valid.size(), 1000u);
  std::nth_element(valid.begin(), valid.begin() + static_cast<std::ptrdiff_t>(valid.size() / 2),
                   valid.end());
  const float median = valid[valid.size() / 2];
  EXPECT_GT(median, 0.5f);
  EXPECT_LT(median, 20.0f);

  // An intrinsics override does not describe the depth files: depth_scale still comes from
  // depth0/sensor.yaml. Frame selection keeps each frame's depth.
  DatasetOptions options;
  options.camera = PinholeCamera::TumFreiburg1();
  options.first_frame = 30;
  options.max_frames = 10;
  const Dataset sub = LoadDataset(DataPath("euroc_mh05_flight"), options);
  EXPECT_DOUBLE_EQ(sub.camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(sub.camera.depth_scale, 1000.0);
  ASSERT_EQ(sub.frames.size(), 10u);
  for (size_t i = 0; i < sub.frames.size(); ++i) {
    EXPECT_EQ(sub.frames[i].depth_path.empty(), i >= 6) << i;
  }
}

// A small EuRoC folder with depth0: the real MH_05 sensor.yaml files, three cam0 frames (tiny
// placeholder PNGs: only their existence is checked while loading) at 1.00, 1.05, 1.10 s, an IMU
// log around them, and depth0 rows for the first and last frame with 752x480 16-bit PNGs.
struct EurocDepthFolder {
  std::string root;  // folder holding mav0
  std::string mav0;
  std::string depth_csv;
  std::string depth_yaml;
};

const char* const kDepthHeader = "#timestamp [ns],filename\n";

EurocDepthFolder MakeEurocDepthFolder(const TempDir& dir) {
  EurocDepthFolder f;
  f.root = dir.Path("MH_depth");
  f.mav0 = f.root + "/mav0";
  f.depth_csv = f.mav0 + "/depth0/data.csv";
  f.depth_yaml = f.mav0 + "/depth0/sensor.yaml";
  const std::string real = DataPath("euroc_mh05_flight/mav0");
  fs::create_directories(f.mav0 + "/cam0/data");
  fs::create_directories(f.mav0 + "/imu0");
  fs::create_directories(f.mav0 + "/depth0/data");
  fs::copy_file(real + "/cam0/sensor.yaml", f.mav0 + "/cam0/sensor.yaml");
  fs::copy_file(real + "/imu0/sensor.yaml", f.mav0 + "/imu0/sensor.yaml");
  dir.Write(
      "MH_depth/mav0/cam0/data.csv",
      std::string(kDepthHeader) +
          "1000000000,1000000000.png\n1050000000,1050000000.png\n1100000000,1100000000.png\n");
  for (const char* name : {"1000000000.png", "1050000000.png", "1100000000.png"}) {
    WriteImage(f.mav0 + "/cam0/data/" + name, cv::Mat(48, 64, CV_8UC1, cv::Scalar(9)));
  }
  std::string imu;
  for (int i = 0; i <= 40; ++i) {
    imu += std::to_string(950000000 + 5000000 * i) + ",0,0,0.1,0,0,9.81\n";
  }
  dir.Write("MH_depth/mav0/imu0/data.csv", imu);
  dir.Write("MH_depth/mav0/depth0/sensor.yaml",
            "%YAML:1.0\nsensor_type: depth\nregistered_to: cam0\ndepth_scale: 5000.0\n");
  dir.Write("MH_depth/mav0/depth0/data.csv",
            std::string(kDepthHeader) + "1000000000,1000000000.png\n1100000000,1100000000.png\n");
  for (const char* name : {"1000000000.png", "1100000000.png"}) {
    WriteImage(f.mav0 + "/depth0/data/" + name, cv::Mat(480, 752, CV_16UC1, cv::Scalar(7500)));
  }
  return f;
}

TEST(Dataset, EurocSyntheticDepthFolderLoads) {
  TempDir dir;
  const EurocDepthFolder f = MakeEurocDepthFolder(dir);
  const Dataset d = LoadDataset(f.root);
  ASSERT_EQ(d.frames.size(), 3u);
  EXPECT_DOUBLE_EQ(d.camera.depth_scale, 5000.0);
  EXPECT_EQ(d.frames[0].depth_path, f.mav0 + "/depth0/data/1000000000.png");
  EXPECT_TRUE(d.frames[1].depth_path.empty());  // a frame without depth
  EXPECT_EQ(d.frames[2].depth_path, f.mav0 + "/depth0/data/1100000000.png");
  const cv::Mat metres =
      DepthToMetres(LoadDepth(d.frames[2].depth_path, cv::Size(d.camera.width, d.camera.height)),
                    d.camera.depth_scale);
  EXPECT_FLOAT_EQ(metres.at<float>(0, 0), 1.5f);
  // Without depth0 the folder loads as before: no depth anywhere, the camera's own depth_scale.
  fs::remove_all(f.mav0 + "/depth0");
  const Dataset no_depth = LoadDataset(f.root);
  ASSERT_EQ(no_depth.frames.size(), 3u);
  for (const FrameRecord& r : no_depth.frames) EXPECT_TRUE(r.depth_path.empty());
  EXPECT_DOUBLE_EQ(no_depth.camera.depth_scale, PinholeCamera().depth_scale);
}

TEST(Dataset, EurocDepthListErrorsNameFileAndLine) {
  TempDir dir;
  const EurocDepthFolder f = MakeEurocDepthFolder(dir);
  auto write_list = [&](const std::string& rows) {
    dir.Write("MH_depth/mav0/depth0/data.csv", std::string(kDepthHeader) + rows);
  };
  write_list("1100000000,1100000000.png\n1000000000,1000000000.png\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_csv, 3, "before the previous");
  write_list("1000000000,1000000000.png\n1000000000,1100000000.png\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_csv, 3, "duplicate");
  write_list("1000000000,1000000000.png\n1100000000;1100000000.png\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_csv, 3, "expected 2 fields");
  // Exact timestamps only: 1 ns off cam0's frame is not that frame's depth.
  write_list("1000000000,1000000000.png\n1100000001,1100000000.png\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_csv, 3,
                   "depth image at t=1100000001 ns has no cam0 frame");
  write_list("1000000000,1000000000.png\n1100000000,missing.png\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_csv, 3, "missing.png not found");
  DatasetOptions no_check;
  no_check.check_files_exist = false;
  EXPECT_EQ(LoadDataset(f.root, no_check).frames[2].depth_path,
            f.mav0 + "/depth0/data/missing.png");
  // depth0 present: its list is required.
  fs::remove(f.depth_csv);
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_csv, 0, "not found");
}

TEST(Dataset, EurocDepthSensorErrorsNameFileAndLine) {
  TempDir dir;
  const EurocDepthFolder f = MakeEurocDepthFolder(dir);
  auto write_yaml = [&](const std::string& text) {
    dir.Write("MH_depth/mav0/depth0/sensor.yaml", text);
  };
  write_yaml("%YAML:1.0\nsensor_type: depth\ndepth_scale: 0\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_yaml, 3, "depth_scale must be > 0");
  write_yaml("%YAML:1.0\nsensor_type: depth\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_yaml, 0, "missing key 'depth_scale'");
  write_yaml("%YAML:1.0\nsensor_type: depth\ndepth_scale: thousand\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_yaml, 3, "'thousand' is not a number");
  write_yaml("%YAML:1.0\nsensor_type: depth\nregistered_to: cam1\ndepth_scale: 1000\n");
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_yaml, 3, "registered_to 'cam1'");
  fs::remove(f.depth_yaml);
  ExpectInputError([&] { LoadDataset(f.root); }, f.depth_yaml, 0, "not found");
}

TEST(Dataset, EurocDepthContentCheckedWhenDecoded) {
  TempDir dir;
  const EurocDepthFolder f = MakeEurocDepthFolder(dir);
  const std::string eight_bit = f.mav0 + "/depth0/data/1000000000.png";
  const std::string small = f.mav0 + "/depth0/data/1100000000.png";
  WriteImage(eight_bit, cv::Mat(480, 752, CV_8UC1, cv::Scalar(7)));
  WriteImage(small, cv::Mat(240, 376, CV_16UC1, cv::Scalar(7500)));
  // Loading only checks that the files exist; decoding checks their content against cam0.
  const Dataset d = LoadDataset(f.root);
  const cv::Size cam_size(d.camera.width, d.camera.height);
  ASSERT_EQ(d.frames[0].depth_path, eight_bit);
  ASSERT_EQ(d.frames[2].depth_path, small);
  ExpectInputError([&] { LoadDepth(d.frames[0].depth_path, cam_size); }, eight_bit, 0,
                   "16-bit single-channel");
  ExpectInputError([&] { LoadDepth(d.frames[2].depth_path, cam_size); }, small, 0,
                   "depth image is 376x240, expected 752x480");
}

// Writes a TUM RGB-D folder: the real image pair as two frames (depth 4 ms after rgb) and a
// ground truth sampled at 100 Hz from an analytic trajectory.
struct TumFolder {
  std::string root;
  std::unique_ptr<Trajectory> truth;
};
TumFolder MakeTumFolder(const TempDir& dir, const std::string& name) {
  TumFolder out;
  out.root = dir.Path(name);
  const std::string pair = DataPath("tum_fr1_xyz_pair/");
  fs::create_directories(out.root + "/rgb");
  fs::create_directories(out.root + "/depth");
  fs::copy_file(pair + "img_prev.png", out.root + "/rgb/1.png");
  fs::copy_file(pair + "img_curr.png", out.root + "/rgb/2.png");
  fs::copy_file(pair + "dep_prev.png", out.root + "/depth/1.png");
  fs::copy_file(pair + "dep_curr.png", out.root + "/depth/2.png");
  dir.Write(name + "/rgb.txt",
            "# color images\n1305031102.500000 rgb/1.png\n1305031102.533333 rgb/2.png\n");
  dir.Write(name + "/depth.txt",
            "# depth images\n1305031102.504000 depth/1.png\n1305031102.537333 depth/2.png\n"
            "1305031103.900000 depth/2.png\n");
  // Camera (z forward) looking horizontally, turning about the world z axis at 0.5 rad/s and
  // moving at 0.2 m/s: world_from_cam(0) maps cam z -> world x, cam x -> world -y, cam y -> -z.
  Eigen::Matrix3d r;
  r << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  out.truth = std::make_unique<ConstantRateTrajectory>(Rigid3d(r, Eigen::Vector3d(1.0, 0.5, 1.5)),
                                                       Eigen::Vector3d(0, -0.5, 0),
                                                       Eigen::Vector3d(0.2, 0.1, 0.0), 2.0);
  std::vector<StampedPose> gt;
  for (int i = 0; i <= 200; ++i) {
    gt.push_back({kT0 + i * 10'000'000LL, out.truth->WorldFromBody(0.01 * i)});
  }
  WriteTumTrajectory(out.root + "/groundtruth.txt", gt);
  return out;
}

TEST(Dataset, TumFolderAssociatesAndSimulatesImuFromGroundTruth) {
  TempDir dir;
  const TumFolder tum = MakeTumFolder(dir, "rgbd_dataset_freiburg1_test");
  const Dataset d = LoadDataset(tum.root);
  EXPECT_EQ(d.kind, DatasetKind::kTumRgbd);
  EXPECT_EQ(d.name, "rgbd_dataset_freiburg1_test");
  // fr1 folder name -> TUM fr1 calibration.
  EXPECT_DOUBLE_EQ(d.camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(d.camera.distortion[0], 0.2624);
  ASSERT_EQ(d.frames.size(), 2u);  // the third depth image has no rgb partner
  EXPECT_EQ(d.frames[0].t_ns, 1305031102'500000000LL);
  EXPECT_EQ(d.frames[0].depth_path, tum.root + "/depth/1.png");
  EXPECT_EQ(d.frames[1].image_path, tum.root + "/rgb/2.png");
  const RgbdImages images = LoadRgbd(d.frames[1].image_path, d.frames[1].depth_path);
  EXPECT_EQ(images.depth.size(), cv::Size(640, 480));
  // Ground truth interpolated at 0.533333 s (between samples) vs the analytic pose.
  for (const FrameRecord& f : d.frames) {
    ASSERT_TRUE(f.world_from_cam.has_value());
    const Rigid3d truth = tum.truth->WorldFromBody(NsToSeconds(f.t_ns - kT0));
    EXPECT_LT((f.world_from_cam->translation - truth.translation).norm(), 1e-9);
    EXPECT_LT(RotationDistance(f.world_from_cam->rotation, truth.rotation), 1e-9);
  }
  EXPECT_EQ(d.groundtruth_world_from_cam.size(), 201u);

  // Simulated IMU: EuRoC model, seed 42, 200 Hz over the ground-truth span, with a note.
  EXPECT_TRUE(d.imu_simulated);
  EXPECT_NE(d.imu_source_note.find("IMU simulated from ground truth with the EuRoC ADIS16448 "
                                   "noise model, seed 42"),
            std::string::npos)
      << d.imu_source_note;
  EXPECT_EQ(d.imu.begin_ns(), kT0);
  EXPECT_NEAR(static_cast<double>(d.imu.size()), 401.0, 1.0);
  // Mean gyro over the middle second ~ the true rate (0, -0.5, 0) in the camera frame (noise and
  // bias walk of the ADIS16448 are ~1e-3 rad/s here).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_accel = Eigen::Vector3d::Zero();
  int n = 0;
  for (const ImuSample& s : d.imu.Slice(kT0 + 500'000'000, kT0 + 1'500'000'000)) {
    mean += s.gyro_rad_s;
    mean_accel += s.accel_m_s2;
    ++n;
  }
  mean /= n;
  mean_accel /= n;
  EXPECT_LT((mean - Eigen::Vector3d(0, -0.5, 0)).norm(), 0.01) << mean.transpose();
  // Constant velocity: the accelerometer reads only gravity's reaction, +9.81 along world up =
  // camera -y.
  EXPECT_LT((mean_accel - Eigen::Vector3d(0, -9.81, 0)).norm(), 0.05) << mean_accel.transpose();
  ASSERT_TRUE(d.frames[0].imu_velocity_in_world.has_value());
  EXPECT_LT((*d.frames[0].imu_velocity_in_world - Eigen::Vector3d(0.2, 0.1, 0)).norm(), 1e-6);

  // Fixed seed: identical on reload; another seed differs.
  const Dataset again = LoadDataset(tum.root);
  ASSERT_EQ(again.imu.size(), d.imu.size());
  EXPECT_EQ(again.imu.samples()[100].gyro_rad_s, d.imu.samples()[100].gyro_rad_s);
  DatasetOptions other;
  other.imu_seed = 7;
  other.groundtruth_lookup = GroundTruthLookup::kNearest;
  const Dataset seven = LoadDataset(tum.root, other);
  EXPECT_NE(seven.imu.samples()[100].gyro_rad_s, d.imu.samples()[100].gyro_rad_s);
  // Nearest lookup: frame 1 (0.533333 s) takes the 0.53 s sample exactly.
  const Rigid3d at_053 = tum.truth->WorldFromBody(0.53);
  EXPECT_LT((seven.frames[1].world_from_cam->translation - at_053.translation).norm(), 1e-12);
}

TEST(Dataset, TumCameraFromCameraTxtOrOptions) {
  TempDir dir;
  const TumFolder tum = MakeTumFolder(dir, "my_sequence");
  DatasetOptions options;
  options.simulate_imu = false;
  const Dataset kinect = LoadDataset(tum.root, options);
  EXPECT_DOUBLE_EQ(kinect.camera.fx, 525.0);  // not a freiburg name: Kinect default
  EXPECT_TRUE(kinect.imu.empty());
  EXPECT_FALSE(kinect.imu_simulated);
  dir.Write("my_sequence/camera.txt", "# fx fy cx cy w h\n500 501 320 240 640 480\n");
  EXPECT_DOUBLE_EQ(LoadDataset(tum.root, options).camera.fy, 501.0);
  options.camera = PinholeCamera::TumFreiburg1();
  EXPECT_DOUBLE_EQ(LoadDataset(tum.root, options).camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(TumCameraForFolderName("rgbd_dataset_freiburg3_long_office").fx, 535.4);
  EXPECT_DOUBLE_EQ(TumCameraForFolderName("rgbd_dataset_freiburg2_desk").cy, 249.7);
}

// A camera file for --camera: a Kalibr / EuRoC camera yaml (here the real MH_05 one) or a text
// line; errors name the file and line.
TEST(Dataset, ReadCameraFileReadsYamlOrText) {
  const PinholeCamera euroc = ReadCameraFile(DataPath("euroc_mh05_flight/mav0/cam0/sensor.yaml"));
  EXPECT_EQ(euroc.width, 752);
  EXPECT_DOUBLE_EQ(euroc.fx, 458.654);
  EXPECT_DOUBLE_EQ(euroc.distortion[0], -0.28340811);
  EXPECT_EQ(euroc.model, DistortionModel::kRadialTangential);
  TempDir dir;
  dir.Write(
      "fisheye.txt",
      "# an equidistant lens\nequidistant 380 379 370 245 752 480 -0.02 0.01 -0.004 0.0005\n");
  const PinholeCamera kb = ReadCameraFile(dir.Path("fisheye.txt"));
  EXPECT_EQ(kb.model, DistortionModel::kEquidistant);
  EXPECT_DOUBLE_EQ(kb.distortion[3], 0.0005);
  dir.Write("bad.txt", "\n380 379 370\n");
  ExpectInputError([&] { ReadCameraFile(dir.Path("bad.txt")); }, dir.Path("bad.txt"), 2,
                   "expected");
  EXPECT_THROW(ReadCameraFile(dir.Path("missing.yaml")), InputError);
}

// The camera override reaches a two-frame pose-pair folder too (eval --camera on the TUM pair).
TEST(Dataset, PosePairFolderTakesTheCameraOverride) {
  const std::string pair = DataPath("tum_fr1_xyz_pair");
  EXPECT_DOUBLE_EQ(LoadDatasetOrPosePair(pair).camera.fx, 525.0);  // the excerpt's Kinect values
  DatasetOptions options;
  options.camera = PinholeCamera::TumFreiburg1();
  const Dataset d = LoadDatasetOrPosePair(pair, options);
  EXPECT_DOUBLE_EQ(d.camera.fx, 517.3);
  EXPECT_TRUE(d.camera.HasDistortion());
  EXPECT_EQ(d.frames.size(), 2u);
}

TEST(Dataset, MissingListedImageNamesListAndLine) {
  TempDir dir;
  const TumFolder tum = MakeTumFolder(dir, "seq");
  fs::remove(tum.root + "/rgb/2.png");
  ExpectInputError([&] { LoadDataset(tum.root); }, tum.root + "/rgb.txt", 3, "rgb/2.png not found");
}

TEST(Dataset, SimulatedImuSpanIsBounded) {
  TempDir dir;
  const TumFolder tum = MakeTumFolder(dir, "seq");  // ground truth over 2 s
  DatasetOptions options;
  options.check_files_exist = false;
  options.max_simulated_imu_span_ns = 1'000'000'000;  // 1 s
  ExpectInputError([&] { LoadDataset(tum.root, options); }, tum.root + "/groundtruth.txt", 0,
                   "ground truth spans 2");
  options.simulate_imu = false;  // nothing simulated: no bound to meet
  EXPECT_NO_THROW(LoadDataset(tum.root, options));
  options.max_simulated_imu_span_ns = DatasetOptions::kMaxSimulatedImuSpanNs + 1;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.max_simulated_imu_span_ns = 0;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

TEST(Dataset, UnknownFolderAndBadOptions) {
  TempDir dir;
  ExpectInputError([&] { LoadDataset(dir.path()); }, dir.path(), 0, "not a recognised dataset");
  ExpectInputError([&] { LoadDataset(dir.Path("missing")); }, dir.Path("missing"), 0, "not found");
  DatasetOptions options;
  options.imu_model = "phone9000";
  EXPECT_THROW(LoadDataset(DataPath("euroc_v101_excerpt"), options), InvalidArgument);
  options = DatasetOptions();
  options.timeshift_cam_imu_s = 1.5;  // no calibration: over a second
  EXPECT_THROW(LoadDataset(DataPath("euroc_v101_excerpt"), options), InvalidArgument);
  options.timeshift_cam_imu_s = std::nan("");
  EXPECT_THROW(LoadDataset(DataPath("euroc_v101_excerpt"), options), InvalidArgument);
}

// A timeshift given in the options (eval / track --timeshift-cam-imu) replaces the calibration's
// (MH_05 has none: 0): every frame moves by it into the IMU's clock, its ground truth read there,
// and the loader says so. A TUM RGB-D folder (IMU simulated in the ground truth's clock) and a
// synthetic one (one clock) refuse it.
TEST(Dataset, AGivenTimeshiftMovesTheFramesIntoTheImusClock) {
  const Dataset recorded = LoadDataset(DataPath("euroc_mh05_flight"));
  EXPECT_EQ(recorded.timeshift_cam_imu_s, 0.0);
  DatasetOptions options;
  options.timeshift_cam_imu_s = -0.004;
  const Dataset shifted = LoadDataset(DataPath("euroc_mh05_flight"), options);
  EXPECT_EQ(shifted.timeshift_cam_imu_s, -0.004);
  ASSERT_EQ(shifted.frames.size(), recorded.frames.size());
  for (size_t i = 50; i + 1 < shifted.frames.size(); i += 50) {
    EXPECT_EQ(shifted.frames[i].t_ns, recorded.frames[i].t_ns - 4'000'000) << i;
    // The ground truth at the moved stamp: where the camera was 4 ms earlier, i.e. moved back by
    // its velocity (from the neighbouring frames' ground truth, 50 ms apart) times 4 ms.
    ASSERT_TRUE(shifted.frames[i].world_from_cam && recorded.frames[i].world_from_cam &&
                recorded.frames[i - 1].world_from_cam && recorded.frames[i + 1].world_from_cam);
    const Eigen::Vector3d velocity =
        (recorded.frames[i + 1].world_from_cam->translation -
         recorded.frames[i - 1].world_from_cam->translation) /
        NsToSeconds(recorded.frames[i + 1].t_ns - recorded.frames[i - 1].t_ns);
    const Eigen::Vector3d moved = shifted.frames[i].world_from_cam->translation -
                                  recorded.frames[i].world_from_cam->translation;
    EXPECT_GT(velocity.norm(), 0.2) << i;  // in flight: the move is measurable
    EXPECT_LT((moved + 0.004 * velocity).norm(), 0.15 * 0.004 * velocity.norm())
        << i << ": moved " << moved.transpose() << ", velocity " << velocity.transpose();
  }
  bool said = false;
  for (const std::string& w : shifted.warnings) {
    said |= w.find("given timeshift_cam_imu (-0.004 s, replacing the calibration's 0 s)") !=
            std::string::npos;
  }
  EXPECT_TRUE(said);
  TempDir dir;
  const TumFolder tum = MakeTumFolder(dir, "rgbd_dataset_freiburg1_test");
  try {
    LoadDataset(tum.root, options);
    ADD_FAILURE() << "a TUM RGB-D folder took a timeshift";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("applies to EuRoC/ASL recordings"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(LoadDatasetOrPosePair(DataPath("tum_fr1_xyz_pair"), options), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
