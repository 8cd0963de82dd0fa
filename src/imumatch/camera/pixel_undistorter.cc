#include "imumatch/camera/pixel_undistorter.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "imumatch/core/error.h"

namespace imumatch {

PixelUndistorter::PixelUndistorter(const PinholeCamera& camera, double cell_px) : camera_(camera) {
  camera.Check();
  IMUMATCH_CHECK(std::isfinite(cell_px) && cell_px >= 1.0, "cell_px=" << cell_px);
  identity_ = !camera.HasDistortion();
  min_x_ = min_y_ = -0.5;
  max_x_ = camera.width - 0.5;
  max_y_ = camera.height - 0.5;
  if (identity_) return;
  cell_ = cell_px;
  inv_cell_ = 1.0 / cell_px;
  cols_ = static_cast<int>(std::ceil(camera.width / cell_px)) + 1;
  rows_ = static_cast<int>(std::ceil(camera.height / cell_px)) + 1;
  table_.resize(static_cast<size_t>(cols_) * rows_);
  for (int r = 0; r < rows_; ++r) {
    for (int c = 0; c < cols_; ++c) {
      table_[static_cast<size_t>(r) * cols_ + c] =
          camera.PixelToNormalized(Eigen::Vector2d(origin_ + c * cell_, origin_ + r * cell_));
    }
  }
  // The image border mapped to ideal pixels, sampled every pixel: its bounding box.
  Eigen::Vector2d lo, hi;
  camera.IdealImageBounds(1.0, &lo, &hi);
  min_x_ = lo.x();
  min_y_ = lo.y();
  max_x_ = hi.x();
  max_y_ = hi.y();
  const double jac_cell = 16.0;
  inv_jac_cell_ = 1.0 / jac_cell;
  jac_cols_ = static_cast<int>(std::ceil((max_x_ - min_x_) / jac_cell)) + 1;
  jac_rows_ = static_cast<int>(std::ceil((max_y_ - min_y_) / jac_cell)) + 1;
  jac_table_.resize(static_cast<size_t>(jac_cols_) * jac_rows_);
  for (int r = 0; r < jac_rows_; ++r) {
    for (int c = 0; c < jac_cols_; ++c) {
      const Eigen::Matrix2d m = camera.IdealFromPixelJacobian(
          Eigen::Vector2d(min_x_ + c * jac_cell, min_y_ + r * jac_cell));
      jac_table_[static_cast<size_t>(r) * jac_cols_ + c] = (m * m.transpose()).cast<float>();
    }
  }
}

Eigen::Vector2d PixelUndistorter::ToIdeal(const Eigen::Vector2d& uv,
                                          Eigen::Matrix2d* ideal_from_pixel) const {
  if (identity_) {
    if (ideal_from_pixel != nullptr) ideal_from_pixel->setIdentity();
    return uv;
  }
  const double gx = (uv.x() - origin_) * inv_cell_, gy = (uv.y() - origin_) * inv_cell_;
  Eigen::Vector2d xy;
  if (gx >= 0.0 && gy >= 0.0 && gx < cols_ - 1 && gy < rows_ - 1) {
    const int c = static_cast<int>(gx), r = static_cast<int>(gy);
    const double fx = gx - c, fy = gy - r;
    const Eigen::Vector2d* row0 = &table_[static_cast<size_t>(r) * cols_ + c];
    const Eigen::Vector2d* row1 = row0 + cols_;
    xy = (1.0 - fy) * ((1.0 - fx) * row0[0] + fx * row0[1]) +
         fy * ((1.0 - fx) * row1[0] + fx * row1[1]);
  } else {
    xy = camera_.PixelToNormalized(uv);  // outside the table (or NaN): the iterative inverse
  }
  // One Newton step on distort(xy) = target.
  const Eigen::Vector2d target = camera_.IdealToNormalized(uv);
  Eigen::Matrix2d j;
  const Eigen::Vector2d residual = camera_.DistortNormalized(xy, &j) - target;
  const Eigen::Matrix2d j_inv = j.inverse();
  xy -= j_inv * residual;
  if (ideal_from_pixel != nullptr) {
    // K J^-1 K^-1 (J at the previous iterate: the difference is far below what noise needs).
    *ideal_from_pixel << j_inv(0, 0), j_inv(0, 1) * camera_.fx / camera_.fy,
        j_inv(1, 0) * camera_.fy / camera_.fx, j_inv(1, 1);
  }
  return camera_.NormalizedToIdeal(xy);
}

}  // namespace imumatch
