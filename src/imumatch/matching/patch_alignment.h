#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace imumatch {

// Translation-only patch alignment between two 8-bit images, shared by the sub-pixel refinement
// of matches and the KLT tracker.
//
// A template is A's (2h+1)^2 patch around a point of A, sampled through a 2x2 map `inv` (offset in
// B -> offset in A: the patch as it should look in B, rotated and scaled by the predicted motion)
// and normalised to zero mean and unit variance, so the exposure's gain and bias cancel. It is
// aligned in B by inverse-compositional Lucas-Kanade on the translation: with T the normalised
// template, g its gradients and I the samples of B at the current position,
//   delta = H^-1 sum_k g_k (I'_k - T_k),  I'_k = (I_k - mean) / sd,  H = sum_k g_k g_k^T,
// and sum_k g_k I'_k = (sum_k g_k I_k - mean sum_k g_k) / sd: one pass over the samples (sums of
// I, I^2 and g I) gives the step; the position moves by -delta. Positions are pixels of the
// image given (pixel centres at integers, OpenCV's convention).
enum class AlignStatus { kAligned, kBorder, kTexture, kNoConvergence };

struct PatchAlignOptions {
  int max_iterations = 10;
  float convergence_px = 0.03f;
  // A step under 5x the tolerance at the last iteration still counts as converged.
  float min_texture = 0.02f;  // smaller Hessian eigenvalue per sample of the normalised template
};

class PatchTemplate {
 public:
  explicit PatchTemplate(int max_half_size);

  // Samples the template around ka in gray_a (half size h <= max_half_size). kBorder when the
  // patch leaves the image, kTexture when it has no texture in both directions. A warp that moves
  // no sample by more than identity_tolerance_px is taken as the identity (A's patch read on a
  // grid, several times faster than the warped read).
  AlignStatus Build(const cv::Mat& gray_a, const Eigen::Vector2f& ka, const Eigen::Matrix2f& inv,
                    int h, float min_texture, float identity_tolerance_px = 0.05f);

  // Aligns the built template in gray_b from start. *xy receives the position (kAligned) or the
  // last estimate (kNoConvergence); kBorder when the patch left image B. *correlation (when
  // given) receives the zero-normalised cross-correlation at the last sampled position (within
  // the last step, under 5x convergence_px, of *xy when aligned).
  AlignStatus Align(const cv::Mat& gray_b, const Eigen::Vector2f& start,
                    const PatchAlignOptions& options, Eigen::Vector2f* xy, int64_t* iterations,
                    float* correlation = nullptr);

  // Zero-normalised cross-correlation in [-1, 1] of the template with B's patch centred at xy;
  // -2 when that patch leaves the image or is flat.
  float Correlation(const cv::Mat& gray_b, const Eigen::Vector2f& xy);

  int half_size() const { return h_; }

 private:
  int max_half_;
  int h_ = 0;
  std::vector<float> ring_, t_, gx_, gy_, target_, xs_, ys_;
  float h00_ = 0, h01_ = 0, h11_ = 0, gsum_x_ = 0, gsum_y_ = 0, gt_x_ = 0, gt_y_ = 0;
};

// True when every point (cx, cy) + offset, offsets spanning [min, max], can be sampled bilinearly.
inline bool BoxInside(const cv::Mat& img, float cx, float cy, float min_x, float max_x, float min_y,
                      float max_y) {
  return cx + min_x >= 0.0f && cy + min_y >= 0.0f && cx + max_x < img.cols - 1.001f &&
         cy + max_y < img.rows - 1.001f;
}

}  // namespace imumatch
