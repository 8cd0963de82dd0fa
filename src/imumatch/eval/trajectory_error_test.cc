#include "imumatch/eval/trajectory_error.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

TEST(RelativePoseError, HandComputedErrorsAndFrameIndependence) {
  // Truth: 1 m steps along x. Estimate: the same motion seen from another world frame, with the
  // second step 10 cm too long and turned by 2 deg about z.
  std::vector<std::optional<Rigid3d>> truth, est;
  for (int i = 0; i < 3; ++i)
    truth.push_back(Rigid3d(Eigen::Quaterniond::Identity(), {1.0 * i, 0, 0}));
  const Rigid3d world(ExpSO3(Eigen::Vector3d(0.3, -0.2, 1.0)), Eigen::Vector3d(5, 6, 7));
  est.push_back(world * *truth[0]);
  est.push_back(world * *truth[1]);
  est.push_back(world * Rigid3d(ExpSO3(Eigen::Vector3d(0, 0, 2.0 * M_PI / 180.0)),
                                Eigen::Vector3d(2.1, 0, 0)));
  const RelativePoseError e = ComputeRelativePoseError(est, truth);
  ASSERT_EQ(e.pairs(), 2u);
  EXPECT_NEAR(e.translation_m[0], 0.0, 1e-12);
  EXPECT_NEAR(e.rotation_deg[0], 0.0, 1e-9);
  EXPECT_NEAR(e.translation_m[1], 0.1, 1e-12);
  EXPECT_NEAR(e.rotation_deg[1], 2.0, 1e-9);
  EXPECT_NEAR(e.rmse_translation_m, std::sqrt(0.01 / 2.0), 1e-12);
  EXPECT_NEAR(e.mean_rotation_deg, 1.0, 1e-9);
  // A missing pose leaves its pairs out; sizes must agree.
  est[1].reset();
  EXPECT_EQ(ComputeRelativePoseError(est, truth).pairs(), 0u);
  EXPECT_EQ(ComputeRelativePoseError(est, truth, 2).pairs(), 1u);
  EXPECT_THROW(ComputeRelativePoseError(est, {}), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
