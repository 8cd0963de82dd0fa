#include "imumatch/core/statistics.h"

#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

TEST(StatisticsTest, MediansOfHandCountedSamples) {
  std::vector<double> odd = {5.0, -1.0, 3.0, 9.0, 2.0};  // sorted: -1 2 3 5 9
  EXPECT_EQ(Median(odd), 3.0);
  EXPECT_EQ(odd[0], 5.0);                            // Median works on a copy
  std::vector<double> even = {4.0, 1.0, 10.0, 2.0};  // sorted: 1 2 4 10
  EXPECT_EQ(Median(even), 3.0);
  EXPECT_EQ(UpperMedianInPlace(even), 4.0);
  std::vector<int> one = {7};
  EXPECT_EQ(UpperMedianInPlace(one), 7);
  std::vector<float> ties = {2.0f, 2.0f, 1.0f, 2.0f};
  EXPECT_EQ(UpperMedianInPlace(ties), 2.0f);
}

TEST(StatisticsTest, AgreesWithSortingOnRandomSamples) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int n = 1; n <= 40; ++n) {
    std::vector<double> v(static_cast<size_t>(n));
    for (double& x : v) x = u(rng);
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    const size_t h = sorted.size() / 2;
    const double expected = n % 2 == 1 ? sorted[h] : 0.5 * (sorted[h - 1] + sorted[h]);
    EXPECT_DOUBLE_EQ(Median(v), expected) << "n = " << n;
    EXPECT_EQ(UpperMedianInPlace(v), sorted[h]) << "n = " << n;
  }
}

TEST(StatisticsTest, AnEmptySampleIsAnError) {
  std::vector<double> empty;
  EXPECT_THROW(UpperMedianInPlace(empty), InvalidArgument);
  EXPECT_THROW(Median(empty), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
