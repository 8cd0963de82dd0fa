#include "imumatch/io/imu_io.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/io/io_test_util.h"

namespace imumatch {
namespace {

using testing::ExpectInputError;
using testing::TempDir;

TEST(ImuIo, WriteReadRoundTripIsBitExact) {
  TempDir dir;
  std::vector<ImuSample> samples;
  for (int i = 0; i < 50; ++i) {
    ImuSample s;
    s.t_ns = 1403715273262142976LL + i * 5000000LL + (i % 3);
    s.gyro_rad_s = Eigen::Vector3d(std::sin(0.1 * i), 1.0 / (i + 3.0), -1e-7 * i);
    s.accel_m_s2 = Eigen::Vector3d(9.81 + std::cos(0.37 * i), -0.1 / 3.0, M_PI * i);
    samples.push_back(s);
  }
  const std::string path = dir.Path("imu.txt");
  WriteImuText(path, samples, "synthetic test");
  const ImuBuffer buffer = ReadImuText(path);
  ASSERT_EQ(buffer.size(), samples.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(buffer.samples()[i].t_ns, samples[i].t_ns);
    EXPECT_EQ(buffer.samples()[i].gyro_rad_s, samples[i].gyro_rad_s);
    EXPECT_EQ(buffer.samples()[i].accel_m_s2, samples[i].accel_m_s2);
  }
}

TEST(ImuIo, ParsesHandWrittenLines) {
  TempDir dir;
  const std::string path = dir.Write(
      "imu.txt", "# t gx gy gz ax ay az\n0.005 0.1 0.2 0.3 0 0 9.81\n0.010 0 0 0 1 2 3\n");
  const ImuBuffer b = ReadImuText(path);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b.samples()[0].t_ns, 5000000);
  EXPECT_DOUBLE_EQ(b.samples()[0].gyro_rad_s.z(), 0.3);
  EXPECT_DOUBLE_EQ(b.samples()[0].accel_m_s2.z(), 9.81);
  EXPECT_DOUBLE_EQ(b.samples()[1].accel_m_s2.y(), 2.0);
}

TEST(ImuIo, MissingAndEmptyFile) {
  TempDir dir;
  const std::string missing = dir.Path("imu.txt");
  ExpectInputError([&] { ReadImuText(missing); }, missing, 0, "not found");
  const std::string empty = dir.Write("empty.txt", "# only a comment\n");
  ExpectInputError([&] { ReadImuText(empty); }, empty, 0, "no IMU samples");
}

TEST(ImuIo, WrongFieldCount) {
  TempDir dir;
  const std::string path = dir.Write("imu.txt", "0.005 0 0 0 0 0 9.81\n0.010 0 0 0 0 9.81\n");
  ExpectInputError([&] { ReadImuText(path); }, path, 2, "expected 7 fields");
}

TEST(ImuIo, NonNumericAndNaN) {
  TempDir dir;
  const std::string text = dir.Write("a.txt", "0.005 0 0 0 0 0 9.81\n0.010 0 zero 0 0 0 9.81\n");
  ExpectInputError([&] { ReadImuText(text); }, text, 2, "gy: 'zero' is not a number");
  const std::string nan = dir.Write("b.txt", "0.005 0 0 0 0 0 9.81\n\n0.010 0 0 0 0 nan 9.81\n");
  ExpectInputError([&] { ReadImuText(nan); }, nan, 3, "ay");
}

TEST(ImuIo, UnsortedAndDuplicateTimestamps) {
  TempDir dir;
  const std::string unsorted =
      dir.Write("a.txt", "0.005 0 0 0 0 0 9.81\n0.015 0 0 0 0 0 9.81\n0.010 0 0 0 0 0 9.81\n");
  ExpectInputError([&] { ReadImuText(unsorted); }, unsorted, 3, "out-of-order");
  const std::string dup = dir.Write("b.txt", "0.005 0 0 0 0 0 9.81\n0.0050 0 0 0 0 0 9.81\n");
  ExpectInputError([&] { ReadImuText(dup); }, dup, 2, "duplicate");
}

TEST(ImuIo, GapMakesQueriesOverItFail) {
  TempDir dir;
  std::string text;
  // 200 Hz for 0.1 s, then nothing for 0.2 s, then 200 Hz again.
  for (int i = 0; i <= 20; ++i) text += std::to_string(0.005 * i) + " 0 0 0 0 0 9.81\n";
  for (int i = 0; i <= 20; ++i) text += std::to_string(0.3 + 0.005 * i) + " 0 0 0 0 0 9.81\n";
  const ImuBuffer buffer = ReadImuText(dir.Write("imu.txt", text));
  ASSERT_EQ(buffer.size(), 42u);
  EXPECT_NO_THROW(buffer.Slice(10'000'000, 90'000'000));
  EXPECT_NO_THROW(buffer.Slice(310'000'000, 390'000'000));
  EXPECT_THROW(buffer.Slice(50'000'000, 350'000'000), OutOfRange);
  EXPECT_THROW(buffer.Interpolate(200'000'000), OutOfRange);
}

}  // namespace
}  // namespace imumatch
