#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "imumatch/core/rigid3.h"
#include "imumatch/core/types.h"
#include "imumatch/sim/trajectory.h"

namespace imumatch {

struct SplineFitOptions {
  // Spacing of the uniform knots (seconds). Larger = smoother (less noise in the derived velocity,
  // acceleration and angular velocity), smaller = closer to the samples. 0.05 s suits
  // motion-capture ground truth at ~100 Hz such as TUM's.
  double knot_spacing_s = 0.05;
  // Weight of the penalty on second differences of the control points (P-spline), relative to the
  // data term; regularises knots without samples. 0 = plain least squares.
  double smoothing = 1e-3;
  void Check() const;
};

// A smooth continuous-time fit of stamped poses world_from_body: uniform cubic B-splines (C2)
// fitted by penalised least squares to the translation and to the quaternion components (signs
// made continuous), the quaternion normalised after evaluation. Position, velocity, acceleration
// and body angular velocity (omega = 2 vec(q^-1 dq/dt)) are analytic derivatives of the splines,
// so an IMU can be simulated from ground truth. Trajectory time t (seconds) is measured from the
// first pose: t = (t_ns - t0_ns()) * 1e-9; queries outside [0, EndTime()] are clamped.
class SplineTrajectory : public Trajectory {
 public:
  // At most this many knot intervals (2e6: 27.8 hours at 0.05 s), checked before allocating.
  static constexpr int kMaxSegments = 2'000'000;
  // Throws InvalidArgument for fewer than 4 poses, timestamps not strictly increasing (names the
  // index), non-finite poses, or bad options.
  explicit SplineTrajectory(const std::vector<StampedPose>& poses,
                            const SplineFitOptions& options = SplineFitOptions());

  Rigid3d WorldFromBody(double t_s) const override;
  Eigen::Vector3d VelocityInWorld(double t_s) const override;
  Eigen::Vector3d AccelerationInWorld(double t_s) const override;
  Eigen::Vector3d AngularVelocityInBody(double t_s) const override;
  double EndTime() const override { return duration_s_; }

  int64_t t0_ns() const { return t0_ns_; }
  double TimeOf(int64_t t_ns) const { return static_cast<double>(t_ns - t0_ns_) * 1e-9; }
  int num_control_points() const { return static_cast<int>(control_.rows()); }

 private:
  // Value (derivative 0, 1 or 2) of the 7 splines (tx ty tz qx qy qz qw) at t.
  Eigen::Matrix<double, 7, 1> Eval(double t_s, int derivative) const;

  int64_t t0_ns_ = 0;
  double duration_s_ = 0.0;
  double knot_spacing_ = 0.0;
  int num_segments_ = 0;
  Eigen::Matrix<double, Eigen::Dynamic, 7> control_;
};

}  // namespace imumatch
