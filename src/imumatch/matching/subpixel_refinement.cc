#include "imumatch/matching/subpixel_refinement.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "imumatch/core/error.h"

namespace imumatch {

void SubpixelOptions::Check() const {
  IMUMATCH_CHECK(half_size >= 2 && half_size <= 15, "half_size=" << half_size);
  IMUMATCH_CHECK(max_iterations >= 1 && max_iterations <= 100, "max_iterations=" << max_iterations);
  IMUMATCH_CHECK(std::isfinite(convergence_px) && convergence_px > 0.0,
                 "convergence_px=" << convergence_px);
  IMUMATCH_CHECK(std::isfinite(max_shift_px) && max_shift_px > 0.0,
                 "max_shift_px=" << max_shift_px);
  IMUMATCH_CHECK(std::isfinite(min_texture) && min_texture >= 0.0, "min_texture=" << min_texture);
}

namespace {

// Bilinear sample of an 8-bit image at a point known to lie inside [0, cols-1) x [0, rows-1).
inline float SampleUnchecked(const uint8_t* data, size_t step, float x, float y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const uint8_t* r0 = data + static_cast<size_t>(y0) * step + x0;
  const uint8_t* r1 = r0 + step;
  const float top = r0[0] + fx * (static_cast<float>(r0[1]) - r0[0]);
  const float bottom = r1[0] + fx * (static_cast<float>(r1[1]) - r1[0]);
  return top + fy * (bottom - top);
}

// Samples the w x h grid of unit steps whose first sample is at (x, y) (bilinear, one set of
// weights for all samples), row-major into out. The grid must lie inside the image.
inline void SampleGrid(const uint8_t* data, size_t step, float x, float y, int w, int h,
                       float* out) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const float w00 = (1.0f - fx) * (1.0f - fy), w01 = fx * (1.0f - fy);
  const float w10 = (1.0f - fx) * fy, w11 = fx * fy;
  for (int r = 0; r < h; ++r) {
    const uint8_t* p = data + static_cast<size_t>(y0 + r) * step + x0;
    const uint8_t* q = p + step;
    float* o = out + static_cast<size_t>(r) * w;
    for (int c = 0; c < w; ++c) {
      o[c] = w00 * p[c] + w01 * p[c + 1] + w10 * q[c] + w11 * q[c + 1];
    }
  }
}

// True when every point centre + offset (offsets spanning [min, max]) can be sampled.
inline bool BoxInside(const cv::Mat& img, float cx, float cy, float min_x, float max_x, float min_y,
                      float max_y) {
  return cx + min_x >= 0.0f && cy + min_y >= 0.0f && cx + max_x < img.cols - 1.001f &&
         cy + max_y < img.rows - 1.001f;
}

enum class AlignResult { kAligned, kBorder, kTexture, kNoConvergence };

// Scratch buffers of one alignment, sized for the largest patch.
struct AlignBuffers {
  std::vector<float> ring, gx, gy, target;
  explicit AlignBuffers(int max_half) {
    const size_t ext = static_cast<size_t>(2 * max_half + 3);
    const size_t side = ext - 2;
    ring.resize(ext * ext);
    gx.resize(side * side);
    gy.resize(side * side);
    target.resize(side * side);
  }
};

// Aligns A's (2h+1)^2 patch around ka, warped by inv (B offset -> A offset), in B starting at kb.
// On kAligned, *xy is the aligned position in B.
AlignResult Align(const cv::Mat& gray_a, const cv::Mat& gray_b, const Eigen::Vector2f& ka,
                  const Eigen::Vector2f& kb, const Eigen::Matrix2f& inv, int h,
                  const SubpixelOptions& options, AlignBuffers& buf, Eigen::Vector2f* xy,
                  int64_t* iterations) {
  const int side = 2 * h + 1, ext = side + 2;
  const size_t n = static_cast<size_t>(side) * side;
  const float inv_n = 1.0f / static_cast<float>(n);
  const uint8_t* data_a = gray_a.ptr<uint8_t>();
  const uint8_t* data_b = gray_b.ptr<uint8_t>();
  const size_t step_a = gray_a.step[0], step_b = gray_b.step[0];
  const float conv2 = static_cast<float>(options.convergence_px * options.convergence_px);
  const float slow2 = 25.0f * conv2;
  const float reach = static_cast<float>(h + 1);
  float* ring = buf.ring.data();
  float* gx = buf.gx.data();
  float* gy = buf.gy.data();
  float* target = buf.target.data();
  // A warp that moves no template sample by more than 0.05 px is the identity: A's patch is
  // then read on a grid too.
  const bool identity =
      (inv - Eigen::Matrix2f::Identity()).cwiseAbs().maxCoeff() * static_cast<float>(2 * h) < 0.05f;
  const float reach_a = reach * inv.cwiseAbs().rowwise().sum().maxCoeff();
  if (!BoxInside(gray_a, ka.x(), ka.y(), -reach_a, reach_a, -reach_a, reach_a)) {
    return AlignResult::kBorder;
  }
  if (identity) {
    SampleGrid(data_a, step_a, ka.x() - reach, ka.y() - reach, ext, ext, ring);
  } else {
    for (int r = 0; r < ext; ++r) {
      const float qy = static_cast<float>(r - h - 1);
      for (int c = 0; c < ext; ++c) {
        const float qx = static_cast<float>(c - h - 1);
        ring[static_cast<size_t>(r) * ext + c] =
            SampleUnchecked(data_a, step_a, ka.x() + inv(0, 0) * qx + inv(0, 1) * qy,
                            ka.y() + inv(1, 0) * qx + inv(1, 1) * qy);
      }
    }
  }
  // Normalised template statistics and its gradients (central differences, B's pixels).
  float sum = 0.0f, sum2 = 0.0f;
  for (int r = 1; r <= side; ++r) {
    for (int c = 1; c <= side; ++c) {
      const float v = ring[static_cast<size_t>(r) * ext + c];
      sum += v;
      sum2 += v * v;
    }
  }
  const float mean_t = sum * inv_n;
  const float var_t = sum2 * inv_n - mean_t * mean_t;
  if (!(var_t > 1e-6f)) {
    return AlignResult::kTexture;
  }
  const float inv_sd_t = 1.0f / std::sqrt(var_t);
  float h00 = 0.0f, h01 = 0.0f, h11 = 0.0f, gsum_x = 0.0f, gsum_y = 0.0f, gt_x = 0.0f, gt_y = 0.0f;
  for (int r = 0; r < side; ++r) {
    for (int c = 0; c < side; ++c) {
      const size_t e = static_cast<size_t>(r + 1) * ext + c + 1;
      const size_t k = static_cast<size_t>(r) * side + c;
      const float t = (ring[e] - mean_t) * inv_sd_t;
      const float dx = 0.5f * inv_sd_t * (ring[e + 1] - ring[e - 1]);
      const float dy = 0.5f * inv_sd_t * (ring[e + ext] - ring[e - ext]);
      gx[k] = dx;
      gy[k] = dy;
      h00 += dx * dx;
      h01 += dx * dy;
      h11 += dy * dy;
      gsum_x += dx;
      gsum_y += dy;
      gt_x += dx * t;
      gt_y += dy * t;
    }
  }
  // Texture in both directions: the smaller eigenvalue of the Hessian per sample.
  const float a00 = h00 * inv_n, a01 = h01 * inv_n, a11 = h11 * inv_n;
  const float min_eig =
      0.5f * (a00 + a11 - std::sqrt((a00 - a11) * (a00 - a11) + 4.0f * a01 * a01));
  if (!(min_eig >= static_cast<float>(options.min_texture))) {
    return AlignResult::kTexture;
  }
  const float det = h00 * h11 - h01 * h01;
  const float i00 = h11 / det, i01 = -h01 / det, i11 = h00 / det;
  float x = kb.x(), y = kb.y();
  bool converged = false, ok = true;
  float last_move2 = std::numeric_limits<float>::infinity();
  for (int it = 0; it < options.max_iterations; ++it) {
    ++*iterations;
    if (!BoxInside(gray_b, x, y, -static_cast<float>(h), static_cast<float>(h),
                   -static_cast<float>(h), static_cast<float>(h))) {
      ok = false;
      break;
    }
    SampleGrid(data_b, step_b, x - static_cast<float>(h), y - static_cast<float>(h), side, side,
               target);
    float s1 = 0.0f, s2 = 0.0f, sgx = 0.0f, sgy = 0.0f;
    for (size_t k = 0; k < n; ++k) {
      const float v = target[k];
      s1 += v;
      s2 += v * v;
      sgx += gx[k] * v;
      sgy += gy[k] * v;
    }
    const float mean_i = s1 * inv_n;
    const float var_i = s2 * inv_n - mean_i * mean_i;
    if (!(var_i > 1e-6f)) {
      ok = false;
      break;
    }
    const float inv_sd_i = 1.0f / std::sqrt(var_i);
    const float bx = (sgx - mean_i * gsum_x) * inv_sd_i - gt_x;
    const float by = (sgy - mean_i * gsum_y) * inv_sd_i - gt_y;
    const float mx = i00 * bx + i01 * by, my = i01 * bx + i11 * by;
    x -= mx;
    y -= my;
    if (!std::isfinite(x) || !std::isfinite(y)) {
      ok = false;
      break;
    }
    last_move2 = mx * mx + my * my;
    if (last_move2 < conv2) {
      converged = true;
      break;
    }
  }
  if (!ok) return AlignResult::kBorder;
  // Slow convergence (a last step under 5x the tolerance) still counts: the estimate is good to
  // a few hundredths of a pixel.
  if (!converged && !(last_move2 < slow2)) return AlignResult::kNoConvergence;
  *xy = Eigen::Vector2f(x, y);
  return AlignResult::kAligned;
}

}  // namespace

