#include "imumatch/matching/match_types.h"

#include <sstream>

namespace imumatch {

std::vector<KeypointInfo> ToKeypointInfos(const std::vector<cv::KeyPoint>& keypoints) {
  std::vector<KeypointInfo> out(keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    out[i] = KeypointInfo{k.pt.x, k.pt.y, k.angle, k.size, k.octave};
  }
  return out;
}

std::vector<cv::DMatch> ToDMatches(const std::vector<Match>& matches) {
  std::vector<cv::DMatch> out;
  out.reserve(matches.size());
  for (const Match& m : matches) out.emplace_back(m.query_idx, m.train_idx, m.distance);
  return out;
}

int MatchStats::OutcomeSum() const {
  return no_prediction + behind_camera + outside_image + no_candidate_in_window + orientation +
         scale + distance_threshold + ratio_test + mutual + matched;
}

const char* ToString(QueryOutcome outcome) {
  switch (outcome) {
    case QueryOutcome::kMatched:
      return "matched";
    case QueryOutcome::kNoPrediction:
      return "no_prediction";
    case QueryOutcome::kBehindCamera:
      return "behind_camera";
    case QueryOutcome::kOutsideImage:
      return "outside_image";
    case QueryOutcome::kNoCandidateInWindow:
      return "no_candidate_in_window";
    case QueryOutcome::kOrientation:
      return "orientation";
    case QueryOutcome::kScale:
      return "scale";
    case QueryOutcome::kDistanceThreshold:
      return "distance_threshold";
    case QueryOutcome::kRatioTest:
      return "ratio_test";
    case QueryOutcome::kMutual:
      return "mutual";
  }
  return "?";
}

std::string MatchStats::ToString() const {
  std::ostringstream out;
  out << "queries=" << queries << " (depth " << predicted_with_depth << ", no-depth "
      << predicted_without_depth << ") matched=" << matched
      << " | rejected: no_prediction=" << no_prediction << " behind_camera=" << behind_camera
      << " outside_image=" << outside_image << " no_candidate_in_window=" << no_candidate_in_window
      << " orientation=" << orientation << " scale=" << scale
      << " distance_threshold=" << distance_threshold << " ratio_test=" << ratio_test
      << " mutual=" << mutual << " | points_scanned=" << points_scanned
      << " distances_computed=" << distances_computed;
  return out.str();
}

}  // namespace imumatch
