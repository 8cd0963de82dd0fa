#include "imumatch/sim/trajectory.h"

#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "imumatch/core/so3.h"

namespace imumatch {
namespace {

// Checks the analytic derivatives of a trajectory against central finite differences of its pose.
void ExpectConsistentDerivatives(const Trajectory& traj) {
  const double h = 1e-4;
  for (double t = traj.StartTime() + 0.1; t < traj.EndTime() - 0.1; t += 0.37) {
    const Rigid3d minus = traj.WorldFromBody(t - h), mid = traj.WorldFromBody(t),
                  plus = traj.WorldFromBody(t + h);
    const Eigen::Vector3d v_fd = (plus.translation - minus.translation) / (2 * h);
    const Eigen::Vector3d a_fd =
        (plus.translation - 2 * mid.translation + minus.translation) / (h * h);
    const Eigen::Vector3d w_fd = (LogSO3(mid.rotation.conjugate() * plus.rotation) -
                                  LogSO3(mid.rotation.conjugate() * minus.rotation)) /
                                 (2 * h);
    EXPECT_LT((traj.VelocityInWorld(t) - v_fd).norm(), 1e-6) << "t=" << t;
    EXPECT_LT((traj.AccelerationInWorld(t) - a_fd).norm(), 1e-4) << "t=" << t;
    EXPECT_LT((traj.AngularVelocityInBody(t) - w_fd).norm(), 1e-6) << "t=" << t;
  }
}

TEST(Trajectory, ConstantRateDerivatives) {
  ConstantRateTrajectory traj(Rigid3d(FromEulerZYX(0.1, -0.2, 0.3), Eigen::Vector3d(1, 2, 3)),
                              Eigen::Vector3d(0.3, -0.5, 1.2), Eigen::Vector3d(0.5, 0, -0.1), 3.0);
  ExpectConsistentDerivatives(traj);
}

TEST(Trajectory, CircleDerivativesAndGeometry) {
  CircleTrajectory traj(2.0, 0.8, 1.5, 5.0);
  ExpectConsistentDerivatives(traj);
  // Hand-computed: at t = pi/(2*0.8) the body is at (0, 2, 1.5) heading along -x.
  const double t = M_PI / 1.6;
  const Rigid3d pose = traj.WorldFromBody(t);
  EXPECT_LT((pose.translation - Eigen::Vector3d(0, 2, 1.5)).norm(), 1e-12);
  EXPECT_LT((pose.rotation * Eigen::Vector3d::UnitX() - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-12);
  EXPECT_NEAR(traj.AccelerationInWorld(t).norm(), 2.0 * 0.8 * 0.8, 1e-12);
}

TEST(Trajectory, SinusoidDerivatives) {
  SinusoidTrajectory::Params p;
  p.angle_amplitude_rad = Eigen::Vector3d(0.3, 0.4, 0.5);  // large enough to couple the axes
  SinusoidTrajectory traj(p);
  ExpectConsistentDerivatives(traj);
}

}  // namespace
}  // namespace imumatch
