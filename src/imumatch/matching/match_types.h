#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace imumatch {

// The geometric part of a keypoint that matching needs, in plain types. angle_deg < 0 means "no
// orientation" (OpenCV's -1); size <= 0 means "no scale".
struct KeypointInfo {
  float x = 0.0f;
  float y = 0.0f;
  float angle_deg = -1.0f;
  float size = 0.0f;
  int octave = 0;
};
std::vector<KeypointInfo> ToKeypointInfos(const std::vector<cv::KeyPoint>& keypoints);

// One correspondence query (frame A) -> train (frame B). Every matcher of this module returns it.
// distance: Hamming bits or L2 (not squared), as OpenCV reports. second_distance: the runner-up
// candidate's distance (+inf when there was none). predicted_uv: the guided prediction in B (NaN
// for the baselines, which predict nothing).
struct Match {
  int query_idx = -1;
  int train_idx = -1;
  float distance = 0.0f;
  float second_distance = std::numeric_limits<float>::infinity();
  Eigen::Vector2f predicted_uv = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  // The matched position in B refined to sub-pixel accuracy against A's patch (image pixels;
  // RefineMatches), NaN when not refined: the keypoint of B is then the matched position.
  Eigen::Vector2f refined_uv_b = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
};

std::vector<cv::DMatch> ToDMatches(const std::vector<Match>& matches);

// Why each query keypoint of A ended with or without a match. Every query is counted in exactly
// one of the outcome fields (no_prediction ... matched), so they sum to `queries`.
struct MatchStats {
  int queries = 0;
  // How the prediction was made (informational, not outcomes).
  int predicted_with_depth = 0;
  int predicted_without_depth = 0;
  // Outcomes.
  int no_prediction = 0;           // invalid input (e.g. NaN position) or no-depth disabled
  int behind_camera = 0;           // the point (or whole depth range) lies behind camera B
  int outside_image = 0;           // predicted outside image B
  int no_candidate_in_window = 0;  // no keypoint of B inside the search region
  int orientation = 0;             // candidates in the window, none with a consistent angle
  int scale = 0;               // candidates with a consistent angle, none with a consistent size
  int distance_threshold = 0;  // best candidate's descriptor distance above the threshold
  int ratio_test = 0;          // best / second-best above the ratio
  int mutual = 0;              // B's best partner (reverse pass) is another keypoint of A
  int matched = 0;
  // Work done: grid points read by the window queries (inside the window or not), and descriptor
  // distances computed.
  int64_t points_scanned = 0;
  int64_t distances_computed = 0;

  int OutcomeSum() const;
  std::string ToString() const;
};

// How one query of the guided matcher ended (the per-query form of MatchStats' outcomes).
enum class QueryOutcome : uint8_t {
  kMatched,
  kNoPrediction,
  kBehindCamera,
  kOutsideImage,
  kNoCandidateInWindow,
  kOrientation,
  kScale,
  kDistanceThreshold,
  kRatioTest,
  kMutual,
};
const char* ToString(QueryOutcome outcome);

struct MatchResult {
  std::vector<Match> matches;
  MatchStats stats;
  std::vector<QueryOutcome> outcomes;  // guided matcher: one per query keypoint
  std::vector<cv::DMatch> ToDMatches() const { return imumatch::ToDMatches(matches); }
};

}  // namespace imumatch
