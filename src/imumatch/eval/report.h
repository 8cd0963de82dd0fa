#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "imumatch/eval/end_to_end.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/summary.h"

namespace imumatch {

// Everything a report states besides the records: how the run was configured and judged.
struct ReportContext {
  std::string title = "imumatch evaluation";
  ThresholdChoice threshold;
  // Extra thresholds at which precision is also tabulated (real ground truth is a few px off).
  std::vector<double> fixed_thresholds = {1.0, 3.0, 5.0, 8.0};
  std::optional<EndToEndTiming> end_to_end;
  // Free-form configuration lines ("detectors" -> "sift,orb", ...), written to JSON and Markdown.
  std::vector<std::pair<std::string, std::string>> config;
};

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
std::string MarkdownMotionErrorTable(const std::vector<DetectorPairRecord>& records);
// Precision (pooled over every case) of each detector x method at several thresholds.
// How the tracks of the tracking methods (klt0, klt, hybrid) ended, mean per pair; "" when no
// record has a tracking run.
std::string MarkdownTrackingTable(const std::vector<DetectorPairRecord>& records);
std::string MarkdownThresholdTable(const std::vector<DetectorPairRecord>& records,
                                   const std::vector<double>& thresholds_px);
// The whole report: context, all tables, skipped pairs (at most max_skipped listed).
std::string MarkdownReport(const EvaluationResult& result, const ReportContext& context,
                           size_t max_skipped = 20);

// CSV (RFC 4180 quoting, header line first).
void WriteSummaryCsv(std::ostream& out, const std::vector<MethodSummary>& summaries);
void WritePairsCsv(std::ostream& out, const std::vector<DetectorPairRecord>& records,
                   double threshold_px);
void WriteSkippedCsv(std::ostream& out, const std::vector<SkippedPair>& skipped);

// JSON: {"title", "threshold": {...}, "config": {...}, "summary": [...], "pairs": [...],
// "skipped": [...], "end_to_end": {...}|null, "notes": [...], "precision_at": [...]}.
nlohmann::json ReportToJson(const EvaluationResult& result, const ReportContext& context);

// Writes report.md, report.json, summary.csv, pairs.csv and skipped.csv into dir (created when
// missing). Returns the paths written. Throws Error when a file cannot be written.
std::vector<std::string> WriteReportFiles(const std::string& dir, const EvaluationResult& result,
                                          const ReportContext& context);

// Quotes a CSV field when it contains a comma, quote or newline.
std::string CsvField(const std::string& field);

}  // namespace imumatch
