#include "imumatch/eval/ground_truth.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/statistics.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

Eigen::Vector2d Undistorted(const PinholeCamera& camera, const Eigen::Vector2d& uv) {
  const Eigen::Vector2d xy = camera.PixelToNormalized(uv);
  return {camera.fx * xy.x() + camera.cx, camera.fy * xy.y() + camera.cy};
}

}  // namespace

void GroundTruthOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(min_depth) && min_depth >= 0.0, "min_depth = " << min_depth);
  IMUMATCH_CHECK(max_depth > min_depth, "max_depth = " << max_depth);
  IMUMATCH_CHECK(std::isfinite(max_candidate_px) && max_candidate_px > 0.0,
                 "max_candidate_px = " << max_candidate_px);
}

void AutoThresholdOptions::Check() const {
  IMUMATCH_CHECK(gate_px > 0.0 && std::isfinite(gate_px), "gate_px = " << gate_px);
  IMUMATCH_CHECK(k >= 0.0 && std::isfinite(k), "k = " << k);
  IMUMATCH_CHECK(min_px > 0.0 && max_px >= min_px, "min_px/max_px = " << min_px << "/" << max_px);
  IMUMATCH_CHECK(min_samples >= 1, "min_samples = " << min_samples);
  IMUMATCH_CHECK(fallback_px > 0.0, "fallback_px = " << fallback_px);
}

Eigen::Matrix3d FundamentalMatrix(const PinholeCamera& camera, const Rigid3d& cam_b_from_cam_a) {
  const Eigen::Matrix3d k = camera.K();
  const Eigen::Matrix3d k_inv = k.inverse();
  const Eigen::Matrix3d essential =
      Hat(cam_b_from_cam_a.translation) * cam_b_from_cam_a.RotationMatrix();
  return k_inv.transpose() * essential * k_inv;
}

double EpipolarDistance(const Eigen::Matrix3d& f_b_from_a, const Eigen::Vector2d& x_a,
                        const Eigen::Vector2d& x_b) {
  const Eigen::Vector3d line = f_b_from_a * x_a.homogeneous();
  const double norm = std::hypot(line.x(), line.y());
  if (!(norm > 0.0)) return std::numeric_limits<double>::infinity();
  return std::abs(line.dot(x_b.homogeneous())) / norm;
}

PairGroundTruth::PairGroundTruth(const PinholeCamera& camera, const Rigid3d& cam_b_from_cam_a,
                                 const cv::Mat& depth_a,
                                 const std::vector<cv::KeyPoint>& keypoints_a,
                                 const std::vector<cv::KeyPoint>& keypoints_b,
                                 const GroundTruthOptions& options)
    : camera_(camera) {
  options.Check();
  camera.Check();
  fundamental_ = FundamentalMatrix(camera, cam_b_from_cam_a);
  const Eigen::Matrix3d k = camera.K();
  infinite_homography_ = k * cam_b_from_cam_a.RotationMatrix() * k.inverse();
  pure_rotation_ = cam_b_from_cam_a.translation.norm() < 1e-9;

  keypoints_a_undistorted_.reserve(keypoints_a.size());
  projected_.assign(keypoints_a.size(), std::nullopt);
  has_depth_.assign(keypoints_a.size(), 0);
  for (size_t i = 0; i < keypoints_a.size(); ++i) {
    const Eigen::Vector2d uv(keypoints_a[i].pt.x, keypoints_a[i].pt.y);
    keypoints_a_undistorted_.push_back(Undistorted(camera, uv));
    if (depth_a.empty()) continue;
    const double d = SampleDepth(depth_a, camera.depth_scale, keypoints_a[i].pt.x,
                                 keypoints_a[i].pt.y, DepthSampling::kNearest);
    if (!(d >= options.min_depth && d <= options.max_depth)) continue;
    ++num_with_depth_;
    has_depth_[i] = 1;
    const Eigen::Vector3d p_b = cam_b_from_cam_a * camera.Unproject(uv, d);
    projected_[i] = camera.Project(p_b);
  }
  keypoints_b_.reserve(keypoints_b.size());
  keypoints_b_undistorted_.reserve(keypoints_b.size());
  for (const cv::KeyPoint& kp : keypoints_b) {
    keypoints_b_.emplace_back(kp.pt.x, kp.pt.y);
    keypoints_b_undistorted_.push_back(Undistorted(camera, keypoints_b_.back()));
  }

  // Candidates: a brute-force radius search (n*m distance checks, cheap next to extraction).
  const double r2 = options.max_candidate_px * options.max_candidate_px;
  for (size_t i = 0; i < projected_.size(); ++i) {
    if (!projected_[i]) continue;
    const Eigen::Vector2d& p = *projected_[i];
    for (size_t j = 0; j < keypoints_b_.size(); ++j) {
      const double d2 = (keypoints_b_[j] - p).squaredNorm();
      if (d2 <= r2) {
        candidates_.push_back(
            {static_cast<int>(i), static_cast<int>(j), static_cast<float>(std::sqrt(d2))});
      }
    }
  }
  std::sort(candidates_.begin(), candidates_.end(), [](const GtCandidate& x, const GtCandidate& y) {
    if (x.distance_px != y.distance_px) return x.distance_px < y.distance_px;
    if (x.a != y.a) return x.a < y.a;
    return x.b < y.b;
  });
}

