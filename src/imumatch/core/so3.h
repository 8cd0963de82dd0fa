#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace imumatch {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kRadToDeg = 180.0 / kPi;
inline constexpr double kDegToRad = kPi / 180.0;

// Skew-symmetric matrix: Hat(a) * b == a.cross(b).
Eigen::Matrix3d Hat(const Eigen::Vector3d& v);

// Exponential map of SO(3): rotation by angle |omega| about omega/|omega|. Exact (no small-angle
// truncation beyond the Taylor branch used for |omega| < 1e-8).
Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& omega);

// Logarithm of SO(3): the rotation vector with norm in [0, pi].
Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q);

// Right Jacobian of SO(3) and its inverse (Forster et al., "On-Manifold Preintegration", eq. 8).
Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& omega);
Eigen::Matrix3d RightJacobianInverseSO3(const Eigen::Vector3d& omega);

// Rotation from Z-Y-X (yaw, pitch, roll) Euler angles: R = Rz(yaw) * Ry(pitch) * Rx(roll).
Eigen::Quaterniond FromEulerZYX(double roll, double pitch, double yaw);

}  // namespace imumatch
