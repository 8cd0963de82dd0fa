#include "imumatch/io/euroc.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/image_io.h"
#include "imumatch/io/io_test_util.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

using testing::DataPath;
using testing::ExpectInputError;
using testing::TempDir;

const char* const kCsvHeader =
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";

TEST(Euroc, RealImuLogParsesFully) {
  const ImuBuffer imu = ReadEurocImu(DataPath("euroc_v101_excerpt/mav0/imu0/data.csv"));
  ASSERT_EQ(imu.size(), 29120u);
  // First and last rows of the file, copied by hand.
  const ImuSample& first = imu.samples().front();
  EXPECT_EQ(first.t_ns, 1403715273262142976LL);
  EXPECT_DOUBLE_EQ(first.gyro_rad_s.x(), -0.0020943951023931952);
  EXPECT_DOUBLE_EQ(first.gyro_rad_s.y(), 0.017453292519943295);
  EXPECT_DOUBLE_EQ(first.gyro_rad_s.z(), 0.07749261878854824);
  EXPECT_DOUBLE_EQ(first.accel_m_s2.x(), 9.0874956666666655);
  EXPECT_DOUBLE_EQ(first.accel_m_s2.y(), 0.13075533333333333);
  EXPECT_DOUBLE_EQ(first.accel_m_s2.z(), -3.6938381666666662);
  const ImuSample& last = imu.samples().back();
  EXPECT_EQ(last.t_ns, 1403715418857143040LL);
  EXPECT_DOUBLE_EQ(last.gyro_rad_s.x(), -0.00069813170079773186);
  EXPECT_DOUBLE_EQ(last.gyro_rad_s.y(), 0.023736477827122883);
  EXPECT_DOUBLE_EQ(last.gyro_rad_s.z(), 0.074001960284559576);
  EXPECT_DOUBLE_EQ(last.accel_m_s2.x(), 9.1610455416666667);
  EXPECT_DOUBLE_EQ(last.accel_m_s2.y(), 0.26151066666666667);
  EXPECT_DOUBLE_EQ(last.accel_m_s2.z(), -3.2035056666666666);
  // 200 Hz over 145.6 s.
  EXPECT_NEAR(NsToSeconds(imu.end_ns() - imu.begin_ns()), 29119 * 0.005, 0.01);
}

TEST(Euroc, RealCameraListAndImages) {
  const std::vector<StampedFile> list =
      ReadEurocImageList(DataPath("euroc_v101_excerpt/mav0/cam0/data.csv"));
  ASSERT_EQ(list.size(), 20u);
  EXPECT_EQ(list.front().t_ns, 1403715273262142976LL);
  EXPECT_EQ(list.front().path, "1403715273262142976.png");
  EXPECT_EQ(list.back().t_ns, 1403715274212143104LL);
  for (const StampedFile& f : list) {
    const cv::Mat image = LoadImage(DataPath("euroc_v101_excerpt/mav0/cam0/data/" + f.path));
    EXPECT_EQ(image.size(), cv::Size(752, 480)) << f.path;
  }
}

TEST(Euroc, RealSequenceWithoutGroundTruth) {
  for (const std::string& path :
       {DataPath("euroc_v101_excerpt"), DataPath("euroc_v101_excerpt/mav0")}) {
    EXPECT_EQ(FindEurocMav0(path), DataPath("euroc_v101_excerpt/mav0"));
  }
  const EurocSequence seq = ReadEurocSequence(DataPath("euroc_v101_excerpt"));
  EXPECT_EQ(seq.images.size(), 20u);
  EXPECT_EQ(seq.imu.size(), 29120u);
  EXPECT_TRUE(seq.groundtruth.empty());
  // imu0's T_BS is the identity, so cam_from_imu is the inverse of cam0's T_BS: the IMU origin
  // (body origin) seen from the camera is -R^T t.
  const Rigid3d cam_from_imu = seq.CamFromImu();
  const Rigid3d& body_from_cam = seq.cam0.body_from_sensor;
  EXPECT_LT((cam_from_imu * body_from_cam.translation).norm(), 1e-12);
  EXPECT_LT(
      (body_from_cam * (cam_from_imu * Eigen::Vector3d(1, 2, 3)) - Eigen::Vector3d(1, 2, 3)).norm(),
      1e-12);
  EXPECT_EQ(seq.ImagePath(seq.images[0]),
            DataPath("euroc_v101_excerpt/mav0/cam0/data/1403715273262142976.png"));
  EXPECT_TRUE(FindEurocMav0(DataPath("tum_fr1_xyz_pair")).empty());
  ExpectInputError([&] { ReadEurocSequence(DataPath("tum_fr1_xyz_pair")); },
                   DataPath("tum_fr1_xyz_pair"), 0, "not a EuRoC folder");
}

