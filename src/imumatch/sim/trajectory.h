#pragma once

#include <cstdint>
#include <memory>

#include <Eigen/Core>

#include "imumatch/core/rigid3.h"

namespace imumatch {

// A continuous-time trajectory of a body (GTSAM's Scenario): everything an IMU simulator and a
// test need, at any time. World frame z up; gravity is not part of the trajectory.
class Trajectory {
 public:
  virtual ~Trajectory() = default;
  virtual Rigid3d WorldFromBody(double t_s) const = 0;
  virtual Eigen::Vector3d VelocityInWorld(double t_s) const = 0;        // d/dt position
  virtual Eigen::Vector3d AccelerationInWorld(double t_s) const = 0;    // d2/dt2 position
  virtual Eigen::Vector3d AngularVelocityInBody(double t_s) const = 0;  // R^T dR/dt = Hat(w)
  // Time span over which the trajectory is defined, in seconds.
  virtual double StartTime() const { return 0.0; }
  virtual double EndTime() const = 0;
};

// Rotation about a fixed axis at a constant rate (rad/s) while moving at constant velocity.
class ConstantRateTrajectory : public Trajectory {
 public:
  ConstantRateTrajectory(const Rigid3d& world_from_body_0, const Eigen::Vector3d& omega_in_body,
                         const Eigen::Vector3d& velocity_in_world, double duration_s);
  Rigid3d WorldFromBody(double t_s) const override;
  Eigen::Vector3d VelocityInWorld(double t_s) const override;
  Eigen::Vector3d AccelerationInWorld(double t_s) const override;
  Eigen::Vector3d AngularVelocityInBody(double t_s) const override;
  double EndTime() const override { return duration_s_; }

 private:
  Rigid3d world_from_body_0_;
  Eigen::Vector3d omega_in_body_, velocity_in_world_;
  double duration_s_;
};

// Horizontal circle of given radius about the world z axis at angular speed omega, the body's x
// axis along the direction of travel (yaw follows the tangent), optionally tilted.
class CircleTrajectory : public Trajectory {
 public:
  CircleTrajectory(double radius_m, double omega_rad_s, double height_m, double duration_s);
  Rigid3d WorldFromBody(double t_s) const override;
  Eigen::Vector3d VelocityInWorld(double t_s) const override;
  Eigen::Vector3d AccelerationInWorld(double t_s) const override;
  Eigen::Vector3d AngularVelocityInBody(double t_s) const override;
  double EndTime() const override { return duration_s_; }

 private:
  double radius_, omega_, height_, duration_s_;
};

// Sinusoidal translation p(t) = p0 + A sin(2 pi f t + phase) per axis, and sinusoidal
// roll/pitch/yaw angles (Z-Y-X Euler) theta(t) = B sin(2 pi g t): a handheld-like shake.
class SinusoidTrajectory : public Trajectory {
 public:
  struct Params {
    Rigid3d world_from_body_0;
    Eigen::Vector3d amplitude_m = Eigen::Vector3d(0.05, 0.03, 0.02);
    Eigen::Vector3d frequency_hz = Eigen::Vector3d(0.7, 1.1, 0.5);
    Eigen::Vector3d angle_amplitude_rad = Eigen::Vector3d(0.05, 0.08, 0.1);  // roll, pitch, yaw
    Eigen::Vector3d angle_frequency_hz = Eigen::Vector3d(0.9, 0.6, 0.4);
    double duration_s = 5.0;
  };
  explicit SinusoidTrajectory(const Params& params);
  Rigid3d WorldFromBody(double t_s) const override;
  Eigen::Vector3d VelocityInWorld(double t_s) const override;
  Eigen::Vector3d AccelerationInWorld(double t_s) const override;
  Eigen::Vector3d AngularVelocityInBody(double t_s) const override;
  double EndTime() const override { return params_.duration_s; }

 private:
  Eigen::Vector3d Angles(double t, int derivative) const;
  Params params_;
};

}  // namespace imumatch
