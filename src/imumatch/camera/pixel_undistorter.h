#pragma once

#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include "imumatch/camera/pinhole_camera.h"

namespace imumatch {

// Image pixel -> ideal pixel (PinholeCamera's "ideal" pixels: K times the undistorted bearing) for
// every keypoint of every frame, fast. PinholeCamera::PixelToIdeal iterates Newton from the
// distorted bearing (several steps for a strong lens); here a table over the image, sampled every
// `cell_px` pixels, gives a start within a small fraction of a pixel and one Newton step with the
// analytic Jacobian finishes it (the error squares: below 1e-6 px for EuRoC's k1 = -0.28 lens).
// The table is built once per camera. Pixels outside the image fall back to the iterative inverse.
// An equidistant lens takes two Newton steps (its ideal pixels curve more at the corners) and, in
// ToIdealInPlace, a radial table (g = tan(theta) / rho by cubic Hermite interpolation), its loop
// vectorised the same way.
// For a camera without distortion every call is the identity.
class PixelUndistorter {
 public:
  PixelUndistorter() = default;
  explicit PixelUndistorter(const PinholeCamera& camera, double cell_px = 8.0);

  const PinholeCamera& camera() const { return camera_; }
  bool identity() const { return identity_; }

  // Image pixel -> ideal pixel. When ideal_from_pixel is given, also d ideal / d pixel there (the
  // map of image-pixel noise into ideal pixels).
  Eigen::Vector2d ToIdeal(const Eigen::Vector2d& uv,
                          Eigen::Matrix2d* ideal_from_pixel = nullptr) const;
  // ToIdeal for n points in place (no Jacobian): point i is (xy[i * stride], xy[i * stride + 1]),
  // stride in floats (2 for packed pairs; more for the x, y members of an array of records). The
  // table and the Newton step written out in one loop, double arithmetic as ToIdeal's (equal to
  // float rounding): what a frame's keypoints cost, about 4x less than a ToIdeal call each.
  // Points outside the table (and NaN) take ToIdeal. The loop is compiled for AVX-512, AVX2+FMA
  // and the baseline, chosen at run time (kAuto: the best the CPU has; a path the CPU lacks
  // throws InvalidArgument).
  enum class Path { kAuto, kPortable, kAvx2, kAvx512 };
  static bool Supported(Path path);
  void ToIdealInPlace(float* xy, int n, int stride, Path path = Path::kAuto) const;
  // Ideal pixel -> image pixel (closed form).
  Eigen::Vector2d ToImage(const Eigen::Vector2d& ideal) const {
    return identity_ ? ideal : camera_.IdealToPixel(ideal);
  }

  // M M^T with M = d ideal / d image pixel at an ideal position, from a table over the ideal image
  // (every 16 ideal px, nearest node): isotropic image-pixel noise of variance v becomes v M M^T
  // in ideal pixels. The lens's local stretch changes by well under 1 % between nodes, and this
  // maps noise, not positions. The identity without distortion.
  const Eigen::Matrix2f& NoiseStretchAt(double ideal_x, double ideal_y) const {
    if (identity_) return identity_jacobian_;
    const int c =
        std::clamp(static_cast<int>((ideal_x - min_x_) * inv_jac_cell_ + 0.5), 0, jac_cols_ - 1);
    const int r =
        std::clamp(static_cast<int>((ideal_y - min_y_) * inv_jac_cell_ + 0.5), 0, jac_rows_ - 1);
    return jac_table_[static_cast<size_t>(r) * jac_cols_ + c];
  }

  // The axis-aligned box in ideal pixels that holds the whole image [-0.5, w-0.5) x [-0.5, h-0.5)
  // (with a barrel lens the corners reach further out than the edge midpoints).
  double ideal_min_x() const { return min_x_; }
  double ideal_min_y() const { return min_y_; }
  double ideal_max_x() const { return max_x_; }
  double ideal_max_y() const { return max_y_; }

 private:
  PinholeCamera camera_;
  bool identity_ = true;
  double cell_ = 8.0, inv_cell_ = 0.125;
  double origin_ = -0.5;  // table node (0, 0) sits at pixel (origin_, origin_)
  int cols_ = 0, rows_ = 0;
  std::vector<Eigen::Vector2d> table_;  // normalised undistorted bearing at each node
  double min_x_ = -0.5, min_y_ = -0.5, max_x_ = 0.0, max_y_ = 0.0;
  Eigen::Matrix2f identity_jacobian_ = Eigen::Matrix2f::Identity();
  double inv_jac_cell_ = 1.0 / 16.0;
  int jac_cols_ = 0, jac_rows_ = 0;
  std::vector<Eigen::Matrix2f> jac_table_;
  // Equidistant lens: the undistorted-to-distorted radius ratio g(rho) = tan(theta(rho)) / rho at
  // rho = k * radial_step_ (k = 0..n-1), with its derivative, for ToIdealInPlace's cubic Hermite
  // interpolation (x_ideal = g(|x_d|) x_d on the normalised plane).
  double radial_step_ = 0.0, inv_radial_step_ = 0.0;
  std::vector<double> radial_g_, radial_dg_;
};

}  // namespace imumatch
