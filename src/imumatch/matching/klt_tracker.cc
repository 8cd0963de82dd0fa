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
  IMUMATCH_CHECK(max_segment_starts >= 1 && max_segment_starts <= max_segment_seeds,
                 "max_segment_starts=" << max_segment_starts);
  IMUMATCH_CHECK(std::isfinite(ambiguity_margin) && ambiguity_margin >= 0.0,
                 "ambiguity_margin=" << ambiguity_margin);
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
    case TrackOutcome::kAmbiguous:
      return "ambiguous";
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
    case TrackOutcome::kAmbiguous:
      ++ambiguous;
      break;
  }
}

int TrackStats::OutcomeSum() const {
  return tracked + no_prediction + border + texture + no_convergence + forward_backward +
         low_correlation + outside_window + ambiguous;
}

std::string TrackStats::ToString() const {
  std::ostringstream s;
  s << "queries=" << queries << " tracked=" << tracked << " no_prediction=" << no_prediction
    << " border=" << border << " texture=" << texture << " no_convergence=" << no_convergence
    << " forward_backward=" << forward_backward << " low_correlation=" << low_correlation
    << " outside_window=" << outside_window << " ambiguous=" << ambiguous;
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
  PatchAlignOptions coarse = align;
  coarse.max_iterations = std::min(options.max_iterations, 10);
  coarse.convergence_px = std::max(align.convergence_px, 0.05f);
  const float max_fb2 =
      static_cast<float>(options.max_forward_backward_px * options.max_forward_backward_px);
  // One template per pyramid level, built once per keypoint and aligned from every seed.
  constexpr int kMaxHalf = 15;
  const int max_half = std::min(2 * h, kMaxHalf);
  std::vector<PatchTemplate> tpl(static_cast<size_t>(top + 1), PatchTemplate(max_half));
  std::vector<AlignStatus> built(static_cast<size_t>(top + 1));
  PatchTemplate back(max_half);
  TrackResult result;
  result.outcomes.resize(keypoints_a.size());
  result.correlation.assign(keypoints_a.size(), -2.0f);
  std::vector<Eigen::Vector2f> seeds;
  std::vector<float> seed_corr;
  std::vector<int> starts;
  std::vector<Eigen::Vector2f> start_pos;
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
    // The starting level: the prediction's uncertainty within the patch's reach there.
    const float radius = PredictionRadius(p);
    int level = 0;
    if (radius > static_cast<float>(h)) {
      level = std::min(top, static_cast<int>(std::ceil(std::log2(radius / static_cast<float>(h)))));
    }
    // Seeds in B's image pixels: the prediction, or points along the epipolar segment 2 px apart
    // at the level where they are compared (coarser while they would be too many).
    seeds.clear();
    int seed_level = level;
    if (p.status == PredictionStatus::kWithDepth) {
      seeds.push_back(undistorter.ToImage(p.uv.cast<double>()).cast<float>());
    } else {
      const Eigen::Vector2f d = p.segment_end - p.segment_start;
      const float length = d.norm();
      auto count = [&](int l) {
        return 1 + static_cast<int>(std::ceil(length / (2.0f * (1 << l))));
      };
      while (seed_level < top && count(seed_level) > options.max_segment_seeds) ++seed_level;
      const int n = std::min(options.max_segment_seeds, count(seed_level));
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
    // Jacobians at A's keypoint and at the (middle) seed.
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
    const int levels = std::max(level, seed_level);
    // A patch without texture in both directions at full resolution (a corner found at a coarse
    // scale, the smooth centre of a blob) is tried again at twice the size.
    int hk = h;
    for (int attempt = 0; attempt < 2; ++attempt) {
      for (int l = 0; l <= levels; ++l) {
        // A coarse level only starts the next one: a quarter-pixel warp error is no matter there.
        built[static_cast<size_t>(l)] = tpl[static_cast<size_t>(l)].Build(
            a.levels[static_cast<size_t>(l)], ka / static_cast<float>(1 << l), inv, hk,
            align.min_texture, l == 0 ? 0.05f : 0.25f);
      }
      if (built[0] != AlignStatus::kTexture || 2 * h > kMaxHalf) break;
      hk = 2 * h;
    }
    if (built[0] != AlignStatus::kAligned) {
      finish(built[0] == AlignStatus::kBorder ? TrackOutcome::kBorder : TrackOutcome::kTexture);
      continue;
    }
    // Coarse to fine from a seed: a level whose patch leaves an image or has no texture is
    // skipped; the finest level decides.
    // Coarse levels need no hundredth of a pixel: the next level refines.
    auto descend = [&](Eigen::Vector2f pos, int from, int to, float* corr) {
      for (int l = from; l >= std::max(to, 1); --l) {
        if (built[static_cast<size_t>(l)] != AlignStatus::kAligned) continue;
        const float scale = static_cast<float>(1 << l);
        Eigen::Vector2f xy;
        const AlignStatus st = tpl[static_cast<size_t>(l)].Align(
            b.levels[static_cast<size_t>(l)], pos / scale, coarse, &xy, &result.stats.iterations);
        if (st == AlignStatus::kAligned || st == AlignStatus::kNoConvergence) pos = xy * scale;
      }
      if (to > 0) return std::make_pair(AlignStatus::kAligned, pos);
      Eigen::Vector2f xy;
      float c0 = -2.0f;
      const AlignStatus st =
          tpl[0].Align(b.levels[0], pos, align, &xy, &result.stats.iterations, &c0);
      *corr = st == AlignStatus::kAligned ? c0 : -2.0f;
      return std::make_pair(st, xy);
    };
    // Starts: the seed, or the best-correlating local maxima along the segment.
    starts.clear();
    if (seeds.size() == 1) {
      starts.push_back(0);
    } else {
      const int sl =
          built[static_cast<size_t>(seed_level)] == AlignStatus::kAligned ? seed_level : 0;
      const float scale = static_cast<float>(1 << sl);
      seed_corr.resize(seeds.size());
      for (size_t k = 0; k < seeds.size(); ++k) {
        seed_corr[k] = tpl[static_cast<size_t>(sl)].Correlation(b.levels[static_cast<size_t>(sl)],
                                                                seeds[k] / scale);
      }
      for (size_t k = 0; k < seeds.size(); ++k) {
        const bool left = k == 0 || seed_corr[k] >= seed_corr[k - 1];
        const bool right = k + 1 == seeds.size() || seed_corr[k] > seed_corr[k + 1];
        if (left && right && seed_corr[k] > -2.0f) starts.push_back(static_cast<int>(k));
      }
      std::sort(starts.begin(), starts.end(), [&](int x, int y) {
        return seed_corr[static_cast<size_t>(x)] > seed_corr[static_cast<size_t>(y)];
      });
      if (static_cast<int>(starts.size()) > options.max_segment_starts) {
        starts.resize(static_cast<size_t>(options.max_segment_starts));
      }
      if (starts.empty()) starts.push_back(static_cast<int>(seeds.size() / 2));
    }
    // Every start descends; the best correlation wins. Another converged position more than a
    // pixel away that correlates nearly as well makes the track ambiguous (a repeated texture
    // along the epipolar line).
    AlignStatus status = AlignStatus::kNoConvergence;
    Eigen::Vector2f pos = seeds[0];
    float c = -2.0f, rival = -2.0f;
    const int from = std::max(level, seed_level);
    // Starts that meet at the coarsest level (within a pixel there) continue as one.
    start_pos.clear();
    for (int k : starts) {
      Eigen::Vector2f q = seeds[static_cast<size_t>(k)];
      if (from > 0) q = descend(q, from, from, nullptr).second;
      const float merge = static_cast<float>(1 << from);
      bool seen = false;
      for (const Eigen::Vector2f& o : start_pos)
        seen = seen || (q - o).squaredNorm() < merge * merge;
      if (!seen) start_pos.push_back(q);
    }
    for (const Eigen::Vector2f& q : start_pos) {
      float corr = -2.0f;
      const auto [st, xy] = descend(q, from - 1, 0, &corr);
      if (st != AlignStatus::kAligned) {
        if (status != AlignStatus::kAligned && st == AlignStatus::kBorder) status = st;
        continue;
      }
      if (status == AlignStatus::kAligned && (xy - pos).squaredNorm() <= 1.0f) continue;
      if (corr > c) {
        rival = c;
        c = corr;
        pos = xy;
      } else {
        rival = std::max(rival, corr);
      }
      status = AlignStatus::kAligned;
    }
    if (status != AlignStatus::kAligned) {
      finish(status == AlignStatus::kBorder ? TrackOutcome::kBorder : TrackOutcome::kNoConvergence);
      continue;
    }
    if (!undistorter.camera().InField(pos.cast<double>())) {  // beyond a fisheye's field of view
      finish(TrackOutcome::kBorder);
      continue;
    }
    result.correlation[i] = c;
    if (!(c >= static_cast<float>(options.min_correlation))) {
      finish(TrackOutcome::kLowCorrelation);
      continue;
    }
    if (rival >= c - static_cast<float>(options.ambiguity_margin)) {
      finish(TrackOutcome::kAmbiguous);
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
    // Compared with max_forward_backward_px only: a quarter-pixel warp error is no matter.
    AlignStatus bs = back.Build(b.levels[0], pos, affine, hk, 0.0f, 0.25f);
    if (bs == AlignStatus::kAligned) {
      // Only compared with max_forward_backward_px: a coarse convergence does.
      bs = back.Align(a.levels[0], ka, coarse, &back_xy, &result.stats.iterations);
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

std::vector<KeypointPrediction> PredictionsOfFailedTracks(
    const std::vector<KeypointPrediction>& predictions, const TrackResult& tracks) {
  IMUMATCH_CHECK(tracks.outcomes.size() == predictions.size(),
                 tracks.outcomes.size()
                     << " track outcomes for " << predictions.size() << " predictions");
  std::vector<KeypointPrediction> rest = predictions;
  for (size_t i = 0; i < rest.size(); ++i) {
    if (tracks.outcomes[i] == TrackOutcome::kTracked) rest[i].status = PredictionStatus::kInvalid;
  }
  return rest;
}

}  // namespace imumatch
