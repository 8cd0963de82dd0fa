// Uses the installed library: integrates a simulated still IMU and projects a point.
#include <cstdio>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/sim/imu_simulator.h"
#include "imumatch/sim/trajectory.h"

int main() {
  using namespace imumatch;
  ConstantRateTrajectory spin(Rigid3d(), Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d::Zero(), 1.0);
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  ImuBuffer buffer;
  for (const ImuSample& s : SimulateImu(spin, ImuParams::Ideal(), opt)) buffer.Push(s);
  const ImuPreintegration pim =
      Preintegrate(buffer.Slice(0, 500'000'000), ImuBias(), ImuParams::Ideal());
  const double angle = RotationAngle(pim.delta_rotation);  // 0.25 rad
  const auto uv = PinholeCamera::KinectDefault().Project(Eigen::Vector3d(0, 0, 2));
  std::printf("rotation %.6f rad, principal point %.1f %.1f\n", angle, uv->x(), uv->y());
  return (std::abs(angle - 0.25) < 1e-9 && std::abs(uv->x() - 319.5) < 1e-12) ? 0 : 1;
}
