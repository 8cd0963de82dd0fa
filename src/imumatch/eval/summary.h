#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "imumatch/eval/evaluation.h"

namespace imumatch {

// The threshold used to call a match correct.
struct ThresholdChoice {
  double threshold_px = 1.5;
  std::string description;
  std::optional<AutoThreshold> automatic;
};
// Fixed (explicit_px given), 1.5 px for exact ground truth, otherwise ComputeAutoThreshold on
// the depth residuals of the brute-force matches of all records.
ThresholdChoice ChooseThreshold(const EvaluationResult& result, bool exact_ground_truth,
                                std::optional<double> explicit_px);

struct StageStats {
  double mean = 0.0, p50 = 0.0, p90 = 0.0, p99 = 0.0;
  int count = 0;
};
StageStats ComputeStageStats(std::vector<double> values);  // nearest-rank percentiles

// One (case, detector, method) row, judged at one threshold.
struct MethodSummary {
  std::string case_name;
  DetectorKind detector = DetectorKind::kOrb;
  MatchMethod method = MatchMethod::kBruteForce;
  int pairs = 0;
  double keypoints = 0.0;  // mean over both frames
  StageStats read_ms, extract_ms, predict_ms, match_ms,
      total_ms;                                      // total: extract+motion+predict+match
  double matches = 0.0, correct = 0.0, wrong = 0.0;  // means per pair
  double possible = 0.0;                             // mean GT-possible correspondences
  double precision = 0.0;                            // pooled: sum correct / sum matches
  double recall = 0.0;             // pooled: sum correct (depth-judged) / sum possible
  double epipolar_fraction = 0.0;  // share of matches judged without depth
  // Guided methods: pooled window recall (see WindowRecall); -1 when there was nothing to check.
  double window_recall = -1.0;
  int window_checked = 0;  // brute-force matches judged correct, over all pairs
  int window_missed = 0;
};

// Per-pair counts of one run at a threshold.
struct RunCounts {
  JudgedCounts counts;
  int possible = 0;
  double precision = 0.0;
  double recall = 0.0;
};
RunCounts CountRun(const DetectorPairRecord& record, const MethodRun& run, double threshold_px);

// Window recall of a guided run: of the record's brute-force matches judged correct at the
// threshold, how many had their partner inside the run's search region.
struct WindowRecall {
  int checked = 0;
  int inside = 0;
  int missed_with_depth = 0;      // the query was predicted with depth (a window)
  int missed_without_depth = 0;   // predicted along an epipolar segment
  int missed_beyond_segment = 0;  // of those: on the segment's line, beyond one of its ends
  int missed_no_prediction = 0;   // behind camera B, outside image B, invalid
  double Recall() const { return checked > 0 ? static_cast<double>(inside) / checked : -1.0; }
  void Add(const WindowRecall& other);
};
WindowRecall ComputeWindowRecall(const DetectorPairRecord& record, const MethodRun& run,
                                 double threshold_px);

// What a guided run made of the queries that brute force matched correctly (at the threshold),
// and what it found where brute force had no correct match: the net of the two is the run's
// correct matches minus brute force's. Not matched: the query's outcome in the run.
struct BruteForceFate {
  int checked = 0;         // brute-force matches judged correct
  int kept = 0;            // the run matched the query correctly too (same or another partner)
  int matched_wrong = 0;   // the run matched the query to a partner judged wrong
  int refine_dropped = 0;  // matched, then dropped by the sub-pixel refinement
  int no_prediction = 0;   // behind camera B, outside image B, invalid
  int no_candidate = 0;    // nothing in the search region
  int inconsistent = 0;    // orientation or scale inconsistent with the predicted motion
  int distance = 0;        // best candidate beyond the absolute distance threshold
  int ratio = 0;           // ratio test against rivals in the search region
  int mutual = 0;          // not the mutual best
  int gained = 0;          // correct matches of the run whose query brute force did not match
                           // correctly
  void Add(const BruteForceFate& other);
  // The counts by name (as report.json and Python's evaluate name them), in the order above.
  std::vector<std::pair<const char*, int>> Named() const;
};
BruteForceFate ComputeBruteForceFate(const DetectorPairRecord& record, const MethodRun& run,
                                     double threshold_px);

// The records again, relabelled by whether frame A had depth: case_name + " [depth]" or
// " [no depth]". Summarize() on them gives the two halves of a sequence that has depth for only
// some frames (e.g. EuRoC MH_05 excerpt's depth0).
std::vector<DetectorPairRecord> SplitByDepth(const std::vector<DetectorPairRecord>& records);

// Rows ordered by case (first appearance), detector, method.
std::vector<MethodSummary> Summarize(const std::vector<DetectorPairRecord>& records,
                                     double threshold_px);

}  // namespace imumatch
