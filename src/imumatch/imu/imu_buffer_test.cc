#include "imumatch/imu/imu_buffer.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

ImuSample Sample(int64_t t_ns, double g) {
  ImuSample s;
  s.t_ns = t_ns;
  s.gyro_rad_s = Eigen::Vector3d(g, 2 * g, 3 * g);
  s.accel_m_s2 = Eigen::Vector3d(0, 0, 9.81 + g);
  return s;
}

TEST(ImuBuffer, InterpolatesAndSlices) {
  ImuBuffer buffer;
  for (int k = 0; k <= 10; ++k) buffer.Push(Sample(k * 5'000'000, k * 0.1));
  const ImuSample mid = buffer.Interpolate(12'500'000);  // halfway between k=2 and k=3
  EXPECT_NEAR(mid.gyro_rad_s.x(), 0.25, 1e-12);
  EXPECT_NEAR(mid.accel_m_s2.z(), 9.81 + 0.25, 1e-12);
  const auto slice = buffer.Slice(7'000'000, 21'000'000);
  ASSERT_EQ(slice.size(), 5u);  // 7 (interpolated), 10, 15, 20, 21 (interpolated)
  EXPECT_EQ(slice.front().t_ns, 7'000'000);
  EXPECT_EQ(slice[1].t_ns, 10'000'000);
  EXPECT_EQ(slice.back().t_ns, 21'000'000);
  EXPECT_NEAR(slice.back().gyro_rad_s.x(), 0.42, 1e-12);
  // A slice that starts exactly on a sample does not repeat it.
  EXPECT_EQ(buffer.Slice(10'000'000, 20'000'000).size(), 3u);
}

TEST(ImuBuffer, RejectsBadSamplesWithSourceAndLine) {
  ImuBuffer buffer;
  buffer.Push(Sample(100, 0), "imu.csv", 2);
  try {
    buffer.Push(Sample(100, 0), "imu.csv", 3);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("duplicate"), std::string::npos) << e.what();
  }
  try {
    buffer.Push(Sample(50, 0), "imu.csv", 4);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("imu.csv:4: out-of-order"), std::string::npos) << e.what();
  }
  ImuSample nan = Sample(200, 0);
  nan.accel_m_s2.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(buffer.Push(nan, "imu.csv", 5), InputError);
  EXPECT_EQ(buffer.size(), 1u);
}

TEST(ImuBuffer, QueriesOutsideRangeOrOverGapsFail) {
  ImuBufferOptions opt;
  opt.max_gap_ns = 20'000'000;
  ImuBuffer buffer(opt);
  EXPECT_THROW(buffer.Interpolate(0), OutOfRange);
  for (int64_t t : {0, 5, 10, 50, 55}) buffer.Push(Sample(t * 1'000'000, 0));
  EXPECT_THROW(buffer.Interpolate(-1), OutOfRange);
  EXPECT_THROW(buffer.Interpolate(56'000'000), OutOfRange);
  EXPECT_THROW(buffer.Interpolate(30'000'000), OutOfRange);  // inside the 40 ms gap
  EXPECT_THROW(buffer.Slice(2'000'000, 52'000'000), OutOfRange);
  EXPECT_THROW(buffer.Slice(5'000'000, 5'000'000), OutOfRange);
  EXPECT_NO_THROW(buffer.Slice(0, 10'000'000));
  EXPECT_NO_THROW(buffer.Slice(50'000'000, 55'000'000));
}

TEST(ImuBuffer, GapsAreListedWithTheirLineAndEndTheGapFreeStretch) {
  ImuBufferOptions opt;
  opt.max_gap_ns = 20'000'000;
  ImuBuffer buffer(opt);
  // Lines 2.. of imu.csv; a 40 ms gap before line 6 and a 25 ms one before line 8.
  const int64_t times_ms[] = {0, 5, 10, 50, 55, 80, 85};
  const int lines[] = {2, 3, 4, 6, 7, 8, 9};
  for (int k = 0; k < 7; ++k) buffer.Push(Sample(times_ms[k] * 1'000'000, 0), "imu.csv", lines[k]);
  const std::vector<ImuBuffer::Gap> gaps = buffer.Gaps();
  ASSERT_EQ(gaps.size(), 2u);
  EXPECT_EQ(gaps[0].begin_ns, 10'000'000);
  EXPECT_EQ(gaps[0].end_ns, 50'000'000);
  EXPECT_EQ(gaps[0].line, 6);
  EXPECT_EQ(gaps[1].begin_ns, 55'000'000);
  EXPECT_EQ(gaps[1].line, 8);
  // The stretch from t0 ends where the first gap after it starts, or at t1 before it.
  EXPECT_EQ(buffer.GapFreeEnd(0, 100'000'000), 10'000'000);
  EXPECT_EQ(buffer.GapFreeEnd(2'000'000, 7'000'000), 7'000'000);
  EXPECT_EQ(buffer.GapFreeEnd(50'000'000, 100'000'000), 55'000'000);
  EXPECT_EQ(buffer.GapFreeEnd(80'000'000, 100'000'000), 85'000'000);
  EXPECT_EQ(buffer.GapFreeEnd(10'000'000, 100'000'000), 10'000'000);
  EXPECT_THROW(buffer.GapFreeEnd(30'000'000, 100'000'000), OutOfRange);  // inside a gap
  // A slice over a gap names the file and the line after the gap.
  try {
    buffer.Slice(0, 52'000'000);
    ADD_FAILURE() << "no throw";
  } catch (const OutOfRange& e) {
    EXPECT_NE(
        std::string(e.what()).find("imu.csv:6: IMU gap [0.010000000, 0.050000000] s (40.0 ms"),
        std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace imumatch