TEST(Euroc, ImuCsvMissingFile) {
  TempDir dir;
  const std::string path = dir.Path("imu0/data.csv");
  ExpectInputError([&] { ReadEurocImu(path); }, path, 0, "not found");
}

TEST(Euroc, ImuCsvWrongFieldCount) {
  TempDir dir;
  const std::string path =
      dir.Write("data.csv", std::string(kCsvHeader) + "1000,0,0,0,0,0,9.8\n2000,0,0,0,0,9.8\n");
  ExpectInputError([&] { ReadEurocImu(path); }, path, 3, "expected 7 fields");
  const std::string empty_field =
      dir.Write("b.csv", std::string(kCsvHeader) + "1000,0,,0,0,0,9.8\n");
  ExpectInputError([&] { ReadEurocImu(empty_field); }, empty_field, 2, "empty field 3");
}

TEST(Euroc, ImuCsvNonNumericAndNaN) {
  TempDir dir;
  const std::string text = dir.Write("a.csv", "1000,0,0,0,0,0,9.8\n2000,0,0,0,0,0,9.8m\n");
  ExpectInputError([&] { ReadEurocImu(text); }, text, 2, "a_z: '9.8m' is not a number");
  const std::string float_t = dir.Write("b.csv", "1000.5,0,0,0,0,0,9.8\n");
  ExpectInputError([&] { ReadEurocImu(float_t); }, float_t, 1, "nanoseconds");
  const std::string nan = dir.Write("c.csv", "1000,0,0,0,0,0,9.8\r\n2000,NaN,0,0,0,0,9.8\r\n");
  ExpectInputError([&] { ReadEurocImu(nan); }, nan, 2, "w_x");
}

TEST(Euroc, ImuCsvUnsortedAndDuplicate) {
  TempDir dir;
  const std::string unsorted =
      dir.Write("a.csv", "1000,0,0,0,0,0,9.8\n3000,0,0,0,0,0,9.8\n2000,0,0,0,0,0,9.8\n");
  ExpectInputError([&] { ReadEurocImu(unsorted); }, unsorted, 3, "out-of-order");
  const std::string dup = dir.Write("b.csv", "1000,0,0,0,0,0,9.8\n1000,0,0,0,0,0,9.8\n");
  ExpectInputError([&] { ReadEurocImu(dup); }, dup, 2, "duplicate");
}

TEST(Euroc, ImageListErrors) {
  TempDir dir;
  const std::string fields = dir.Write("a.csv", "#timestamp [ns],filename\n1000,1000.png,x\n");
  ExpectInputError([&] { ReadEurocImageList(fields); }, fields, 2, "expected 2 fields");
  const std::string dup = dir.Write("b.csv", "1000,1000.png\n1000,1001.png\n");
  ExpectInputError([&] { ReadEurocImageList(dup); }, dup, 2, "duplicate");
  const std::string unsorted = dir.Write("c.csv", "2000,2000.png\n1000,1000.png\n");
  ExpectInputError([&] { ReadEurocImageList(unsorted); }, unsorted, 2, "before the previous");
  const std::string empty = dir.Write("d.csv", "#timestamp [ns],filename\n");
  ExpectInputError([&] { ReadEurocImageList(empty); }, empty, 0, "no images");
}

