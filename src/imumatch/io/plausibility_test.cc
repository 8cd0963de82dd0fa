// Values outside the stated plausibility bounds are bad data: every reader throws InputError naming
// the file and line, before any work or allocation that the value would drive.
#include "imumatch/io/plausibility.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/euroc.h"
#include "imumatch/io/image_io.h"
#include "imumatch/io/imu_io.h"
#include "imumatch/io/io_test_util.h"
#include "imumatch/io/trajectory_io.h"

namespace imumatch {
namespace {

using testing::ExpectInputError;
using testing::TempDir;

TEST(PlausibilityTest, TrajectoryTimestampJumpIsAnErrorOnItsLine) {
  TempDir dir;
  // A line appended far ahead (1e6 s): the IMU simulated over that span would need 2e8 samples.
  const std::string path =
      dir.Write("groundtruth.txt", "1.0 0 0 0 0 0 0 1\n1.1 0 0 0 0 0 0 1\n1000000 0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(path); }, path, 3, "jumps");
  // One hour is the largest step accepted.
  const std::string ok = dir.Write("ok.txt", "1.0 0 0 0 0 0 0 1\n3601.0 0 0 0 0 0 0 1\n");
  EXPECT_EQ(ReadTumTrajectory(ok).size(), 2u);
}

TEST(PlausibilityTest, TimestampsNearTheInt64LimitAreRejected) {
  TempDir dir;
  const std::string tum = dir.Write("traj.txt", "9.2e9 0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(tum); }, tum, 1, "not plausible");
  const std::string neg = dir.Write("neg.txt", "-9.2e9 0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(neg); }, neg, 1, "not plausible");
  const std::string imu = dir.Write("mav0/imu0/data.csv",
                                    "#timestamp,wx,wy,wz,ax,ay,az\n"
                                    "9200000000000000000,0,0,0,0,0,9.8\n");
  ExpectInputError([&] { ReadEurocImu(imu); }, imu, 2, "not plausible");
}

TEST(PlausibilityTest, AbsurdImuAndGroundTruthValuesNameFileAndLine) {
  TempDir dir;
  const std::string imu = dir.Write("imu.txt", "0.000 0 0 0 0 0 9.81\n0.005 1e300 0 0 0 0 9.81\n");
  ExpectInputError([&] { ReadImuText(imu); }, imu, 2, "gyro");
  const std::string accel = dir.Write("imu2.txt", "0.000 0 0 0 0 0 2000\n");
  ExpectInputError([&] { ReadImuText(accel); }, accel, 1, "accel");
  const std::string euroc = dir.Write("data.csv",
                                      "#timestamp,wx,wy,wz,ax,ay,az\n"
                                      "1000000000,0,0,0,0,0,9.8\n"
                                      "1005000000,0,0,0,1e300,0,9.8\n");
  ExpectInputError([&] { ReadEurocImu(euroc); }, euroc, 3, "accel");
  const std::string tum = dir.Write("gt.txt", "1.0 1e300 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(tum); }, tum, 1, "position");
  const std::string gt = dir.Write("state.csv",
                                   "#t,px,py,pz,qw,qx,qy,qz,vx,vy,vz,bwx,bwy,bwz,bax,bay,baz\n"
                                   "1000000000,0,0,0,1,0,0,0,1e300,0,0,0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadEurocGroundTruth(gt); }, gt, 2, "velocity");
  // Plausible values pass.
  const std::string fine = dir.Write("imu3.txt", "0.000 17 0 0 0 0 150\n");
  EXPECT_EQ(ReadImuText(fine).size(), 1u);
}

TEST(PlausibilityTest, JsonNumberOverflowNamesTheFile) {
  TempDir dir;
  const std::string json = dir.Write("seq/sequence.json",
                                     "{\"generator\": \"imumatch synth\", \"camera\": "
                                     "{\"width\": 1e400}}\n");
  ExpectInputError([&] { LoadDataset(dir.Path("seq")); }, json, 0, "JSON");
  // A huge width that parses: bounded before the cast to int.
  dir.Write("seq/sequence.json",
            "{\"generator\": \"imumatch synth\", \"camera\": {\"width\": 9.2e18, \"height\": 480, "
            "\"fx\": 500, \"fy\": 500, \"cx\": 320, \"cy\": 240, \"distortion\": [0,0,0,0,0], "
            "\"depth_scale\": 5000}}\n");
  ExpectInputError([&] { LoadDataset(dir.Path("seq")); }, json, 0, "width");
}

TEST(PlausibilityTest, CameraTextWithAHugeSizeIsAnError) {
  ExpectInputError([] { ParseCameraFromText("525 525 319.5 239.5 9.2e18 480\n", "cam.txt"); },
                   "cam.txt", 1, "width and height");
  ExpectInputError([] { ParseCameraFromText("525 525 319.5 239.5 640 -480\n", "cam.txt"); },
                   "cam.txt", 1, "width and height");
  EXPECT_EQ(ParseCameraFromText("525 525 319.5 239.5 32768 480\n", "cam.txt").width, 32768);
}

TEST(PlausibilityTest, AByteOrderMarkIsSkipped) {
  TempDir dir;
  const std::string path = dir.Write("traj.txt",
                                     "\xEF\xBB\xBF"
                                     "1.5 1 2 3 0 0 0 1\n");
  const auto poses = ReadTumTrajectory(path);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].t_ns, 1'500'000'000);
  EXPECT_EQ(ParseCameraFromText("\xEF\xBB\xBF"
                                "525 525 319.5 239.5\n",
                                "cam.txt")
                .fx,
            525.0);
  // CRLF line ends keep working.
  const std::string crlf = dir.Write("crlf.txt", "1.5 1 2 3 0 0 0 1\r\n2.5 1 2 3 0 0 0 1\r\n");
  EXPECT_EQ(ReadTumTrajectory(crlf).size(), 2u);
}

std::string PngHeader(uint32_t width, uint32_t height) {
  std::string png("\x89PNG\r\n\x1a\n", 8);
  png += std::string("\0\0\0\x0dIHDR", 8);
  for (uint32_t v : {width, height}) {
    for (int shift = 24; shift >= 0; shift -= 8) png += static_cast<char>((v >> shift) & 0xFF);
  }
  png += std::string("\x10\x02\0\0\0", 5);  // 16-bit RGB
  png += std::string("\0\0\0\0", 4);        // CRC (not checked before the size)
  png += std::string("\0\0\0\x16IDAT", 8) + std::string(22, '\0') + std::string(4, '\0');
  return png;
}

TEST(PlausibilityTest, AnImageHeaderClaimingAHugeSizeIsRejectedBeforeDecoding) {
  TempDir dir;
  const std::string path = dir.Write("huge.png", PngHeader(32000, 32000));
  ExpectInputError([&] { LoadImage(path); }, path, 0, "32000x32000");
  ExpectInputError([&] { LoadDepth(path); }, path, 0, "not plausible");
  // The same for BMP and PNM headers (found by fuzzing LoadImage); other formats are refused.
  std::string bmp = "BM" + std::string(16, '\0');
  for (int32_t v : {30000, 30000}) {
    for (int shift = 0; shift < 32; shift += 8) bmp += static_cast<char>((v >> shift) & 0xFF);
  }
  bmp += std::string(28, '\0');
  const std::string bmp_path = dir.Write("huge.bmp", bmp);
  ExpectInputError([&] { LoadImage(bmp_path); }, bmp_path, 0, "30000x30000");
  const std::string ppm = dir.Write("huge.ppm", "P6\n30000 30000\n65535\n0123456789");
  ExpectInputError([&] { LoadImage(ppm); }, ppm, 0, "30000x30000");
  const std::string tiff = dir.Write("image.tif", "II*\0 some tiff bytes");
  ExpectInputError([&] { LoadImage(tiff); }, tiff, 0, "not a PNG, JPEG, BMP or PNM");
  // Plausible small BMP and PGM files decode.
  cv::Mat small(6, 8, CV_8UC1, cv::Scalar(42));
  WriteImage(dir.Path("small.bmp"), small);
  WriteImage(dir.Path("small.pgm"), small);
  EXPECT_EQ(LoadImage(dir.Path("small.bmp")).at<uint8_t>(2, 3), 42);
  EXPECT_EQ(LoadImage(dir.Path("small.pgm")).at<uint8_t>(2, 3), 42);
}

TEST(PlausibilityTest, BoundsAreStatedOnce) {
  EXPECT_EQ(plausibility::kMaxImageSide, PinholeCamera::kMaxSide);
  // Any two plausible timestamps differ by less than int64's range.
  EXPECT_LT(plausibility::kMaxAbsTimestampNs, std::numeric_limits<int64_t>::max() / 2);
}

}  // namespace
}  // namespace imumatch
