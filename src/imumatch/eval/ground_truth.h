#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/matching/match_types.h"

namespace imumatch {

// Ground-truth judging of matches between frames A and B, given the exact (or measured) relative
// pose cam_b_from_cam_a and A's depth image.
//
// A match (kp_a, kp_b) gets one residual in pixels:
//   - kDepth: kp_a has a depth d (sampled from A's depth image, nearest valid pixel of the 3x3
//     neighbourhood); the residual is |project(cam_b_from_cam_a * unproject(kp_a, d)) - kp_b|.
//   - kEpipolar: no depth; the residual is the distance of kp_b to the ground-truth epipolar line
//     of kp_a in B (undistorted pixels). This cannot see errors along the line, so it is a weaker
//     test; results say how many matches were judged that way. Without translation (|t| < 1e-9 m)
//     the infinite homography K R K^-1 is used instead (the residual is then a point distance).
//   - kUnjudgeable: the point lies behind camera B (depth case) or a coordinate is not finite.
// A match is correct when its residual is <= the threshold. Residuals are stored so the same
// matches can be re-judged at several thresholds without recomputing anything.
enum class ResidualKind : uint8_t { kDepth, kEpipolar, kUnjudgeable };

struct MatchResidual {
  ResidualKind kind = ResidualKind::kUnjudgeable;
  float residual_px = 0.0f;  // +inf for kUnjudgeable

  // Judged, and within threshold_px of where the ground truth puts the partner.
  bool CorrectAt(double threshold_px) const {
    return kind != ResidualKind::kUnjudgeable && residual_px <= threshold_px;
  }
};

// A candidate ground-truth correspondence: keypoint a of A (with depth) reprojects within
// distance_px of keypoint b of B.
struct GtCandidate {
  int a = -1;
  int b = -1;
  float distance_px = 0.0f;
};

struct GroundTruthOptions {
  // Depth readings outside [min_depth, max_depth] metres count as "no depth" (the same bounds as
  // PredictionOptions: far readings of a large room are real).
  double min_depth = 0.1;
  double max_depth = 100.0;
  // Candidates for the possible-correspondence count are kept up to this distance, so any
  // threshold up to it can be evaluated later.
  double max_candidate_px = 10.0;
  void Check() const;
};

// Precomputed ground truth of one frame pair for one set of keypoints.
class PairGroundTruth {
 public:
  // depth_a: CV_16U raw (camera.depth_scale units per metre) or CV_32F metres, or empty (no
  // depth: every match is judged epipolar, no possible correspondences).
  PairGroundTruth(const PinholeCamera& camera, const Rigid3d& cam_b_from_cam_a,
                  const cv::Mat& depth_a, const std::vector<cv::KeyPoint>& keypoints_a,
                  const std::vector<cv::KeyPoint>& keypoints_b,
                  const GroundTruthOptions& options = GroundTruthOptions());

  // Residual of one match / many matches (query_idx into keypoints_a, train_idx into keypoints_b).
  // The many-matches form judges Match::refined_uv_b instead of the keypoint of B when the match
  // was refined (finite).
  MatchResidual Judge(int query_idx, int train_idx) const;
  std::vector<MatchResidual> Judge(const std::vector<Match>& matches) const;
  // The residual of keypoint query_idx of A matched to an arbitrary position uv_b of B (pixels).
  MatchResidual JudgeAt(int query_idx, const Eigen::Vector2d& uv_b) const;

  // Ground-truth position in B of keypoint a (nullopt without depth or behind camera B).
  const std::optional<Eigen::Vector2d>& ProjectedInB(int a) const { return projected_[a]; }
  int num_with_depth() const { return num_with_depth_; }
  // All pairs (a, b) with the reprojection of a within max_candidate_px of b, sorted by distance.
  const std::vector<GtCandidate>& candidates() const { return candidates_; }

 private:
  MatchResidual JudgeAt(int query_idx, const Eigen::Vector2d& uv_b,
                        const Eigen::Vector2d* uv_b_undistorted) const;
  PinholeCamera camera_;
  Eigen::Matrix3d fundamental_;  // undistorted pixels A -> epipolar line in B
  Eigen::Matrix3d infinite_homography_;
  bool pure_rotation_ = false;
  std::vector<Eigen::Vector2d> keypoints_a_undistorted_;
  std::vector<Eigen::Vector2d> keypoints_b_;
  std::vector<Eigen::Vector2d> keypoints_b_undistorted_;
  std::vector<std::optional<Eigen::Vector2d>> projected_;
  std::vector<char> has_depth_;
  std::vector<GtCandidate> candidates_;
  int num_with_depth_ = 0;
};

// Number of one-to-one ground-truth correspondences at a threshold: candidates with
// distance <= threshold_px taken greedily by increasing distance, each keypoint used once.
int CountPossibleCorrespondences(const std::vector<GtCandidate>& sorted_candidates,
                                 double threshold_px);

// Point-to-line distance of (undistorted) pixel x_b to the epipolar line F * x_a.
double EpipolarDistance(const Eigen::Matrix3d& f_b_from_a, const Eigen::Vector2d& x_a,
                        const Eigen::Vector2d& x_b);

// F = K^-T [t]x R K^-1 for p_b = R p_a + t (pinhole part of the camera).
Eigen::Matrix3d FundamentalMatrix(const PinholeCamera& camera, const Rigid3d& cam_b_from_cam_a);

// Counts of a set of residuals at one threshold.
struct JudgedCounts {
  int matches = 0;
  int correct = 0;
  int wrong = 0;            // matches - correct (unjudgeable ones count as wrong)
  int judged_by_depth = 0;  // matches judged with depth (the rest: epipolar or unjudgeable)
  int correct_by_depth = 0;
};
JudgedCounts CountCorrect(const std::vector<MatchResidual>& residuals, double threshold_px);

// The automatic threshold for real data. Real ground truth (motion capture + Kinect depth) puts
// correct matches a few pixels off, so a fixed 1.5 px would call good matches false. From the
// depth residuals of a method that does not use the prediction (brute force + ratio test):
//   1. keep residuals below gate_px (20 px: far beyond any plausible correct match),
//   2. m = median, s = 1.4826 * MAD (the standard deviation of a Gaussian core),
//   3. threshold = clamp(m + k * s, min_px, max_px) with k = 3.
// Outliers inside the gate inflate m and s a little, making the threshold conservative (lenient).
struct AutoThresholdOptions {
  double gate_px = 20.0;
  double k = 3.0;
  double min_px = 2.0;
  double max_px = 10.0;
  int min_samples = 20;  // fewer residuals than this -> fallback_px
  double fallback_px = 3.0;
  void Check() const;
};
struct AutoThreshold {
  double threshold_px = 0.0;
  double median_px = 0.0;
  double mad_sigma_px = 0.0;  // 1.4826 * MAD
  int samples = 0;            // residuals used (after the gate)
  double k = 3.0;
  double gate_px = 20.0;
  bool clamped = false;
  bool fallback = false;
  std::string Describe() const;
};
AutoThreshold ComputeAutoThreshold(const std::vector<float>& depth_residuals_px,
                                   const AutoThresholdOptions& options = AutoThresholdOptions());

}  // namespace imumatch
