#pragma once

#include <string>
#include <vector>

#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/summary.h"

namespace imumatch {

// Markdown tables (GitHub style). Rows: detector x method; columns: cases.
// Table I: mean time per pair, "match ms / total ms" (total = extraction of both frames + IMU
// motion + prediction + matching).
std::string MarkdownTimeTable(const std::vector<MethodSummary>& summaries);
// Table II: mean matches and false matches per pair, "matches / false".
std::string MarkdownMatchTable(const std::vector<MethodSummary>& summaries);
// Per (case, detector, method): pairs, keypoints, stage times (mean, match p50/p90/p99), matches,
// correct, false, precision, recall.
std::string MarkdownDetailTable(const std::vector<MethodSummary>& summaries);
// IMU-guided against brute force per case and detector: match time ratio, correct, precision.
std::string MarkdownSpeedupTable(const std::vector<MethodSummary>& summaries);
// Window recall of the guided methods per case and detector (pooled, worst pair, misses by how
// the query was predicted), and the motion's error against the ground truth per case.
std::string MarkdownWindowTable(const std::vector<DetectorPairRecord>& records,
                                double threshold_px);
// Per case, detector and prediction method (summed over pairs): of brute force's correct
// matches, how many the method kept, matched wrongly or did not match and why; the correct matches
// it found where brute force had none; the net. Empty without such runs.
std::string MarkdownBruteForceFateTable(const std::vector<DetectorPairRecord>& records,
                                        double threshold_px);
std::string MarkdownMotionErrorTable(const std::vector<DetectorPairRecord>& records);
// Where the epipolar segments of keypoints without depth started (PredictKeypointsInScene) per
// case, detector and method: near end min / median / max, pairs whose near end moved, pilot
// matches; "" when no record predicted a keypoint without depth.
std::string MarkdownSceneNearTable(const std::vector<DetectorPairRecord>& records);
// The guided method's second pass (motion fitted to the first pass): pairs where it ran, why it
// did not, the fit's residual, the windows before and after. Empty when it was never tried.
std::string MarkdownSecondPassTable(const std::vector<DetectorPairRecord>& records);
// The sub-pixel refinement (RefineMatches) per case, detector and method, mean per pair: aligned
// (and by the larger patch after a drift), unrefined (flat / border), dropped. Empty when no run
// was refined.
// The second look by the image patch (MatchByPatch), mean per pair: queries looked at again,
// candidates aligned, queries whose patch was found at two places, matches added, kept after
// refinement, correct at threshold_px, the time.
std::string MarkdownPatchLookTable(const std::vector<DetectorPairRecord>& records,
                                   double threshold_px);
std::string MarkdownRefinementTable(const std::vector<DetectorPairRecord>& records);
// How the tracks of the tracking methods (klt0, klt, hybrid) ended, mean per pair; "" when no
// record has a tracking run.
std::string MarkdownTrackingTable(const std::vector<DetectorPairRecord>& records);
// Precision (pooled over every case) of each detector x method at several thresholds.
std::string MarkdownThresholdTable(const std::vector<DetectorPairRecord>& records,
                                   const std::vector<double>& thresholds_px);
// v with a fixed number of digits after the point.
std::string FormatFixed(double v, int digits);

}  // namespace imumatch