// Inverse-compositional Lucas-Kanade on the translation with zero-mean, unit-variance
// intensities. The template is A's patch warped into B's frame once (A sampled at
// ka + M^-1 q for q on B's unit grid, M the predicted affine map), so every iteration samples B
// on an axis-aligned grid with one set of bilinear weights. With T the normalised template, g its
// gradients and I the samples of B at the current position, the Gauss-Newton step is
//   delta = H^-1 sum_k g_k (I'_k - T_k),  I'_k = (I_k - mean) / sd,  H = sum_k g_k g_k^T,
// and sum_k g_k I'_k = (sum_k g_k I_k - mean sum_k g_k) / sd, so one pass over the samples
// (sums of I, I^2 and g I) gives the step; the position moves by -delta.
SubpixelStats RefineMatches(const cv::Mat& gray_a, const cv::Mat& gray_b,
                            const std::vector<cv::KeyPoint>& keypoints_a,
                            const std::vector<cv::KeyPoint>& keypoints_b,
                            const std::vector<KeypointPrediction>& predictions,
                            const PinholeCamera& camera, const SubpixelOptions& options,
                            std::vector<Match>& matches) {
  options.Check();
  IMUMATCH_CHECK(!gray_a.empty() && !gray_b.empty(), "empty image");
  IMUMATCH_CHECK(gray_a.type() == CV_8UC1 && gray_b.type() == CV_8UC1,
                 "sub-pixel refinement needs 8-bit gray images");
  IMUMATCH_CHECK(predictions.empty() || predictions.size() == keypoints_a.size(),
                 predictions.size() << " predictions for " << keypoints_a.size() << " keypoints");
  SubpixelStats stats;
  const bool distorted = camera.HasDistortion();
  const float max_shift2 = static_cast<float>(options.max_shift_px * options.max_shift_px);
  AlignBuffers buffers(2 * options.half_size);
  std::vector<char> drop(matches.size(), 0);
  for (size_t mi = 0; mi < matches.size(); ++mi) {
    Match& m = matches[mi];
    m.refined_uv_b = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
    IMUMATCH_CHECK(m.query_idx >= 0 && static_cast<size_t>(m.query_idx) < keypoints_a.size() &&
                       m.train_idx >= 0 && static_cast<size_t>(m.train_idx) < keypoints_b.size(),
                   "match index outside the keypoints");
    const cv::KeyPoint& ka = keypoints_a[static_cast<size_t>(m.query_idx)];
    const cv::KeyPoint& kb = keypoints_b[static_cast<size_t>(m.train_idx)];
    // d pixel_b / d pixel_a: the prediction's affine map in ideal pixels, conjugated by the lens.
    Eigen::Matrix2f affine = Eigen::Matrix2f::Identity();
    if (!predictions.empty()) {
      const KeypointPrediction& p = predictions[static_cast<size_t>(m.query_idx)];
      if (p.HasWindow() && p.local_affine.allFinite()) {
        affine = p.local_affine;
        if (distorted) {
          // The lens's local Jacobians, taken at the image positions instead of the ideal ones
          // (a few per cent off at the corners of a strong lens; no iterative undistortion).
          affine = (camera.IdealFromPixelJacobian(Eigen::Vector2d(kb.pt.x, kb.pt.y)).inverse() *
                    affine.cast<double>() *
                    camera.IdealFromPixelJacobian(Eigen::Vector2d(ka.pt.x, ka.pt.y)))
                       .cast<float>();
        }
      }
    }
    const float det_a = affine.determinant();
    if (!(std::fabs(det_a) > 1e-3f)) {
      ++stats.failed_texture;  // a degenerate warp: nothing to align
      continue;
    }
    const Eigen::Matrix2f inv = affine.inverse();  // B offset -> A offset
    // A flat patch (the centre of a blob: SURF, AKAZE) is tried again at twice the size, where
    // the blob's edges give it texture.
    Eigen::Vector2f xy;
    const Eigen::Vector2f pa(ka.pt.x, ka.pt.y), pb(kb.pt.x, kb.pt.y);
    AlignResult r = Align(gray_a, gray_b, pa, pb, inv, options.half_size, options, buffers, &xy,
                          &stats.iterations);
    if (r == AlignResult::kTexture) {
      r = Align(gray_a, gray_b, pa, pb, inv, 2 * options.half_size, options, buffers, &xy,
                &stats.iterations);
    }
    if (r == AlignResult::kBorder) {
      ++stats.failed_border;
      continue;
    }
    if (r == AlignResult::kTexture) {
      ++stats.failed_texture;
      continue;
    }
    if (r == AlignResult::kNoConvergence || (xy - pb).squaredNorm() > max_shift2) {
      ++stats.failed_convergence;
      drop[mi] = options.drop_unaligned ? 1 : 0;
      continue;
    }
    m.refined_uv_b = xy;
    ++stats.refined;
  }
  if (options.drop_unaligned) {
    size_t keep = 0;
    for (size_t mi = 0; mi < matches.size(); ++mi) {
      if (!drop[mi]) matches[keep++] = matches[mi];
    }
    matches.resize(keep);
  }
  return stats;
}

}  // namespace imumatch