MatchResidual PairGroundTruth::Judge(int query_idx, int train_idx) const {
  IMUMATCH_CHECK(train_idx >= 0 && train_idx < static_cast<int>(keypoints_b_.size()),
                 "train_idx " << train_idx);
  return JudgeAt(query_idx, keypoints_b_[train_idx], &keypoints_b_undistorted_[train_idx]);
}

MatchResidual PairGroundTruth::JudgeAt(int query_idx, const Eigen::Vector2d& uv_b) const {
  return JudgeAt(query_idx, uv_b, nullptr);
}

MatchResidual PairGroundTruth::JudgeAt(int query_idx, const Eigen::Vector2d& uv_b,
                                       const Eigen::Vector2d* uv_b_undistorted) const {
  IMUMATCH_CHECK(query_idx >= 0 && query_idx < static_cast<int>(projected_.size()),
                 "query_idx " << query_idx);
  MatchResidual r;
  if (!uv_b.allFinite()) return {ResidualKind::kUnjudgeable, kInf};
  const auto& projected = projected_[query_idx];
  if (projected) {
    r.kind = ResidualKind::kDepth;
    r.residual_px = static_cast<float>((*projected - uv_b).norm());
    return r;
  }
  if (has_depth_[query_idx]) return {ResidualKind::kUnjudgeable, kInf};  // behind camera B
  const Eigen::Vector2d b_undistorted =
      uv_b_undistorted != nullptr ? *uv_b_undistorted : Undistorted(camera_, uv_b);
  double residual;
  if (pure_rotation_) {
    const Eigen::Vector3d h =
        infinite_homography_ * keypoints_a_undistorted_[query_idx].homogeneous();
    if (!(h.z() > 0.0)) return {ResidualKind::kUnjudgeable, kInf};
    residual = (h.hnormalized() - b_undistorted).norm();
  } else {
    residual = EpipolarDistance(fundamental_, keypoints_a_undistorted_[query_idx], b_undistorted);
  }
  if (!std::isfinite(residual)) return {ResidualKind::kUnjudgeable, kInf};
  r.kind = ResidualKind::kEpipolar;
  r.residual_px = static_cast<float>(residual);
  return r;
}

std::vector<MatchResidual> PairGroundTruth::Judge(const std::vector<Match>& matches) const {
  std::vector<MatchResidual> out;
  out.reserve(matches.size());
  for (const Match& m : matches) {
    out.push_back(m.refined_uv_b.allFinite() ? JudgeAt(m.query_idx, m.refined_uv_b.cast<double>())
                                             : Judge(m.query_idx, m.train_idx));
  }
  return out;
}

int CountPossibleCorrespondences(const std::vector<GtCandidate>& sorted_candidates,
                                 double threshold_px) {
  int max_a = -1, max_b = -1;
  for (const GtCandidate& c : sorted_candidates) {
    max_a = std::max(max_a, c.a);
    max_b = std::max(max_b, c.b);
  }
  std::vector<char> used_a(static_cast<size_t>(max_a + 1), 0);
  std::vector<char> used_b(static_cast<size_t>(max_b + 1), 0);
  int count = 0;
  for (const GtCandidate& c : sorted_candidates) {
    if (c.distance_px > threshold_px) break;
    if (used_a[c.a] || used_b[c.b]) continue;
    used_a[c.a] = used_b[c.b] = 1;
    ++count;
  }
  return count;
}

JudgedCounts CountCorrect(const std::vector<MatchResidual>& residuals, double threshold_px) {
  JudgedCounts c;
  c.matches = static_cast<int>(residuals.size());
  for (const MatchResidual& r : residuals) {
    const bool ok = r.CorrectAt(threshold_px);
    if (ok) ++c.correct;
    if (r.kind == ResidualKind::kDepth) {
      ++c.judged_by_depth;
      if (ok) ++c.correct_by_depth;
    }
  }
  c.wrong = c.matches - c.correct;
  return c;
}

AutoThreshold ComputeAutoThreshold(const std::vector<float>& depth_residuals_px,
                                   const AutoThresholdOptions& options) {
  options.Check();
  std::vector<double> kept;
  for (float r : depth_residuals_px) {
    if (std::isfinite(r) && r >= 0.0f && r < options.gate_px) kept.push_back(r);
  }
  AutoThreshold t;
  t.k = options.k;
  t.gate_px = options.gate_px;
  t.samples = static_cast<int>(kept.size());
  if (t.samples < options.min_samples) {
    t.fallback = true;
    t.threshold_px = options.fallback_px;
    return t;
  }
  t.median_px = Median(kept);
  std::vector<double> dev;
  dev.reserve(kept.size());
  for (double r : kept) dev.push_back(std::abs(r - t.median_px));
  t.mad_sigma_px = 1.4826 * Median(dev);
  const double raw = t.median_px + options.k * t.mad_sigma_px;
  t.threshold_px = std::clamp(raw, options.min_px, options.max_px);
  t.clamped = t.threshold_px != raw;
  return t;
}

std::string AutoThreshold::Describe() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  if (fallback) {
    out << "auto threshold: only " << samples << " depth residuals < " << gate_px
        << " px, fallback " << threshold_px << " px";
    return out.str();
  }
  out << "auto threshold " << threshold_px << " px = median " << median_px << " + " << k
      << " x MAD-sigma " << mad_sigma_px << " of " << samples
      << " ground-truth residuals of brute-force ratio-test matches (< " << gate_px << " px gate)"
      << (clamped ? ", clamped" : "");
  return out.str();
}

}  // namespace imumatch
