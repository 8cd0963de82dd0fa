#include "imumatch/matching/klt_tracker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/LU>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "imumatch/core/error.h"
#include "imumatch/matching/patch_alignment.h"

namespace imumatch {

TrackingPyramid TrackingPyramid::Build(const cv::Mat& gray, int max_level) {
  IMUMATCH_CHECK(!gray.empty() && gray.type() == CV_8UC1,
                 "tracking needs a non-empty 8-bit gray image");
  IMUMATCH_CHECK(max_level >= 0 && max_level <= 8, "max_level=" << max_level);
  TrackingPyramid p;
  p.levels.push_back(gray);
  for (int l = 1; l <= max_level; ++l) {
    const cv::Mat& prev = p.levels.back();
    if (prev.cols < 16 || prev.rows < 16) break;
    cv::Mat next;
    cv::pyrDown(prev, next);
    p.levels.push_back(next);
  }
  return p;
}

void KltOptions::Check() const {
  IMUMATCH_CHECK(half_size >= 2 && half_size <= 15, "half_size=" << half_size);
  IMUMATCH_CHECK(max_level >= 0 && max_level <= 8, "max_level=" << max_level);
  IMUMATCH_CHECK(max_iterations >= 1 && max_iterations <= 100, "max_iterations=" << max_iterations);
  IMUMATCH_CHECK(std::isfinite(convergence_px) && convergence_px > 0.0,
                 "convergence_px=" << convergence_px);
  IMUMATCH_CHECK(std::isfinite(min_texture) && min_texture >= 0.0, "min_texture=" << min_texture);
  IMUMATCH_CHECK(std::isfinite(max_forward_backward_px) && max_forward_backward_px > 0.0,
                 "max_forward_backward_px=" << max_forward_backward_px);
  IMUMATCH_CHECK(min_correlation >= -1.0 && min_correlation <= 1.0,
                 "min_correlation=" << min_correlation);
  IMUMATCH_CHECK(max_segment_seeds >= 1 && max_segment_seeds <= 1000,
                 "max_segment_seeds=" << max_segment_seeds);
}

const char* ToString(TrackOutcome outcome) {
  switch (outcome) {
    case TrackOutcome::kTracked:
      return "tracked";
    case TrackOutcome::kNoPrediction:
      return "no_prediction";
    case TrackOutcome::kBorder:
      return "border";
    case TrackOutcome::kTexture:
      return "texture";
    case TrackOutcome::kNoConvergence:
      return "no_convergence";
    case TrackOutcome::kForwardBackward:
      return "forward_backward";
    case TrackOutcome::kLowCorrelation:
      return "low_correlation";
    case TrackOutcome::kOutsideWindow:
      return "outside_window";
  }
  return "?";
}

void TrackStats::Count(TrackOutcome outcome) {
  ++queries;
  switch (outcome) {
    case TrackOutcome::kTracked:
      ++tracked;
      break;
    case TrackOutcome::kNoPrediction:
      ++no_prediction;
      break;
    case TrackOutcome::kBorder:
      ++border;
      break;
    case TrackOutcome::kTexture:
      ++texture;
      break;
    case TrackOutcome::kNoConvergence:
      ++no_convergence;
      break;
    case TrackOutcome::kForwardBackward:
      ++forward_backward;
      break;
    case TrackOutcome::kLowCorrelation:
      ++low_correlation;
      break;
    case TrackOutcome::kOutsideWindow:
      ++outside_window;
      break;
  }
}

int TrackStats::OutcomeSum() const {
  return tracked + no_prediction + border + texture + no_convergence + forward_backward +
         low_correlation + outside_window;
}

std::string TrackStats::ToString() const {
  std::ostringstream s;
  s << "queries=" << queries << " tracked=" << tracked << " no_prediction=" << no_prediction
    << " border=" << border << " texture=" << texture << " no_convergence=" << no_convergence
    << " forward_backward=" << forward_backward << " low_correlation=" << low_correlation
    << " outside_window=" << outside_window;
  return s.str();
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

void Accept(int query, const Eigen::Vector2f& seed, const Eigen::Vector2f& xy, float correlation,
            TrackResult& result) {
  Match m;
  m.query_idx = query;
  m.train_idx = -1;
  m.distance = 1.0f - correlation;
  m.predicted_uv = seed;
  m.refined_uv_b = xy;
  result.tracks.push_back(m);
}

// The uncertainty a track must cover from its seed: the window's half size (with depth) or the
// capsule's radius around the segment (without).
float PredictionRadius(const KeypointPrediction& p) {
  if (p.status == PredictionStatus::kWithoutDepth) return p.radius;
  return 0.5f * std::max(p.max_x - p.min_x, p.max_y - p.min_y);
}

}  // namespace

TrackResult TrackSeeded(const TrackingPyramid& a, const TrackingPyramid& b,
                        const std::vector<cv::KeyPoint>& keypoints_a,
                        const std::vector<KeypointPrediction>& predictions,
                        const PixelUndistorter& undistorter, const KltOptions& options) {
  options.Check();
  IMUMATCH_CHECK(!a.levels.empty() && !b.levels.empty(), "empty pyramid");
  IMUMATCH_CHECK(
      a.levels[0].size() == b.levels[0].size(),
      "frames of different sizes: " << a.levels[0].size() << " and " << b.levels[0].size());
  IMUMATCH_CHECK(predictions.size() == keypoints_a.size(),
                 predictions.size() << " predictions for " << keypoints_a.size() << " keypoints");
  const int h = options.half_size;
  const int top = std::min({options.max_level, static_cast<int>(a.levels.size()) - 1,
                            static_cast<int>(b.levels.size()) - 1});
  PatchAlignOptions align;
  align.max_iterations = options.max_iterations;
  align.convergence_px = static_cast<float>(options.convergence_px);
  align.min_texture = static_cast<float>(options.min_texture);
  const float min_texture = align.min_texture;
  const float max_fb2 =
      static_cast<float>(options.max_forward_backward_px * options.max_forward_backward_px);
  PatchTemplate tpl(h), back(h);
  TrackResult result;
  result.outcomes.resize(keypoints_a.size());
  result.correlation.assign(keypoints_a.size(), -2.0f);
  std::vector<Eigen::Vector2f> seeds;
  for (size_t i = 0; i < keypoints_a.size(); ++i) {
    auto finish = [&](TrackOutcome outcome) {
      result.outcomes[i] = outcome;
      result.stats.Count(outcome);
    };
    const KeypointPrediction& p = predictions[i];
    const Eigen::Vector2f ka(keypoints_a[i].pt.x, keypoints_a[i].pt.y);
    if (!p.HasWindow() || !ka.allFinite()) {
      finish(TrackOutcome::kNoPrediction);
      continue;
    }
    // Seeds in B's image pixels.
    seeds.clear();
    const float radius = PredictionRadius(p);
    int level = 0;
    if (radius > static_cast<float>(h)) {
      level = std::min(top, static_cast<int>(std::ceil(std::log2(radius / static_cast<float>(h)))));
    }
    if (p.status == PredictionStatus::kWithDepth) {
      seeds.push_back(undistorter.ToImage(p.uv.cast<double>()).cast<float>());
    } else {
      const Eigen::Vector2f d = p.segment_end - p.segment_start;
      const float spacing = static_cast<float>(h) * static_cast<float>(1 << level);
      const int n =
          std::min(options.max_segment_seeds, 1 + static_cast<int>(std::ceil(d.norm() / spacing)));
      for (int k = 0; k < n; ++k) {
        const float s = n == 1 ? 0.5f : static_cast<float>(k) / static_cast<float>(n - 1);
        seeds.push_back(
            undistorter.ToImage((p.segment_start + s * d).cast<double>()).cast<float>());
      }
    }
    if (!seeds[0].allFinite()) {
      finish(TrackOutcome::kNoPrediction);
      continue;
    }
    // The patch's warp in image pixels: the predicted affine map, conjugated by the lens's local
    // Jacobians at A's keypoint and at the seed.
    Eigen::Matrix2f affine = Eigen::Matrix2f::Identity();
    if (options.warp_patch && p.local_affine.allFinite()) {
      Eigen::Matrix2d ja, jb;
      undistorter.ToIdeal(ka.cast<double>(), &ja);
      undistorter.ToIdeal(seeds[seeds.size() / 2].cast<double>(), &jb);
      affine = (jb.inverse() * p.local_affine.cast<double>() * ja).cast<float>();
    }
    if (!affine.allFinite() || !(std::fabs(affine.determinant()) > 1e-3f)) {
      affine = Eigen::Matrix2f::Identity();
    }
    const Eigen::Matrix2f inv = affine.inverse();  // B offset -> A offset
    // Coarse to fine. A level whose patch leaves the image or has no texture is skipped; the
    // finest level decides.
    Eigen::Vector2f pos = seeds[0];
    TrackOutcome failed = TrackOutcome::kTracked;
    bool seeded = seeds.size() == 1;
    for (int l = level; l >= 0; --l) {
      const float scale = 1.0f / static_cast<float>(1 << l);
      const AlignStatus built =
          tpl.Build(a.levels[static_cast<size_t>(l)], ka * scale, inv, h, min_texture);
      if (built != AlignStatus::kAligned) {
        if (l == 0)
          failed = built == AlignStatus::kBorder ? TrackOutcome::kBorder : TrackOutcome::kTexture;
        continue;
      }
      const cv::Mat& img_b = b.levels[static_cast<size_t>(l)];
      if (!seeded) {
        float best = -3.0f;
        for (const Eigen::Vector2f& s : seeds) {
          const float c = tpl.Correlation(img_b, s * scale);
          if (c > best) {
            best = c;
            pos = s;
          }
        }
        seeded = true;
      }
      Eigen::Vector2f xy;
      const AlignStatus st = tpl.Align(img_b, pos * scale, align, &xy, &result.stats.iterations);
      if (l > 0) {
        if (st == AlignStatus::kAligned || st == AlignStatus::kNoConvergence) pos = xy / scale;
        continue;
      }
      if (st == AlignStatus::kBorder) {
        failed = TrackOutcome::kBorder;
      } else if (st == AlignStatus::kNoConvergence) {
        failed = TrackOutcome::kNoConvergence;
      } else {
        pos = xy;
      }
    }
    if (failed != TrackOutcome::kTracked) {
      finish(failed);
      continue;
    }
    // tpl holds the finest level's template.
    const float c = tpl.Correlation(b.levels[0], pos);
    result.correlation[i] = c;
    if (!(c >= static_cast<float>(options.min_correlation))) {
      finish(TrackOutcome::kLowCorrelation);
      continue;
    }
    if (options.gate_by_window) {
      const Eigen::Vector2f ideal = undistorter.ToIdeal(pos.cast<double>()).cast<float>();
      if (!p.Contains(ideal.x(), ideal.y())) {
        finish(TrackOutcome::kOutsideWindow);
        continue;
      }
    }
    // Backward: B's patch at the track, warped back into A, aligned in A from A's keypoint.
    Eigen::Vector2f back_xy;
    AlignStatus bs = back.Build(b.levels[0], pos, affine, h, 0.0f);
    if (bs == AlignStatus::kAligned) {
      bs = back.Align(a.levels[0], ka, align, &back_xy, &result.stats.iterations);
    }
    if (bs == AlignStatus::kBorder) {
      finish(TrackOutcome::kBorder);
      continue;
    }
    if (bs != AlignStatus::kAligned || (back_xy - ka).squaredNorm() > max_fb2) {
      finish(TrackOutcome::kForwardBackward);
      continue;
    }
    finish(TrackOutcome::kTracked);
    Accept(static_cast<int>(i), seeds.size() == 1 ? seeds[0] : pos, pos, c, result);
  }
  return result;
}

TrackResult TrackOpenCvLk(const cv::Mat& gray_a, const cv::Mat& gray_b,
                          const std::vector<cv::KeyPoint>& keypoints_a, const KltOptions& options) {
  options.Check();
  IMUMATCH_CHECK(
      !gray_a.empty() && !gray_b.empty() && gray_a.type() == CV_8UC1 && gray_b.type() == CV_8UC1,
      "tracking needs non-empty 8-bit gray images");
  IMUMATCH_CHECK(gray_a.size() == gray_b.size(),
                 "frames of different sizes: " << gray_a.size() << " and " << gray_b.size());
  TrackResult result;
  result.outcomes.assign(keypoints_a.size(), TrackOutcome::kNoPrediction);
  result.correlation.assign(keypoints_a.size(), -2.0f);
  if (keypoints_a.empty()) return result;
  std::vector<cv::Point2f> pa, pb, back;
  cv::KeyPoint::convert(keypoints_a, pa);
  const cv::Size win(2 * options.half_size + 1, 2 * options.half_size + 1);
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                  options.max_iterations, options.convergence_px);
  std::vector<uchar> status, back_status;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(gray_a, gray_b, pa, pb, status, err, win, options.max_level, criteria);
  back = pa;  // the backward pass starts at A's keypoints (VINS-Fusion's reverse check)
  cv::calcOpticalFlowPyrLK(gray_b, gray_a, pb, back, back_status, err, win, options.max_level,
                           criteria, cv::OPTFLOW_USE_INITIAL_FLOW);
  const float max_fb2 =
      static_cast<float>(options.max_forward_backward_px * options.max_forward_backward_px);
  PatchTemplate tpl(options.half_size);
  PatchAlignOptions align;
  for (size_t i = 0; i < pa.size(); ++i) {
    auto finish = [&](TrackOutcome outcome) {
      result.outcomes[i] = outcome;
      result.stats.Count(outcome);
    };
    const Eigen::Vector2f ka(pa[i].x, pa[i].y), xy(pb[i].x, pb[i].y);
    if (!status[i] || !xy.allFinite() ||
        !BoxInside(gray_b, xy.x(), xy.y(), 0.0f, 0.0f, 0.0f, 0.0f)) {
      finish(TrackOutcome::kNoConvergence);
      continue;
    }
    const float dx = back[i].x - pa[i].x, dy = back[i].y - pa[i].y;
    if (!back_status[i] || !(dx * dx + dy * dy <= max_fb2)) {
      finish(TrackOutcome::kForwardBackward);
      continue;
    }
    const AlignStatus built =
        tpl.Build(gray_a, ka, Eigen::Matrix2f::Identity(), options.half_size, 0.0f);
    const float c = built == AlignStatus::kAligned ? tpl.Correlation(gray_b, xy) : -2.0f;
    result.correlation[i] = c;
    if (options.min_correlation > -1.0 && !(c >= static_cast<float>(options.min_correlation))) {
      finish(TrackOutcome::kLowCorrelation);
      continue;
    }
    finish(TrackOutcome::kTracked);
    Accept(static_cast<int>(i), Eigen::Vector2f::Constant(kNaN), xy, c, result);
  }
  return result;
}

}  // namespace imumatch
