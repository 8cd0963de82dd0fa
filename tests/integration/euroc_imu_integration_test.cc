// The real EuRoC V1_01 IMU log: the MAV sits on the ground for its first ~4.5 s with the rotors
// vibrating (gyro std up to 0.1 rad/s, accelerometer std ~1 m/s^2, stable means).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/io/euroc.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

TEST(EurocImu, StillStartIntegratesToNoRotationOnceBiasIsRemoved) {
  const ImuBuffer buffer = ReadEurocImu(testing::DataPath("euroc_v101_excerpt/mav0/imu0/data.csv"));
  ASSERT_EQ(buffer.size(), 29120u);
  const int64_t t0 = buffer.begin_ns();
  const ImuParams params = ImuParams::EurocAdis16448();

  // Bias from [1 s, 4 s]; integrate over the first second, where the 20 camera frames are:
  // a disjoint interval, so the check is not circular.
  const StillInitialization init =
      InitializeFromStill(buffer, t0 + kSecond, t0 + 4 * kSecond, params);
  EXPECT_NEAR(init.bias.gyro.z(), 0.078, 0.005);  // the ADIS16448's z bias on this sequence
  EXPECT_NEAR(init.gravity_in_imu.norm(), 9.81, 1e-9);
  // The IMU's x axis points up on this MAV: specific force ~ +9.1 m/s^2 on x.
  EXPECT_GT(-init.gravity_in_imu.normalized().x(), 0.9);

  const auto samples = buffer.Slice(t0, t0 + kSecond);
  const double with_bias = RotationAngle(Preintegrate(samples, init.bias, params).delta_rotation);
  const double raw = RotationAngle(Preintegrate(samples, ImuBias(), params).delta_rotation);
  std::printf("rotation over the still first second: %.5f rad raw, %.5f rad bias removed\n", raw,
              with_bias);
  EXPECT_GT(raw, 0.05);  // ~0.08 rad/s of bias over 1 s
  EXPECT_LT(with_bias, 0.01);
}

TEST(EurocImu, TakeOffIsNotStill) {
  const ImuBuffer buffer = ReadEurocImu(testing::DataPath("euroc_v101_excerpt/mav0/imu0/data.csv"));
  const int64_t t0 = buffer.begin_ns();
  EXPECT_THROW(
      InitializeFromStill(buffer, t0 + 6 * kSecond, t0 + 10 * kSecond, ImuParams::EurocAdis16448()),
      InvalidArgument);
}

}  // namespace
}  // namespace imumatch
