#include "imumatch/sim/trajectory.h"

#include <cmath>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {

ConstantRateTrajectory::ConstantRateTrajectory(const Rigid3d& world_from_body_0,
                                               const Eigen::Vector3d& omega_in_body,
                                               const Eigen::Vector3d& velocity_in_world,
                                               double duration_s)
    : world_from_body_0_(world_from_body_0),
      omega_in_body_(omega_in_body),
      velocity_in_world_(velocity_in_world),
      duration_s_(duration_s) {
  IMUMATCH_CHECK(duration_s > 0, "duration must be positive");
}

Rigid3d ConstantRateTrajectory::WorldFromBody(double t) const {
  return Rigid3d(world_from_body_0_.rotation * ExpSO3(omega_in_body_ * t),
                 world_from_body_0_.translation + velocity_in_world_ * t);
}
Eigen::Vector3d ConstantRateTrajectory::VelocityInWorld(double) const { return velocity_in_world_; }
Eigen::Vector3d ConstantRateTrajectory::AccelerationInWorld(double) const {
  return Eigen::Vector3d::Zero();
}
Eigen::Vector3d ConstantRateTrajectory::AngularVelocityInBody(double) const {
  return omega_in_body_;
}

CircleTrajectory::CircleTrajectory(double radius_m, double omega_rad_s, double height_m,
                                   double duration_s)
    : radius_(radius_m), omega_(omega_rad_s), height_(height_m), duration_s_(duration_s) {
  IMUMATCH_CHECK(radius_m > 0 && duration_s > 0, "radius and duration must be positive");
}

Rigid3d CircleTrajectory::WorldFromBody(double t) const {
  const double a = omega_ * t;
  // Body x along the direction of travel (tangent), z up.
  const double yaw = a + (omega_ >= 0 ? M_PI / 2 : -M_PI / 2);
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())),
                 Eigen::Vector3d(radius_ * std::cos(a), radius_ * std::sin(a), height_));
}
Eigen::Vector3d CircleTrajectory::VelocityInWorld(double t) const {
  const double a = omega_ * t;
  return radius_ * omega_ * Eigen::Vector3d(-std::sin(a), std::cos(a), 0.0);
}
Eigen::Vector3d CircleTrajectory::AccelerationInWorld(double t) const {
  const double a = omega_ * t;
  return -radius_ * omega_ * omega_ * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
}
Eigen::Vector3d CircleTrajectory::AngularVelocityInBody(double) const {
  return Eigen::Vector3d(0.0, 0.0, omega_);
}

SinusoidTrajectory::SinusoidTrajectory(const Params& params) : params_(params) {
  IMUMATCH_CHECK(params.duration_s > 0, "duration must be positive");
}

// derivative 0: angles (roll, pitch, yaw); 1: their rates; 2: their second derivatives.
Eigen::Vector3d SinusoidTrajectory::Angles(double t, int derivative) const {
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) {
    const double w = 2.0 * M_PI * params_.angle_frequency_hz[i];
    const double b = params_.angle_amplitude_rad[i];
    switch (derivative) {
      case 0:
        out[i] = b * std::sin(w * t);
        break;
      case 1:
        out[i] = b * w * std::cos(w * t);
        break;
      default:
        out[i] = -b * w * w * std::sin(w * t);
        break;
    }
  }
  return out;
}

Rigid3d SinusoidTrajectory::WorldFromBody(double t) const {
  const Eigen::Vector3d e = Angles(t, 0);
  Eigen::Vector3d p = params_.world_from_body_0.translation;
  for (int i = 0; i < 3; ++i) {
    p[i] += params_.amplitude_m[i] * std::sin(2.0 * M_PI * params_.frequency_hz[i] * t);
  }
  return Rigid3d(params_.world_from_body_0.rotation * FromEulerZYX(e[0], e[1], e[2]), p);
}

Eigen::Vector3d SinusoidTrajectory::VelocityInWorld(double t) const {
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const double w = 2.0 * M_PI * params_.frequency_hz[i];
    v[i] = params_.amplitude_m[i] * w * std::cos(w * t);
  }
  return v;
}

Eigen::Vector3d SinusoidTrajectory::AccelerationInWorld(double t) const {
  Eigen::Vector3d a;
  for (int i = 0; i < 3; ++i) {
    const double w = 2.0 * M_PI * params_.frequency_hz[i];
    a[i] = -params_.amplitude_m[i] * w * w * std::sin(w * t);
  }
  return a;
}

Eigen::Vector3d SinusoidTrajectory::AngularVelocityInBody(double t) const {
  // Body rates of R = Rz(yaw) Ry(pitch) Rx(roll) (the constant R0 in front does not change them).
  const Eigen::Vector3d e = Angles(t, 0), d = Angles(t, 1);
  const double sr = std::sin(e[0]), cr = std::cos(e[0]), sp = std::sin(e[1]), cp = std::cos(e[1]);
  return Eigen::Vector3d(d[0] - sp * d[2], cr * d[1] + sr * cp * d[2], -sr * d[1] + cr * cp * d[2]);
}

}  // namespace imumatch