TEST(Euroc, RealDepthListAndSensor) {
  const std::string depth0 = DataPath("euroc_mh05_flight/mav0/depth0");
  const std::vector<StampedFile> list = ReadEurocDepthList(depth0 + "/data.csv");
  ASSERT_EQ(list.size(), 36u);
  EXPECT_EQ(list.front().t_ns, 1403638538577829376LL);
  EXPECT_EQ(list.front().path, "1403638538577829376.png");
  EXPECT_EQ(list.front().line, 2);  // after the "#timestamp [ns],filename" header
  const EurocDepthSensor sensor = ReadEurocDepthSensor(depth0 + "/sensor.yaml");
  EXPECT_DOUBLE_EQ(sensor.depth_scale, 1000.0);
  EXPECT_EQ(sensor.registered_to, "cam0");
}

TEST(Euroc, RealSequenceWithAndWithoutDepth) {
  const EurocSequence seq = ReadEurocSequence(DataPath("euroc_mh05_flight"));
  ASSERT_TRUE(seq.depth0.has_value());
  EXPECT_DOUBLE_EQ(seq.depth0->depth_scale, 1000.0);
  ASSERT_EQ(seq.images.size(), 200u);
  ASSERT_EQ(seq.depth_images.size(), 36u);
  // depth0 covers cam0's first 36 frames, timestamp for timestamp.
  for (size_t i = 0; i < seq.depth_images.size(); ++i) {
    EXPECT_EQ(seq.depth_images[i].t_ns, seq.images[i].t_ns) << i;
  }
  EXPECT_EQ(seq.DepthPath(seq.depth_images[0]),
            DataPath("euroc_mh05_flight/mav0/depth0/data/1403638538577829376.png"));
  const EurocSequence no_depth = ReadEurocSequence(DataPath("euroc_v101_excerpt"));
  EXPECT_FALSE(no_depth.depth0.has_value());
  EXPECT_TRUE(no_depth.depth_images.empty());
}

TEST(Euroc, DepthListErrors) {
  TempDir dir;
  const std::string header = "#timestamp [ns],filename\n";
  const std::string ok = dir.Write("ok.csv", header + "1000,a.png\n\n# note\n2000,b.png\n");
  ASSERT_EQ(ReadEurocDepthList(ok).size(), 2u);
  EXPECT_EQ(ReadEurocDepthList(ok)[1].line, 5);
  const std::string malformed = dir.Write("a.csv", header + "1000,a.png\n2000\n");
  ExpectInputError([&] { ReadEurocDepthList(malformed); }, malformed, 3, "expected 2 fields");
  const std::string bad_time = dir.Write("b.csv", header + "1.5e9,a.png\n");
  ExpectInputError([&] { ReadEurocDepthList(bad_time); }, bad_time, 2, "nanoseconds");
  const std::string dup = dir.Write("c.csv", header + "1000,a.png\n1000,b.png\n");
  ExpectInputError([&] { ReadEurocDepthList(dup); }, dup, 3, "duplicate");
  const std::string unsorted = dir.Write("d.csv", header + "2000,b.png\n1000,a.png\n");
  ExpectInputError([&] { ReadEurocDepthList(unsorted); }, unsorted, 3, "before the previous");
  const std::string empty = dir.Write("e.csv", header);
  ExpectInputError([&] { ReadEurocDepthList(empty); }, empty, 0, "no depth images listed");
  const std::string missing = dir.Path("none.csv");
  ExpectInputError([&] { ReadEurocDepthList(missing); }, missing, 0, "not found");
}

