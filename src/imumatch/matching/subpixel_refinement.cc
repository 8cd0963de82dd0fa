#include "imumatch/matching/subpixel_refinement.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "imumatch/core/error.h"
#include "imumatch/matching/patch_alignment.h"

namespace imumatch {

void SubpixelOptions::Check() const {
  IMUMATCH_CHECK(half_size >= 2 && half_size <= 15, "half_size=" << half_size);
  IMUMATCH_CHECK(max_iterations >= 1 && max_iterations <= 100, "max_iterations=" << max_iterations);
  IMUMATCH_CHECK(std::isfinite(convergence_px) && convergence_px > 0.0,
                 "convergence_px=" << convergence_px);
  IMUMATCH_CHECK(std::isfinite(max_shift_px) && max_shift_px > 0.0,
                 "max_shift_px=" << max_shift_px);
  IMUMATCH_CHECK(std::isfinite(min_texture) && min_texture >= 0.0, "min_texture=" << min_texture);
  IMUMATCH_CHECK(retry_min_correlation >= -1.0 && retry_min_correlation <= 1.0,
                 "retry_min_correlation=" << retry_min_correlation);
}

namespace {

// Builds A's template around ka and aligns it in B from kb.
AlignStatus AlignPatch(PatchTemplate& tpl, const cv::Mat& gray_a, const cv::Mat& gray_b,
                       const Eigen::Vector2f& ka, const Eigen::Vector2f& kb,
                       const Eigen::Matrix2f& inv, int h, const SubpixelOptions& options,
                       Eigen::Vector2f* xy, int64_t* iterations) {
  PatchAlignOptions align;
  align.max_iterations = options.max_iterations;
  align.convergence_px = static_cast<float>(options.convergence_px);
  align.min_texture = static_cast<float>(options.min_texture);
  const AlignStatus built = tpl.Build(gray_a, ka, inv, h, align.min_texture);
  if (built != AlignStatus::kAligned) return built;
  return tpl.Align(gray_b, kb, align, xy, iterations);
}

}  // namespace

Eigen::Matrix2f PatchWarpInImage(const KeypointPrediction& prediction, const PinholeCamera& camera,
                                 const Eigen::Vector2f& pa, const Eigen::Vector2f& pb) {
  if (!prediction.HasWindow() || !prediction.local_affine.allFinite()) {
    return Eigen::Matrix2f::Identity();
  }
  if (!camera.HasDistortion()) return prediction.local_affine;
  return (camera.IdealFromPixelJacobian(pb.cast<double>()).inverse() *
          prediction.local_affine.cast<double>() * camera.IdealFromPixelJacobian(pa.cast<double>()))
      .cast<float>();
}

// The alignment itself: patch_alignment.h.
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
  const float max_shift2 = static_cast<float>(options.max_shift_px * options.max_shift_px);
  PatchTemplate tpl(2 * options.half_size);
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
    const Eigen::Matrix2f affine =
        predictions.empty() ? Eigen::Matrix2f::Identity()
                            : PatchWarpInImage(predictions[static_cast<size_t>(m.query_idx)],
                                               camera, Eigen::Vector2f(ka.pt.x, ka.pt.y),
                                               Eigen::Vector2f(kb.pt.x, kb.pt.y));
    const float det_a = affine.determinant();
    if (!(std::fabs(det_a) > 1e-3f)) {
      ++stats.failed_texture;  // a degenerate warp: nothing to align
      continue;
    }
    const Eigen::Matrix2f inv = affine.inverse();  // B offset -> A offset
    // A flat patch (the centre of a blob: SURF, AKAZE) is tried again at twice the size, where
    // the blob's edges give it texture. So is a patch that drifted (no convergence, or farther
    // than max_shift_px): 9 x 9 samples of a repetitive or edge-like neighbourhood can slide
    // along it, four times the samples pin the position. A second chance must show its patch:
    // the larger patch must align within max_shift_px and correlate (ZNCC) at least
    // retry_min_correlation there, else the match stays unaligned.
    Eigen::Vector2f xy;
    const Eigen::Vector2f pa(ka.pt.x, ka.pt.y), pb(kb.pt.x, kb.pt.y);
    AlignStatus r = AlignPatch(tpl, gray_a, gray_b, pa, pb, inv, options.half_size, options, &xy,
                               &stats.iterations);
    const bool drifted = r == AlignStatus::kNoConvergence ||
                         (r == AlignStatus::kAligned && (xy - pb).squaredNorm() > max_shift2);
    if (r == AlignStatus::kTexture || (drifted && options.retry_drifted_larger)) {
      r = AlignPatch(tpl, gray_a, gray_b, pa, pb, inv, 2 * options.half_size, options, &xy,
                     &stats.iterations);
      if (drifted) {
        const bool shown = r == AlignStatus::kAligned && (xy - pb).squaredNorm() <= max_shift2 &&
                           tpl.Correlation(gray_b, xy) >= options.retry_min_correlation;
        r = shown ? AlignStatus::kAligned : AlignStatus::kNoConvergence;
        stats.recovered_larger += shown ? 1 : 0;
      }
    }
    if (r == AlignStatus::kBorder) {
      ++stats.failed_border;
      continue;
    }
    if (r == AlignStatus::kTexture) {
      ++stats.failed_texture;
      continue;
    }
    if (r == AlignStatus::kNoConvergence || (xy - pb).squaredNorm() > max_shift2) {
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
