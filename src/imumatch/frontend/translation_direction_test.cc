#include "imumatch/frontend/translation_direction.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

constexpr double kF = 500.0;  // focal length (px)

// Exact correspondences of points 1-10 m in front of A, seen after rotation R and translation t:
// ra = R x_a and x_b, bearings at z = 1.
struct Bearings {
  std::vector<Eigen::Vector3d> ra, xb;
};
Bearings MakeBearings(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::uniform_real_distribution<double> depth(1.0, 10.0);
  Bearings b;
  while (static_cast<int>(b.ra.size()) < n) {
    const Eigen::Vector3d xa(u(rng), u(rng), 1.0);
    const Eigen::Vector3d q = r * (depth(rng) * xa) + t;
    if (q.z() <= 0.1) continue;
    b.ra.push_back(r * xa);
    b.xb.push_back(q / q.z());
  }
  return b;
}

double AngleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::min(1.0, std::fabs(a.normalized().dot(b.normalized()))));
}

TEST(TranslationDirectionTest, EpipolarDistanceOfOneCorrespondenceByHand) {
  // Translation along x: epipolar lines are horizontal, the distance is the y offset (in px).
  const std::vector<Eigen::Vector3d> ra = {Eigen::Vector3d(0.1, 0.2, 1.0)};
  const std::vector<Eigen::Vector3d> xb = {Eigen::Vector3d(0.3, 0.2 + 2.0 / kF, 1.0)};
  std::vector<double> scratch;
  EXPECT_NEAR(MedianEpipolarDistancePx(ra, xb, Eigen::Vector3d(0.05, 0, 0), kF, scratch), 2.0,
              1e-9);
  // Along y the lines are vertical: the offset is the x one, 0.2 of a unit = 100 px.
  EXPECT_NEAR(MedianEpipolarDistancePx(ra, xb, Eigen::Vector3d(0, 0.05, 0), kF, scratch), 100.0,
              1e-6);
}

TEST(TranslationDirectionTest, ExactCorrespondencesGiveTheTruthAndItsCostIsTheLeast) {
  const Eigen::Matrix3d r = ExpSO3(Eigen::Vector3d(0.01, -0.02, 0.005)).toRotationMatrix();
  const Eigen::Vector3d t(0.02, 0.05, -0.03);
  const Bearings b = MakeBearings(r, t, 150, 5);
  std::vector<double> scratch;
  EXPECT_LT(MedianEpipolarDistancePx(b.ra, b.xb, t, kF, scratch), 1e-9);
  // A prior 50 degrees off in direction, same length.
  const Eigen::Vector3d side = t.cross(Eigen::Vector3d::UnitX()).normalized() * t.norm();
  const Eigen::Vector3d prior = (t + 1.2 * side).normalized() * t.norm();
  ASSERT_GT(AngleBetween(prior, t), 0.8);
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity() / (0.03 * 0.03);
  EXPECT_LT(TranslationDirectionCost(b.ra, b.xb, t, kF, 0.5, 2.3849, prior, info),
            TranslationDirectionCost(b.ra, b.xb, prior, kF, 0.5, 2.3849, prior, info));
  const TranslationSearchResult search =
      SearchTranslationDirection(b.ra, b.xb, prior, prior, info, kF, 0.5, 2.3849, 48, scratch);
  const Eigen::Vector3d found = search.translation;
  EXPECT_NEAR(found.norm(), prior.norm(), 1e-12);  // the length stays the prior's
  EXPECT_LT(AngleBetween(found, t), 0.01);
  EXPECT_DOUBLE_EQ(search.cost,
                   TranslationDirectionCost(b.ra, b.xb, found, kF, 0.5, 2.3849, prior, info));
  // The linear solution from the prior, for comparison, also finds it on exact data.
  EXPECT_LT(
      AngleBetween(EpipolarTranslationDirection(b.ra, b.xb, prior, kF, 0.5, 2.3849, scratch), t),
      0.01);
}

TEST(TranslationDirectionTest, BadArguments) {
  const std::vector<Eigen::Vector3d> ra(3, Eigen::Vector3d(0, 0, 1)),
      xb(2, Eigen::Vector3d::UnitZ());
  std::vector<double> scratch;
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  EXPECT_THROW(
      SearchTranslationDirection(ra, xb, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitX(), info,
                                 kF, 0.5, 2.3849, 8, scratch),
      InvalidArgument);
  EXPECT_THROW(SearchTranslationDirection(ra, ra, Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero(),
                                          info, kF, 0.5, 2.3849, 8, scratch),
               InvalidArgument);
}

}  // namespace
}  // namespace imumatch