TEST(Euroc, GroundTruthCsvHasQuaternionWFirst) {
  TempDir dir;
  // 90 degrees about z: w = x... = cos 45, z = sin 45.
  const std::string path = dir.Write(
      "data.csv",
      "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
      "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
      "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
      "b_a_RS_S_z [m s^-2]\n"
      "1403715274302142976,0.878612,2.142470,0.947262,0.7071068,0.0,0.0,0.7071068,0.009474,"
      "-0.014009,-0.002145,-0.002229,0.020700,0.076350,-0.012492,0.547666,0.069073\n");
  const std::vector<EurocGroundTruthState> gt = ReadEurocGroundTruth(path);
  ASSERT_EQ(gt.size(), 1u);
  EXPECT_EQ(gt[0].t_ns, 1403715274302142976LL);
  EXPECT_DOUBLE_EQ(gt[0].world_from_body.translation.y(), 2.142470);
  EXPECT_LT((gt[0].world_from_body * Eigen::Vector3d(1, 0, 0) -
             Eigen::Vector3d(0.878612, 3.142470, 0.947262))
                .norm(),
            1e-6);
  EXPECT_DOUBLE_EQ(gt[0].velocity_in_world.x(), 0.009474);
  EXPECT_DOUBLE_EQ(gt[0].gyro_bias.z(), 0.076350);
  EXPECT_DOUBLE_EQ(gt[0].accel_bias.y(), 0.547666);
  const std::string bad_q = dir.Write("b.csv", "1,0,0,0,0.5,0,0,0.5,0,0,0,0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadEurocGroundTruth(bad_q); }, bad_q, 1, "norm");
}

TEST(Euroc, PoseGroundTruthParsesAndRefusesBadRows) {
  TempDir dir;
  const std::string path = dir.Write(
      "data.csv",
      "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
      "q_RS_z []\n"
      "1520530308199447626,0.878612,2.142470,0.947262,0.7071068,0.0,0.0,0.7071068\n"
      "1520530308207780958,0.878700,2.142400,0.947300,1.0,0.0,0.0,0.0\n");
  const std::vector<StampedPose> poses = ReadEurocPoses(path);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].t_ns, 1520530308199447626LL);
  // 90 deg about z, w first.
  EXPECT_LT((poses[0].world_from_body * Eigen::Vector3d(1, 0, 0) -
             Eigen::Vector3d(0.878612, 3.142470, 0.947262))
                .norm(),
            1e-6);
  const std::string short_row = dir.Write("b.csv", "1,0,0,0,1,0,0\n");
  ExpectInputError([&] { ReadEurocPoses(short_row); }, short_row, 1, "");
  const std::string unsorted = dir.Write("c.csv", "5,0,0,0,1,0,0,0\n5,0,0,0,1,0,0,0\n");
  ExpectInputError([&] { ReadEurocPoses(unsorted); }, unsorted, 2, "");
  const std::string nan = dir.Write("d.csv", "5,0,nan,0,1,0,0,0\n");
  ExpectInputError([&] { ReadEurocPoses(nan); }, nan, 1, "");
}

// Velocities from poses against an analytic trajectory: p(t) = (0.5 t + 0.3 t^2, sin 2t, 0),
// sampled at 120 Hz for 1 s with a gap from 0.4 to 0.6 s, through a marker 10 cm above the body.
TEST(Euroc, GroundTruthFromPosesDifferentiatesTheBodysPositions) {
  const Rigid3d body_from_marker(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())),
      Eigen::Vector3d(0.0, 0.0, 0.1));
  auto position = [](double t) {
    return Eigen::Vector3d(0.5 * t + 0.3 * t * t, std::sin(2.0 * t), 0.0);
  };
  auto velocity = [](double t) {
    return Eigen::Vector3d(0.5 + 0.6 * t, 2.0 * std::cos(2.0 * t), 0.0);
  };
  std::vector<StampedPose> marker;
  const int64_t t0 = 1'520'530'308'000'000'000;
  for (int k = 0; k <= 120; ++k) {
    const double t = k / 120.0;
    if (t > 0.4 && t < 0.6) continue;
    const Rigid3d world_from_body(
        Eigen::Quaterniond(Eigen::AngleAxisd(t, Eigen::Vector3d::UnitZ())), position(t));
    marker.push_back(
        {t0 + static_cast<int64_t>(std::llround(t * 1e9)), world_from_body * body_from_marker});
  }
  const std::vector<EurocGroundTruthState> states = GroundTruthFromPoses(marker, body_from_marker);
  ASSERT_EQ(states.size(), marker.size());
  int with_velocity = 0;
  for (const EurocGroundTruthState& s : states) {
    const double t = 1e-9 * static_cast<double>(s.t_ns - t0);
    EXPECT_LT((s.world_from_body.translation - position(t)).norm(), 1e-9) << t;
    // The window must reach both sides: not at the ends, nor at the gap's edges.
    const bool both_sides =
        t > 1e-6 && t < 1.0 - 1e-6 && std::abs(t - 0.4) > 1e-6 && std::abs(t - 0.6) > 1e-6;
    EXPECT_EQ(s.velocity_in_world.allFinite(), both_sides) << t;
    if (!both_sides) continue;
    ++with_velocity;
    // A straight line over +-50 ms: exact for the quadratic where the window is symmetric, the
    // sine's curvature leaves a few mm/s; one-sided windows next to the gap and the ends lean
    // by half the window times the acceleration (about 0.1 m/s at most here).
    const double tolerance = (t < 0.05 || t > 0.95 || std::abs(t - 0.5) < 0.15) ? 0.15 : 0.01;
    EXPECT_LT((s.velocity_in_world - velocity(t)).norm(), tolerance) << t;
  }
  EXPECT_GT(with_velocity, 90);
}

