#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "imumatch/eval/end_to_end.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/report_tables.h"
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
