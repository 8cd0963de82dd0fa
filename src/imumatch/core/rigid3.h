#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace imumatch {

// A rigid transform that maps points from frame A into frame B, named b_from_a:
//   p_in_b = b_from_a * p_in_a = rotation * p_in_a + translation.
// Compose as c_from_a = c_from_b * b_from_a.
struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& q, const Eigen::Vector3d& t)
      : rotation(q.normalized()), translation(t) {}
  Rigid3d(const Eigen::Matrix3d& r, const Eigen::Vector3d& t)
      : rotation(Eigen::Quaterniond(r).normalized()), translation(t) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  Rigid3d operator*(const Rigid3d& a) const {
    return Rigid3d(rotation * a.rotation, rotation * a.translation + translation);
  }
  Rigid3d Inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return Rigid3d(inv, -(inv * translation));
  }
  Eigen::Matrix3d RotationMatrix() const { return rotation.toRotationMatrix(); }
  Eigen::Matrix4d ToMatrix() const {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = RotationMatrix();
    m.topRightCorner<3, 1>() = translation;
    return m;
  }
  // Throws InvalidArgument unless the top-left block is a rotation (orthonormal, det +1, within
  // tol) and the last row is 0 0 0 1.
  static Rigid3d FromMatrix(const Eigen::Matrix4d& m, double tol = 1e-4);
  static Rigid3d Identity() { return Rigid3d(); }
};

// Angle in radians of the rotation a^-1 * b (0 when equal), and the distance of the translations.
double RotationAngle(const Eigen::Quaterniond& q);
double RotationDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

// Linear interpolation of translation and slerp of rotation, alpha in [0,1].
Rigid3d Interpolate(const Rigid3d& a, const Rigid3d& b, double alpha);

}  // namespace imumatch