// The EuRoC flight's own ground truth read back as poses only (a mocap0 folder of its poses at
// 200 Hz beside its camera and IMU): the same frame poses, and velocities within 2 cm/s of the
// estimator's own.
TEST(Euroc, AMocapFolderGivesTheFlightsPosesAndVelocities) {
  const std::string real = DataPath("euroc_mh05_flight/mav0");
  const std::vector<EurocGroundTruthState> truth =
      ReadEurocGroundTruth(real + "/state_groundtruth_estimate0/data.csv");
  TempDir dir;
  std::string csv = "#timestamp [ns], p x, p y, p z, q w, q x, q y, q z\n";
  for (const EurocGroundTruthState& s : truth) {
    const Rigid3d& p = s.world_from_body;
    std::ostringstream row;
    row.precision(17);
    row << s.t_ns << "," << p.translation.x() << "," << p.translation.y() << ","
        << p.translation.z() << "," << p.rotation.w() << "," << p.rotation.x() << ","
        << p.rotation.y() << "," << p.rotation.z() << "\n";
    csv += row.str();
  }
  dir.Write("mav0/mocap0/data.csv", csv);
  for (const char* sensor : {"cam0", "imu0"}) {
    std::filesystem::create_directory_symlink(real + "/" + sensor, dir.Path("mav0/") + sensor);
  }
  const EurocSequence seq = ReadEurocSequence(dir.path());
  EXPECT_EQ(seq.groundtruth_source, "mocap0");
  ASSERT_EQ(seq.groundtruth.size(), truth.size());
  std::vector<double> errors;
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_LT(
        (seq.groundtruth[i].world_from_body.translation - truth[i].world_from_body.translation)
            .norm(),
        1e-9);
    if (!seq.groundtruth[i].velocity_in_world.allFinite()) continue;
    errors.push_back((seq.groundtruth[i].velocity_in_world - truth[i].velocity_in_world).norm());
  }
  EXPECT_EQ(errors.size(), truth.size() - 2);  // all but the two ends
  // The estimate's positions jump by 8-10 mm three times (rows 850, 1030 and 1230, a second
  // apart: where its batch segments meet), which no velocity from positions can follow for
  // +-50 ms (about 60 samples, 1 %); elsewhere they agree to millimetres per second.
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.005);
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.01);
  EXPECT_LT(errors[errors.size() * 99 / 100], 0.03);
  EXPECT_LT(errors.back(), 0.2);
  std::printf("velocity from poses vs the estimator's: median %.4f, 99 %% %.4f, max %.4f m/s\n",
              errors[errors.size() / 2], errors[errors.size() * 99 / 100], errors.back());
}

}  // namespace
}  // namespace imumatch
