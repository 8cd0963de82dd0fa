#include "imumatch/matching/patch_alignment.h"

#include <cmath>
#include <limits>

#include "imumatch/matching/bilinear_sampling.h"

namespace imumatch {

PatchTemplate::PatchTemplate(int max_half_size) : max_half_(max_half_size) {
  const size_t ext = static_cast<size_t>(2 * max_half_size + 3);
  const size_t side = ext - 2;
  ring_.resize(ext * ext);
  xs_.resize(ext * ext);
  ys_.resize(ext * ext);
  t_.resize(side * side);
  gx_.resize(side * side);
  gy_.resize(side * side);
  target_.resize(side * side);
}

AlignStatus PatchTemplate::Build(const cv::Mat& gray_a, const Eigen::Vector2f& ka,
                                 const Eigen::Matrix2f& inv, int h, float min_texture,
                                 float identity_tolerance_px) {
  h_ = h < 1 ? 1 : (h > max_half_ ? max_half_ : h);
  const int side = 2 * h_ + 1, ext = side + 2;
  const size_t n = static_cast<size_t>(side) * side;
  const float inv_n = 1.0f / static_cast<float>(n);
  const uint8_t* data_a = gray_a.ptr<uint8_t>();
  const size_t step_a = gray_a.step[0];
  const float reach = static_cast<float>(h_ + 1);
  float* ring = ring_.data();
  const bool identity =
      (inv - Eigen::Matrix2f::Identity()).cwiseAbs().maxCoeff() * static_cast<float>(2 * h_) <
      identity_tolerance_px;
  const float reach_a = reach * inv.cwiseAbs().rowwise().sum().maxCoeff();
  if (!(reach_a < 1e6f) ||
      !BoxInside(gray_a, ka.x(), ka.y(), -reach_a, reach_a, -reach_a, reach_a)) {
    return AlignStatus::kBorder;
  }
  if (identity) {
    SampleGrid(data_a, step_a, ka.x() - reach, ka.y() - reach, ext, ext, ring);
  } else {
    // Row by row: the sample position moves by inv's first column along a row.
    const float dxc = inv(0, 0), dyc = inv(1, 0);
    // The positions first, then all of them sampled in one call (vectorised).
    for (int r = 0; r < ext; ++r) {
      const float qy = static_cast<float>(r - h_ - 1);
      float x = ka.x() - reach * dxc + inv(0, 1) * qy;
      float y = ka.y() - reach * dyc + inv(1, 1) * qy;
      float* xs = xs_.data() + static_cast<size_t>(r) * ext;
      float* ys = ys_.data() + static_cast<size_t>(r) * ext;
      for (int c = 0; c < ext; ++c, x += dxc, y += dyc) {
        xs[c] = x;
        ys[c] = y;
      }
    }
    SamplePoints(data_a, step_a, gray_a.rows, xs_.data(), ys_.data(), ext * ext, ring);
  }
  // Normalised template statistics and its gradients (central differences, B's pixels). The
  // sums are vectorised (their order is not fixed).
  float sum = 0.0f, sum2 = 0.0f;
  for (int r = 1; r <= side; ++r) {
    const float* row = ring + static_cast<size_t>(r) * ext + 1;
#pragma omp simd reduction(+ : sum, sum2)
    for (int c = 0; c < side; ++c) {
      sum += row[c];
      sum2 += row[c] * row[c];
    }
  }
  const float mean_t = sum * inv_n;
  const float var_t = sum2 * inv_n - mean_t * mean_t;
  if (!(var_t > 1e-6f)) return AlignStatus::kTexture;
  const float inv_sd_t = 1.0f / std::sqrt(var_t);
  const float half_sd = 0.5f * inv_sd_t;
  float h00 = 0.0f, h01 = 0.0f, h11 = 0.0f, gsx = 0.0f, gsy = 0.0f, gtx = 0.0f, gty = 0.0f;
  for (int r = 0; r < side; ++r) {
    const float* mid = ring + static_cast<size_t>(r + 1) * ext + 1;
    const float* up = mid - ext;
    const float* down = mid + ext;
    float* t_row = t_.data() + static_cast<size_t>(r) * side;
    float* gx_row = gx_.data() + static_cast<size_t>(r) * side;
    float* gy_row = gy_.data() + static_cast<size_t>(r) * side;
#pragma omp simd reduction(+ : h00, h01, h11, gsx, gsy, gtx, gty)
    for (int c = 0; c < side; ++c) {
      const float t = (mid[c] - mean_t) * inv_sd_t;
      const float dx = half_sd * (mid[c + 1] - mid[c - 1]);
      const float dy = half_sd * (down[c] - up[c]);
      t_row[c] = t;
      gx_row[c] = dx;
      gy_row[c] = dy;
      h00 += dx * dx;
      h01 += dx * dy;
      h11 += dy * dy;
      gsx += dx;
      gsy += dy;
      gtx += dx * t;
      gty += dy * t;
    }
  }
  h00_ = h00;
  h01_ = h01;
  h11_ = h11;
  gsum_x_ = gsx;
  gsum_y_ = gsy;
  gt_x_ = gtx;
  gt_y_ = gty;
  // Texture in both directions: the smaller eigenvalue of the Hessian per sample.
  const float a00 = h00_ * inv_n, a01 = h01_ * inv_n, a11 = h11_ * inv_n;
  const float min_eig =
      0.5f * (a00 + a11 - std::sqrt((a00 - a11) * (a00 - a11) + 4.0f * a01 * a01));
  if (!(min_eig >= min_texture)) return AlignStatus::kTexture;
  return AlignStatus::kAligned;
}

AlignStatus PatchTemplate::Align(const cv::Mat& gray_b, const Eigen::Vector2f& start,
                                 const PatchAlignOptions& options, Eigen::Vector2f* xy,
                                 int64_t* iterations, float* correlation) {
  const int h = h_, side = 2 * h + 1;
  const size_t n = static_cast<size_t>(side) * side;
  const float inv_n = 1.0f / static_cast<float>(n);
  const uint8_t* data_b = gray_b.ptr<uint8_t>();
  const size_t step_b = gray_b.step[0];
  const float conv2 = options.convergence_px * options.convergence_px;
  const float slow2 = 25.0f * conv2;
  const float hf = static_cast<float>(h);
  const float det = h00_ * h11_ - h01_ * h01_;
  const float i00 = h11_ / det, i01 = -h01_ / det, i11 = h00_ / det;
  const float* gx = gx_.data();
  const float* t = t_.data();
  const float* gy = gy_.data();
  float* target = target_.data();
  float x = start.x(), y = start.y();
  bool converged = false;
  float last_move2 = std::numeric_limits<float>::infinity();
  for (int it = 0; it < options.max_iterations; ++it) {
    ++*iterations;
    if (!BoxInside(gray_b, x, y, -hf, hf, -hf, hf)) return AlignStatus::kBorder;
    SampleGrid(data_b, step_b, x - hf, y - hf, side, side, target);
    float s1 = 0.0f, s2 = 0.0f, sgx = 0.0f, sgy = 0.0f, st = 0.0f;
#pragma omp simd reduction(+ : s1, s2, sgx, sgy, st)
    for (size_t k = 0; k < n; ++k) {
      const float v = target[k];
      s1 += v;
      s2 += v * v;
      sgx += gx[k] * v;
      sgy += gy[k] * v;
      st += t[k] * v;
    }
    const float mean_i = s1 * inv_n;
    const float var_i = s2 * inv_n - mean_i * mean_i;
    if (!(var_i > 1e-6f)) return AlignStatus::kBorder;
    const float inv_sd_i = 1.0f / std::sqrt(var_i);
    if (correlation != nullptr) *correlation = st * inv_n * inv_sd_i;
    const float bx = (sgx - mean_i * gsum_x_) * inv_sd_i - gt_x_;
    const float by = (sgy - mean_i * gsum_y_) * inv_sd_i - gt_y_;
    const float mx = i00 * bx + i01 * by, my = i01 * bx + i11 * by;
    x -= mx;
    y -= my;
    if (!std::isfinite(x) || !std::isfinite(y)) return AlignStatus::kBorder;
    last_move2 = mx * mx + my * my;
    if (last_move2 < conv2) {
      converged = true;
      break;
    }
  }
  *xy = Eigen::Vector2f(x, y);
  // Slow convergence (a last step under 5x the tolerance) still counts: the estimate is good to
  // a few hundredths of a pixel.
  if (!converged && !(last_move2 < slow2)) return AlignStatus::kNoConvergence;
  return AlignStatus::kAligned;
}

float PatchTemplate::Correlation(const cv::Mat& gray_b, const Eigen::Vector2f& xy) {
  const int side = 2 * h_ + 1;
  const float hf = static_cast<float>(h_);
  if (!xy.allFinite() || !BoxInside(gray_b, xy.x(), xy.y(), -hf, hf, -hf, hf)) return -2.0f;
  const size_t n = static_cast<size_t>(side) * side;
  float* target = target_.data();
  SampleGrid(gray_b.ptr<uint8_t>(), gray_b.step[0], xy.x() - hf, xy.y() - hf, side, side, target);
  float s1 = 0.0f, s2 = 0.0f, st = 0.0f;
  const float* t = t_.data();
#pragma omp simd reduction(+ : s1, s2, st)
  for (size_t k = 0; k < n; ++k) {
    s1 += target[k];
    s2 += target[k] * target[k];
    st += t[k] * target[k];
  }
  const float inv_n = 1.0f / static_cast<float>(n);
  const float mean = s1 * inv_n;
  const float var = s2 * inv_n - mean * mean;
  if (!(var > 1e-6f)) return -2.0f;
  // sum_k T_k (I_k - mean) / (n sd): T has zero mean and unit variance.
  return st * inv_n / std::sqrt(var);
}

}  // namespace imumatch
