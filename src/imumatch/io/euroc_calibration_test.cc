#include "imumatch/io/euroc.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/io_test_util.h"
#include "imumatch/testing/test_data.h"

// The calibration files of a EuRoC / ASL folder: cam0, imu0 and depth0 sensor.yaml, Kalibr's
// camchain.yaml and imu.yaml, and the camera-IMU timeshift they may hold.
namespace imumatch {
namespace {

using testing::DataPath;
using testing::ExpectInputError;
using testing::TempDir;

TEST(EurocCalibration, RealCameraSensorYaml) {
  const EurocCameraSensor cam =
      ReadEurocCameraSensor(DataPath("euroc_v101_excerpt/mav0/cam0/sensor.yaml"));
  EXPECT_DOUBLE_EQ(cam.camera.fx, 458.654);
  EXPECT_DOUBLE_EQ(cam.camera.fy, 457.296);
  EXPECT_DOUBLE_EQ(cam.camera.cx, 367.215);
  EXPECT_DOUBLE_EQ(cam.camera.cy, 248.375);
  EXPECT_EQ(cam.camera.width, 752);
  EXPECT_EQ(cam.camera.height, 480);
  EXPECT_DOUBLE_EQ(cam.camera.distortion[0], -0.28340811);
  EXPECT_DOUBLE_EQ(cam.camera.distortion[1], 0.07395907);
  EXPECT_DOUBLE_EQ(cam.camera.distortion[2], 0.00019359);
  EXPECT_DOUBLE_EQ(cam.camera.distortion[3], 1.76187114e-05);
  EXPECT_DOUBLE_EQ(cam.camera.distortion[4], 0.0);
  EXPECT_DOUBLE_EQ(cam.rate_hz, 20.0);
  // T_BS: translation as in the file; rotation close to the file's matrix and orthonormal.
  EXPECT_DOUBLE_EQ(cam.body_from_sensor.translation.x(), -0.0216401454975);
  EXPECT_DOUBLE_EQ(cam.body_from_sensor.translation.y(), -0.064676986768);
  EXPECT_DOUBLE_EQ(cam.body_from_sensor.translation.z(), 0.00981073058949);
  const Eigen::Matrix3d r = cam.body_from_sensor.RotationMatrix();
  EXPECT_NEAR(r(0, 1), -0.999880929698, 1e-6);
  EXPECT_NEAR(r(1, 0), 0.999557249008, 1e-6);
  EXPECT_NEAR(r(2, 2), 0.999660727178, 1e-6);
  EXPECT_LT((r * r.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
}

TEST(EurocCalibration, RealImuSensorYaml) {
  const EurocImuSensor imu =
      ReadEurocImuSensor(DataPath("euroc_v101_excerpt/mav0/imu0/sensor.yaml"));
  EXPECT_DOUBLE_EQ(imu.params.gyro_noise_density, 1.6968e-4);
  EXPECT_DOUBLE_EQ(imu.params.gyro_random_walk, 1.9393e-5);
  EXPECT_DOUBLE_EQ(imu.params.accel_noise_density, 2.0e-3);
  EXPECT_DOUBLE_EQ(imu.params.accel_random_walk, 3.0e-3);
  EXPECT_DOUBLE_EQ(imu.params.rate_hz, 200.0);
  EXPECT_TRUE(imu.body_from_sensor.rotation.isApprox(Eigen::Quaterniond::Identity()));
  EXPECT_EQ(imu.body_from_sensor.translation, Eigen::Vector3d::Zero());
}

TEST(EurocCalibration, DepthSensorYamlErrors) {
  TempDir dir;
  // The OpenCV "%YAML:1.0" first line is accepted like in the other sensor.yaml files.
  const std::string opencv = dir.Write(
      "ok.yaml", "%YAML:1.0\nsensor_type: depth\nregistered_to: cam0\ndepth_scale: 5000\n");
  EXPECT_DOUBLE_EQ(ReadEurocDepthSensor(opencv).depth_scale, 5000.0);
  // registered_to is optional and then means cam0.
  const std::string implicit = dir.Write("implicit.yaml", "depth_scale: 1000.0\n");
  EXPECT_EQ(ReadEurocDepthSensor(implicit).registered_to, "cam0");
  const std::string zero = dir.Write("a.yaml", "sensor_type: depth\ndepth_scale: 0\n");
  ExpectInputError([&] { ReadEurocDepthSensor(zero); }, zero, 2, "depth_scale must be > 0");
  const std::string negative = dir.Write("b.yaml", "%YAML:1.0\ndepth_scale: -1000\n");
  ExpectInputError([&] { ReadEurocDepthSensor(negative); }, negative, 2, "depth_scale must be > 0");
  const std::string missing_key = dir.Write("c.yaml", "sensor_type: depth\nregistered_to: cam0\n");
  ExpectInputError([&] { ReadEurocDepthSensor(missing_key); }, missing_key, 0,
                   "missing key 'depth_scale'");
  const std::string text = dir.Write("d.yaml", "sensor_type: depth\n\ndepth_scale: mm\n");
  ExpectInputError([&] { ReadEurocDepthSensor(text); }, text, 3,
                   "depth_scale: 'mm' is not a number");
  const std::string nan = dir.Write("e.yaml", "depth_scale: .nan\n");
  ExpectInputError([&] { ReadEurocDepthSensor(nan); }, nan, 1, "depth_scale");
  const std::string list = dir.Write("f.yaml", "depth_scale: [1000]\n");
  ExpectInputError([&] { ReadEurocDepthSensor(list); }, list, 1, "expected a number");
  const std::string cam1 = dir.Write(
      "g.yaml", "%YAML:1.0\nsensor_type: depth\nregistered_to: cam1\ndepth_scale: 1000\n");
  ExpectInputError([&] { ReadEurocDepthSensor(cam1); }, cam1, 3, "registered_to 'cam1'");
  const std::string not_text = dir.Write("h.yaml", "registered_to: [cam0]\ndepth_scale: 1000\n");
  ExpectInputError([&] { ReadEurocDepthSensor(not_text); }, not_text, 1, "expected a text value");
  const std::string none = dir.Path("none.yaml");
  ExpectInputError([&] { ReadEurocDepthSensor(none); }, none, 0, "not found");
}

std::string CameraYaml(const std::string& t_bs_row0, const std::string& distortion_model,
                       const std::string& coefficients = "-0.28, 0.07, 0.0002, 1.7e-05",
                       const std::string& intrinsics = "458.654, 457.296, 367.215, 248.375") {
  return "%YAML:1.0\n"            // 1
         "sensor_type: camera\n"  // 2
         "T_BS:\n"                // 3
         "  cols: 4\n"            // 4
         "  rows: 4\n"            // 5
         "  data: [" +
         t_bs_row0 +
         ",\n"                             // 6
         "         0.0, 1.0, 0.0, 0.0,\n"  // 7
         "         0.0, 0.0, 1.0, 0.0,\n"  // 8
         "         0.0, 0.0, 0.0, 1.0]\n"  // 9
         "rate_hz: 20\n"                   // 10
         "resolution: [752, 480]\n"        // 11
         "camera_model: pinhole\n"         // 12
         "intrinsics: [" +
         intrinsics +
         "]\n"  // 13
         "distortion_model: " +
         distortion_model +
         "\n"  // 14
         "distortion_coefficients: [" +
         coefficients + "]\n";  // 15
}

TEST(EurocCalibration, SensorYamlErrors) {
  TempDir dir;
  const std::string ok =
      dir.Write("ok.yaml", CameraYaml("1.0, 0.0, 0.0, 0.1", "radial-tangential"));
  EXPECT_DOUBLE_EQ(ReadEurocCameraSensor(ok).body_from_sensor.translation.x(), 0.1);
  // A rotation block that is not orthonormal: error on the data line.
  const std::string skew =
      dir.Write("a.yaml", CameraYaml("1.0, 0.1, 0.0, 0.1", "radial-tangential"));
  ExpectInputError([&] { ReadEurocCameraSensor(skew); }, skew, 6, "T_BS is not a rigid transform");
  // Kalibr's equidistant (Kannala-Brandt) lens: four coefficients.
  const std::string equi = dir.Write(
      "b.yaml", CameraYaml("1.0, 0.0, 0.0, 0.1", "equidistant", "-0.01, 0.002, -0.0005, 0.0001"));
  const EurocCameraSensor kb = ReadEurocCameraSensor(equi);
  EXPECT_EQ(kb.camera.model, DistortionModel::kEquidistant);
  EXPECT_DOUBLE_EQ(kb.camera.distortion[1], 0.002);
  EXPECT_DOUBLE_EQ(kb.camera.distortion[3], 0.0001);
  EXPECT_EQ(ReadEurocCameraSensor(ok).camera.model, DistortionModel::kRadialTangential);
  const std::string equi5 = dir.Write(
      "b5.yaml", CameraYaml("1.0, 0.0, 0.0, 0.1", "equidistant", "-0.01, 0.002, 0, 0.0001, 0"));
  ExpectInputError([&] { ReadEurocCameraSensor(equi5); }, equi5, 15, "");
  const std::string omni = dir.Write("b6.yaml", CameraYaml("1.0, 0.0, 0.0, 0.1", "omni"));
  ExpectInputError([&] { ReadEurocCameraSensor(omni); }, omni, 14, "not supported");
  // A fisheye (corners 2.7 rad from the axis at fx = 160) is read; one whose lens folds back
  // (k1 = -0.5: at 47 deg) before its field's edge is refused.
  const std::string wide = dir.Write("b7.yaml", CameraYaml("1.0, 0.0, 0.0, 0.1", "equidistant",
                                                           "0, 0, 0, 0", "160, 160, 376, 240"));
  EXPECT_TRUE(ReadEurocCameraSensor(wide).camera.WiderThanField());
  const std::string folding = dir.Write(
      "b8.yaml",
      CameraYaml("1.0, 0.0, 0.0, 0.1", "equidistant", "-0.5, 0, 0, 0", "160, 160, 376, 240"));
  ExpectInputError([&] { ReadEurocCameraSensor(folding); }, folding, 13, "stops growing");
  const std::string short_row = dir.Write("c.yaml", CameraYaml("1.0, 0.0, 0.0", "radtan"));
  ExpectInputError([&] { ReadEurocCameraSensor(short_row); }, short_row, 6,
                   "expected 16 numbers, got 15");
  const std::string text_value = dir.Write("d.yaml", CameraYaml("1.0, 0.0, 0.0, abc", "radtan"));
  ExpectInputError([&] { ReadEurocCameraSensor(text_value); }, text_value, 6, "'abc'");
  const std::string syntax = dir.Write("e.yaml", "%YAML:1.0\nrate_hz: 20\nintrinsics: [1, 2\n");
  ExpectInputError([&] { ReadEurocCameraSensor(syntax); }, syntax, 4, "YAML error");
  const std::string header_only = dir.Write("g.yaml", "%YAML:1.0\n# nothing else\n");
  ExpectInputError([&] { ReadEurocCameraSensor(header_only); }, header_only, 0,
                   "the file holds no keys");
  const std::string a_list = dir.Write("h.yaml", "- 1\n- 2\n");
  ExpectInputError([&] { ReadEurocImuSensor(a_list); }, a_list, 0,
                   "expected a YAML mapping of keys to values");
  const std::string no_key = dir.Write("f.yaml", "%YAML:1.0\nsensor_type: imu\nrate_hz: 200\n");
  ExpectInputError([&] { ReadEurocImuSensor(no_key); }, no_key, 0,
                   "missing key 'gyroscope_noise_density'");
  const std::string missing = dir.Path("none.yaml");
  ExpectInputError([&] { ReadEurocImuSensor(missing); }, missing, 0, "not found");
}

// EuRoC's cam0 and imu0 calibration written as Kalibr writes it (camchain.yaml with T_cam_imu as
// four rows, imu.yaml under imu0): the same camera, extrinsics and noise model as EuRoC's own
// sensor.yaml files give; errors name the file and line.
std::string EurocCamchain(const Rigid3d& cam_from_imu, const std::string& extra = "") {
  const Eigen::Matrix4d m = cam_from_imu.ToMatrix();
  std::ostringstream y;
  y.precision(17);
  y << "cam0:\n  T_cam_imu:\n";
  for (int r = 0; r < 4; ++r) {
    y << "  - [" << m(r, 0) << ", " << m(r, 1) << ", " << m(r, 2) << ", " << m(r, 3) << "]\n";
  }
  y << "  cam_overlaps: []\n  camera_model: pinhole\n"
       "  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"
       "  distortion_model: radtan\n  intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
       "  resolution: [752, 480]\n  rostopic: /cam0/image_raw\n"
    << extra;
  return y.str();
}

TEST(EurocCalibration, KalibrFilesGiveWhatEurocsSensorYamlGives) {
  const std::string real = DataPath("euroc_mh05_flight/mav0");
  const EurocCameraSensor cam = ReadEurocCameraSensor(real + "/cam0/sensor.yaml");
  const EurocImuSensor imu = ReadEurocImuSensor(real + "/imu0/sensor.yaml");
  const Rigid3d cam_from_imu = cam.body_from_sensor.Inverse() * imu.body_from_sensor;
  TempDir dir;
  const std::string chain =
      dir.Write("camchain.yaml", EurocCamchain(cam_from_imu, "  timeshift_cam_imu: 0.0021\n"));
  const EurocCameraSensor kalibr = ReadKalibrCamchain(chain);
  EXPECT_TRUE(kalibr.camera.SameImageGeometry(cam.camera));
  EXPECT_LT((kalibr.body_from_sensor.Inverse().ToMatrix() - cam_from_imu.ToMatrix()).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(kalibr.timeshift_cam_imu_s, 0.0021);
  // Either yaml gives its camera (as `--camera FILE` reads it).
  EXPECT_TRUE(ReadYamlCamera(chain).SameImageGeometry(cam.camera));
  EXPECT_TRUE(ReadYamlCamera(real + "/cam0/sensor.yaml").SameImageGeometry(cam.camera));
  const std::string imu_yaml = dir.Write(
      "imu.yaml",
      "imu0:\n  accelerometer_noise_density: 2.0000e-3\n  accelerometer_random_walk: 3.0000e-3\n"
      "  gyroscope_noise_density: 1.6968e-04\n  gyroscope_random_walk: 1.9393e-05\n"
      "  rostopic: /imu0\n  update_rate: 200.0\n");
  const EurocImuSensor kalibr_imu = ReadKalibrImu(imu_yaml);
  EXPECT_DOUBLE_EQ(kalibr_imu.params.gyro_noise_density, imu.params.gyro_noise_density);
  EXPECT_DOUBLE_EQ(kalibr_imu.params.accel_random_walk, imu.params.accel_random_walk);
  EXPECT_DOUBLE_EQ(kalibr_imu.params.rate_hz, 200.0);
  // Flat, as Kalibr's imu.yaml and TUM-VI's imu_config.yaml are.
  const std::string flat = dir.Write(
      "imu_flat.yaml",
      "accelerometer_noise_density: 0.0028\naccelerometer_random_walk: 0.00086\n"
      "gyroscope_noise_density: 0.00016\ngyroscope_random_walk: 0.000022\nupdate_rate: 200.0\n");
  EXPECT_DOUBLE_EQ(ReadKalibrImu(flat).params.gyro_random_walk, 0.000022);

  // Errors: the camera missing, a row short, a transform that is not rigid, a missing key.
  const std::string kCamera =
      "  camera_model: pinhole\n  distortion_coeffs: [0, 0, 0, 0]\n  distortion_model: radtan\n"
      "  intrinsics: [458.654, 457.296, 367.215, 248.375]\n  resolution: [752, 480]\n";
  ExpectInputError([&] { ReadKalibrCamchain(chain, "cam1"); }, chain, 0, "missing key 'cam1'");
  const std::string short_row =
      dir.Write("b.yaml",
                "cam0:\n  T_cam_imu:\n  - [1, 0, 0, 0]\n  - [0, 1, 0]\n  - [0, 0, 1, 0]\n"
                "  - [0, 0, 0, 1]\n" +
                    kCamera);
  ExpectInputError([&] { ReadKalibrCamchain(short_row); }, short_row, 4, "four rows");
  const std::string not_rigid =
      dir.Write("c.yaml",
                "cam0:\n  T_cam_imu:\n  - [2, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n"
                "  - [0, 0, 0, 1]\n" +
                    kCamera);
  ExpectInputError([&] { ReadKalibrCamchain(not_rigid); }, not_rigid, 3, "not a rigid transform");
  const std::string no_rate = dir.Write("d.yaml", "gyroscope_noise_density: 0.00016\n");
  ExpectInputError([&] { ReadKalibrImu(no_rate); }, no_rate, 0, "missing key");
}

// A EuRoC-layout recording without sensor.yaml files and its Kalibr files in dso/ (as TUM-VI's
// exports): read with the same camera and extrinsics as from EuRoC's own files.
TEST(EurocCalibration, AFolderWithKalibrFilesInDsoReadsLikeItsSensorYaml) {
  const std::string real = DataPath("euroc_mh05_flight/mav0");
  const EurocSequence reference = ReadEurocSequence(real);
  TempDir dir;
  dir.Write("dso/camchain.yaml", EurocCamchain(reference.CamFromImu()));
  dir.Write("dso/imu_config.yaml",
            "accelerometer_noise_density: 2.0000e-3\naccelerometer_random_walk: 3.0000e-3\n"
            "gyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\n"
            "update_rate: 200.0\n");
  for (const char* sensor : {"cam0", "imu0"}) {
    std::filesystem::create_directories(dir.Path(std::string("mav0/") + sensor));
    std::filesystem::copy_file(real + "/" + sensor + "/data.csv",
                               dir.Path(std::string("mav0/") + sensor + "/data.csv"));
  }
  std::filesystem::create_directory_symlink(real + "/cam0/data", dir.Path("mav0/cam0/data"));
  const EurocSequence seq = ReadEurocSequence(dir.path());
  EXPECT_TRUE(seq.kalibr_calibration);
  EXPECT_EQ(seq.cam0_calibration_file, dir.Path("dso/camchain.yaml"));
  EXPECT_TRUE(seq.cam0.camera.SameImageGeometry(reference.cam0.camera));
  EXPECT_LT((seq.CamFromImu().ToMatrix() - reference.CamFromImu().ToMatrix()).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(seq.imu0.params.accel_noise_density, reference.imu0.params.accel_noise_density);
  EXPECT_EQ(seq.images.size(), reference.images.size());
  // Kalibr's timeshift (t_imu = t_cam + shift) moves the frames into the IMU's clock, and the
  // loader says so; beyond a second it is no calibration.
  dir.Write("dso/camchain.yaml",
            EurocCamchain(reference.CamFromImu(), "  timeshift_cam_imu: 0.0021\n"));
  const Dataset shifted = LoadDataset(dir.path());
  ASSERT_EQ(shifted.frames.size(), reference.images.size());
  EXPECT_EQ(shifted.frames[5].t_ns, reference.images[5].t_ns + 2'100'000);
  // The EuRoC layout's cameras may record 16 bits (TUM-VI's do).
  EXPECT_EQ(shifted.sixteen_bit_images, SixteenBitImages::kScaleTo8Bit);
  bool said = false;
  for (const std::string& w : shifted.warnings)
    said |= w.find("timeshift_cam_imu") != std::string::npos;
  EXPECT_TRUE(said);
  const std::string far = dir.Write(
      "dso/camchain.yaml", EurocCamchain(reference.CamFromImu(), "  timeshift_cam_imu: -1.5\n"));
  ExpectInputError([&] { ReadEurocSequence(dir.path()); }, far, 14, "beyond 1 s");
  // Without either, the error names the sensor.yaml that EuRoC's layout expects.
  std::filesystem::remove(dir.Path("dso/camchain.yaml"));
  ExpectInputError([&] { ReadEurocSequence(dir.path()); }, dir.Path("mav0/cam0/sensor.yaml"), 0,
                   "");
}

TEST(EurocCalibration, Mh05Cam0IsTheNamedEurocCamera) {
  const EurocCameraSensor s =
      ReadEurocCameraSensor(testing::DataPath("euroc_mh05_flight/mav0/cam0/sensor.yaml"));
  const PinholeCamera named = PinholeCamera::EurocCam0();
  EXPECT_EQ(s.camera.width, named.width);
  EXPECT_EQ(s.camera.height, named.height);
  EXPECT_DOUBLE_EQ(s.camera.fx, named.fx);
  EXPECT_DOUBLE_EQ(s.camera.fy, named.fy);
  EXPECT_DOUBLE_EQ(s.camera.cx, named.cx);
  EXPECT_DOUBLE_EQ(s.camera.cy, named.cy);
  for (size_t i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(s.camera.distortion[i], named.distortion[i]);
  EXPECT_EQ(s.timeshift_cam_imu_s, 0.0);  // EuRoC's files have no such key
}

// The timeshift eval and track advise to set, written as Kalibr names it into a EuRoC
// cam0/sensor.yaml: read, and the frames move into the IMU's clock by it (the loader says so,
// naming the file); beyond a second it is refused naming the line.
TEST(EurocCalibration, ATimeshiftAddedToCam0SensorYamlMovesTheFrames) {
  const std::string real = testing::DataPath("euroc_mh05_flight/mav0");
  testing::TempDir dir;
  std::filesystem::create_directories(dir.Path("mav0/cam0"));
  std::filesystem::copy(real + "/imu0", dir.Path("mav0/imu0"),
                        std::filesystem::copy_options::recursive);
  std::filesystem::copy_file(real + "/cam0/data.csv", dir.Path("mav0/cam0/data.csv"));
  std::filesystem::create_directory_symlink(real + "/cam0/data", dir.Path("mav0/cam0/data"));
  std::ifstream in(real + "/cam0/sensor.yaml");
  const std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string sensor =
      dir.Write("mav0/cam0/sensor.yaml", yaml + "\ntimeshift_cam_imu: 0.0102\n");
  EXPECT_DOUBLE_EQ(ReadEurocCameraSensor(sensor).timeshift_cam_imu_s, 0.0102);
  const Dataset recorded = LoadDataset(testing::DataPath("euroc_mh05_flight"));
  const Dataset shifted = LoadDataset(dir.path());
  ASSERT_EQ(shifted.frames.size(), recorded.frames.size());
  EXPECT_EQ(shifted.timeshift_cam_imu_s, 0.0102);
  EXPECT_EQ(shifted.frames[7].t_ns, recorded.frames[7].t_ns + 10'200'000);
  bool said = false;
  for (const std::string& w : shifted.warnings) {
    said |= w.find("timeshift_cam_imu of " + sensor + " (0.0102 s)") != std::string::npos;
  }
  EXPECT_TRUE(said) << ::testing::PrintToString(shifted.warnings);
  const std::string far = dir.Write("mav0/cam0/sensor.yaml", yaml + "\ntimeshift_cam_imu: 2\n");
  const int line = static_cast<int>(std::count(yaml.begin(), yaml.end(), '\n')) + 2;
  testing::ExpectInputError([&] { ReadEurocCameraSensor(far); }, far, line, "beyond 1 s");
}

}  // namespace
}  // namespace imumatch
