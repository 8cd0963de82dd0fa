#include "imumatch/eval/report.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <tuple>

#include "imumatch/core/error.h"
#include "imumatch/io/output_files.h"

namespace imumatch {
namespace {

std::string Fixed(double v, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << v;
  return out.str();
}

std::vector<std::string> Cases(const std::vector<MethodSummary>& summaries) {
  std::vector<std::string> cases;
  for (const auto& s : summaries) {
    if (std::find(cases.begin(), cases.end(), s.case_name) == cases.end())
      cases.push_back(s.case_name);
  }
  return cases;
}

// Rows (detector, method) in order of appearance.
std::vector<std::pair<DetectorKind, MatchMethod>> Rows(
    const std::vector<MethodSummary>& summaries) {
  std::vector<std::pair<DetectorKind, MatchMethod>> rows;
  for (const auto& s : summaries) {
    const auto key = std::make_pair(s.detector, s.method);
    if (std::find(rows.begin(), rows.end(), key) == rows.end()) rows.push_back(key);
  }
  std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return static_cast<int>(a.first) < static_cast<int>(b.first);
    return static_cast<int>(a.second) < static_cast<int>(b.second);
  });
  return rows;
}

const MethodSummary* Find(const std::vector<MethodSummary>& summaries, const std::string& c,
                          DetectorKind d, MatchMethod m) {
  for (const auto& s : summaries) {
    if (s.case_name == c && s.detector == d && s.method == m) return &s;
  }
  return nullptr;
}

template <typename Cell>
std::string CaseTable(const std::vector<MethodSummary>& summaries, Cell cell) {
  const auto cases = Cases(summaries);
  std::ostringstream out;
  out << "| Detector | Method |";
  for (const auto& c : cases) out << " " << c << " |";
  out << "\n|---|---|";
  for (size_t i = 0; i < cases.size(); ++i) out << "---:|";
  out << "\n";
  for (const auto& [d, m] : Rows(summaries)) {
    out << "| " << ToString(d) << " | " << DisplayName(m) << " |";
    for (const auto& c : cases) {
      const MethodSummary* s = Find(summaries, c, d, m);
      out << " " << (s ? cell(*s) : std::string("-")) << " |";
    }
    out << "\n";
  }
  return out.str();
}

nlohmann::json StatsJson(const StageStats& s) {
  return {{"mean", s.mean}, {"p50", s.p50}, {"p90", s.p90}, {"p99", s.p99}, {"count", s.count}};
}

}  // namespace

std::string CsvField(const std::string& field) {
  if (field.find_first_of(",\"\n\r") == std::string::npos) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string MarkdownTimeTable(const std::vector<MethodSummary>& summaries) {
  return CaseTable(summaries, [](const MethodSummary& s) {
    return Fixed(s.match_ms.mean, 2) + " / " + Fixed(s.total_ms.mean, 1);
  });
}

std::string MarkdownMatchTable(const std::vector<MethodSummary>& summaries) {
  return CaseTable(summaries, [](const MethodSummary& s) {
    return Fixed(s.matches, 1) + " / " + Fixed(s.wrong, 1);
  });
}

std::string MarkdownDetailTable(const std::vector<MethodSummary>& summaries) {
  std::ostringstream out;
  out << "| Case | Detector | Method | Pairs | Keypoints | Read ms | Extract ms | Predict ms | "
         "Match "
         "ms (mean/p50/p90/p99) | Total ms | Matches | Correct | False | Precision | Recall |\n"
         "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& s : summaries) {
    out << "| " << s.case_name << " | " << ToString(s.detector) << " | " << DisplayName(s.method)
        << " | " << s.pairs << " | " << Fixed(s.keypoints, 0) << " | " << Fixed(s.read_ms.mean, 1)
        << " | " << Fixed(s.extract_ms.mean, 1) << " | " << Fixed(s.predict_ms.mean, 2) << " | "
        << Fixed(s.match_ms.mean, 2) << " / " << Fixed(s.match_ms.p50, 2) << " / "
        << Fixed(s.match_ms.p90, 2) << " / " << Fixed(s.match_ms.p99, 2) << " | "
        << Fixed(s.total_ms.mean, 1) << " | " << Fixed(s.matches, 1) << " | " << Fixed(s.correct, 1)
        << " | " << Fixed(s.wrong, 1) << " | " << Fixed(s.precision, 3) << " | "
        << (s.possible > 0.0 ? Fixed(s.recall, 3) : std::string("n/a (no depth)")) << " |\n";
  }
  return out.str();
}

std::string MarkdownSpeedupTable(const std::vector<MethodSummary>& summaries) {
  std::ostringstream out;
  out << "| Case | Detector | BF match ms | Guided match ms (incl. predict) | Speed-up | BF "
         "correct "
         "| Guided correct | BF precision | Guided precision | Window recall |\n"
         "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& c : Cases(summaries)) {
    for (const auto& [d, m] : Rows(summaries)) {
      if (m != MatchMethod::kGuided) continue;
      const MethodSummary* g = Find(summaries, c, d, MatchMethod::kGuided);
      const MethodSummary* b = Find(summaries, c, d, MatchMethod::kBruteForce);
      if (!g || !b) continue;
      const double guided_ms = g->match_ms.mean + g->predict_ms.mean;
      out << "| " << c << " | " << ToString(d) << " | " << Fixed(b->match_ms.mean, 2) << " | "
          << Fixed(guided_ms, 2) << " | x"
          << Fixed(guided_ms > 0 ? b->match_ms.mean / guided_ms : 0.0, 1) << " | "
          << Fixed(b->correct, 1) << " | " << Fixed(g->correct, 1) << " | "
          << Fixed(b->precision, 3) << " | " << Fixed(g->precision, 3) << " | "
          << (g->window_recall >= 0.0 ? Fixed(g->window_recall, 4) : std::string("n/a")) << " |\n";
    }
  }
  return out.str();
}

std::string MarkdownWindowTable(const std::vector<DetectorPairRecord>& records,
                                double threshold_px) {
  struct Acc {
    WindowRecall w;
    std::vector<double> per_pair;
  };
  std::map<std::tuple<std::string, int, int>, Acc> acc;
  std::vector<std::string> order;
  for (const auto& r : records) {
    if (std::find(order.begin(), order.end(), r.case_name) == order.end())
      order.push_back(r.case_name);
    for (const auto& run : r.runs) {
      if (!UsesPrediction(run.method)) continue;
      const WindowRecall w = ComputeWindowRecall(r, run, threshold_px);
      if (w.checked == 0) continue;
      Acc& a = acc[{r.case_name, static_cast<int>(r.detector), static_cast<int>(run.method)}];
      a.w.Add(w);
      a.per_pair.push_back(w.Recall());
    }
  }
  std::ostringstream out;
  out << "| Case | Detector | Method | BF correct checked | pooled | worst pair | missed: with "
         "depth / epipolar (beyond its ends) / no prediction "
         "|\n|---|---|---|---:|---:|---:|---:|\n";
  for (const auto& c : order) {
    for (const auto& [key, a] : acc) {
      if (std::get<0>(key) != c) continue;
      out << "| " << c << " | " << ToString(static_cast<DetectorKind>(std::get<1>(key))) << " | "
          << DisplayName(static_cast<MatchMethod>(std::get<2>(key))) << " | " << a.w.checked
          << " | " << Fixed(a.w.Recall(), 4) << " | "
          << Fixed(*std::min_element(a.per_pair.begin(), a.per_pair.end()), 3) << " | "
          << a.w.missed_with_depth << " / " << a.w.missed_without_depth << " ("
          << a.w.missed_beyond_segment << ") / " << a.w.missed_no_prediction << " |\n";
    }
  }
  return out.str();
}

std::string MarkdownMotionErrorTable(const std::vector<DetectorPairRecord>& records) {
  std::map<std::string, std::vector<double>> rot, trans;
  std::vector<std::string> order;
  std::map<std::pair<std::string, size_t>, bool> seen;  // one value per pair, not per detector
  for (const auto& r : records) {
    if (!seen.emplace(std::make_pair(r.case_name, r.pair_index), true).second) continue;
    if (rot.find(r.case_name) == rot.end()) order.push_back(r.case_name);
    rot[r.case_name].push_back(r.motion_rotation_error_deg);
    trans[r.case_name].push_back(r.motion_translation_error_m * 1000.0);
  }
  std::ostringstream out;
  out << "| Case | pairs | rotation error deg: median / p90 / max | translation error mm: median "
         "/ p90 / max |\n|---|---:|---:|---:|\n";
  for (const auto& c : order) {
    const StageStats sr = ComputeStageStats(rot[c]), st = ComputeStageStats(trans[c]);
    const double max_r = *std::max_element(rot[c].begin(), rot[c].end());
    const double max_t = *std::max_element(trans[c].begin(), trans[c].end());
    out << "| " << c << " | " << sr.count << " | " << Fixed(sr.p50, 4) << " / " << Fixed(sr.p90, 4)
        << " / " << Fixed(max_r, 4) << " | " << Fixed(st.p50, 2) << " / " << Fixed(st.p90, 2)
        << " / " << Fixed(max_t, 2) << " |\n";
  }
  return out.str();
}

std::string MarkdownThresholdTable(const std::vector<DetectorPairRecord>& records,
                                   const std::vector<double>& thresholds_px) {
  std::ostringstream out;
  out << "| Detector | Method |";
  for (double t : thresholds_px) out << " precision @" << Fixed(t, 1) << " px |";
  out << "\n|---|---|";
  for (size_t i = 0; i < thresholds_px.size(); ++i) out << "---:|";
  out << "\n";
  std::map<std::pair<int, int>, std::vector<std::pair<double, double>>> acc;  // correct, matches
  for (const auto& r : records) {
    for (const auto& run : r.runs) {
      auto& v = acc[{static_cast<int>(r.detector), static_cast<int>(run.method)}];
      v.resize(thresholds_px.size());
      for (size_t i = 0; i < thresholds_px.size(); ++i) {
        const JudgedCounts c = CountCorrect(run.residuals, thresholds_px[i]);
        v[i].first += c.correct;
        v[i].second += c.matches;
      }
    }
  }
  for (const auto& [key, v] : acc) {
    out << "| " << ToString(static_cast<DetectorKind>(key.first)) << " | "
        << DisplayName(static_cast<MatchMethod>(key.second)) << " |";
    for (const auto& [correct, matches] : v) {
      out << " " << (matches > 0 ? Fixed(correct / matches, 3) : std::string("-")) << " |";
    }
    out << "\n";
  }
  return out.str();
}

std::string MarkdownTrackingTable(const std::vector<DetectorPairRecord>& records) {
  struct Acc {
    TrackStats s;
    int pairs = 0;
    int64_t from_tracks = 0, from_descriptors = 0;
  };
  std::map<std::tuple<std::string, int, int>, Acc> acc;
  std::vector<std::string> order;
  for (const auto& r : records) {
    for (const auto& run : r.runs) {
      if (!IsTracking(run.method)) continue;
      if (std::find(order.begin(), order.end(), r.case_name) == order.end()) {
        order.push_back(r.case_name);
      }
      Acc& a = acc[{r.case_name, static_cast<int>(r.detector), static_cast<int>(run.method)}];
      const TrackStats& t = run.track_stats;
      a.s.queries += t.queries;
      a.s.tracked += t.tracked;
      a.s.no_prediction += t.no_prediction;
      a.s.border += t.border;
      a.s.texture += t.texture;
      a.s.no_convergence += t.no_convergence;
      a.s.forward_backward += t.forward_backward;
      a.s.low_correlation += t.low_correlation;
      a.s.outside_window += t.outside_window;
      a.s.ambiguous += t.ambiguous;
      a.from_tracks += run.from_tracks;
      a.from_descriptors += run.from_descriptors;
      ++a.pairs;
    }
  }
  if (acc.empty()) return "";
  std::ostringstream out;
  out << "| Case | Detector | Method | queries | tracked | no prediction | border / texture | no "
         "convergence | forward-backward | low correlation | ambiguous | outside window | "
         "hybrid: tracks / descriptor matches "
         "|\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
         "---:|---:|\n";
  for (const auto& c : order) {
    for (const auto& [key, a] : acc) {
      if (std::get<0>(key) != c) continue;
      const double n = a.pairs;
      const TrackStats& t = a.s;
      const auto m = static_cast<MatchMethod>(std::get<2>(key));
      out << "| " << c << " | " << ToString(static_cast<DetectorKind>(std::get<1>(key))) << " | "
          << DisplayName(m) << " | " << Fixed(t.queries / n, 1) << " | " << Fixed(t.tracked / n, 1)
          << " | " << Fixed(t.no_prediction / n, 1) << " | " << Fixed(t.border / n, 1) << " / "
          << Fixed(t.texture / n, 1) << " | " << Fixed(t.no_convergence / n, 1) << " | "
          << Fixed(t.forward_backward / n, 1) << " | " << Fixed(t.low_correlation / n, 1) << " | "
          << Fixed(t.ambiguous / n, 1) << " | " << Fixed(t.outside_window / n, 1) << " | "
          << (m == MatchMethod::kHybrid
                  ? Fixed(a.from_tracks / n, 1) + " / " + Fixed(a.from_descriptors / n, 1)
                  : std::string("-"))
          << " |\n";
    }
  }
  return out.str();
}

std::string MarkdownReport(const EvaluationResult& result, const ReportContext& context,
                           size_t max_skipped) {
  const auto summaries = Summarize(result.records, context.threshold.threshold_px);
  std::ostringstream out;
  out << "# " << context.title << "\n\n";
  for (const auto& [k, v] : context.config) out << "- " << k << ": " << v << "\n";
  out << "- pairs: " << result.pairs_total << " selected, " << result.skipped.size()
      << " skipped entries; wall time " << Fixed(result.wall_s, 1) << " s\n";
  out << "- correct match: " << context.threshold.description << "\n";
  for (const auto& w : result.warnings) out << "- **warning**: " << w << "\n";
  for (const auto& n : result.notes) out << "- note: " << n << "\n";
  out << "\n## Table I: time per pair, match ms / total ms (mean)\n\n"
      << "total = feature extraction of both frames + IMU motion + prediction + matching\n\n"
      << MarkdownTimeTable(summaries);
  out << "\n## Table II: matches / false matches per pair (mean, threshold "
      << Fixed(context.threshold.threshold_px, 2) << " px)\n\n"
      << MarkdownMatchTable(summaries);
  out << "\n## IMU-guided vs brute force\n\n" << MarkdownSpeedupTable(summaries);
  // A sequence with depth for only some frames: the two halves separately.
  bool with = false, without = false;
  for (const auto& r : result.records) (r.has_depth ? with : without) = true;
  if (with && without) {
    out << "\n### By depth of frame A\n\n"
        << MarkdownSpeedupTable(
               Summarize(SplitByDepth(result.records), context.threshold.threshold_px));
  }
  out << "\n## Window recall\n\n"
      << "Of the brute-force matches judged correct, the share whose partner lies inside the "
         "guided search region.\n\n"
      << MarkdownWindowTable(result.records, context.threshold.threshold_px);
  out << "\n## Motion given to the predictor vs ground truth (per pair)\n\n"
      << MarkdownMotionErrorTable(result.records);
  const std::string tracking = MarkdownTrackingTable(result.records);
  if (!tracking.empty()) {
    out << "\n## Tracking outcomes (mean per pair)\n\n"
        << "klt0, klt: how every keypoint's track ended; hybrid: the same for its tracks, and how "
           "many correspondences each path made (tracks, then guided matches for the rest).\n\n"
        << tracking;
  }
  out << "\n## Details\n\n" << MarkdownDetailTable(summaries);
  if (!context.fixed_thresholds.empty()) {
    out << "\n## Precision at fixed thresholds (all cases pooled)\n\n"
        << MarkdownThresholdTable(result.records, context.fixed_thresholds);
  }
  if (context.end_to_end && context.end_to_end->frames > 0) {
    out << "\n## End-to-end\n\n" << context.end_to_end->Describe() << "\n";
  }
  if (!result.skipped.empty()) {
    out << "\n## Skipped\n\n";
    for (size_t i = 0; i < result.skipped.size() && i < max_skipped; ++i) {
      const auto& s = result.skipped[i];
      out << "- " << s.case_name << " pair " << s.pair_index << " (frames " << s.frame_a << ", "
          << s.frame_b << ")" << (s.detector.empty() ? "" : " " + s.detector) << ": " << s.reason
          << "\n";
    }
    if (result.skipped.size() > max_skipped) {
      out << "- ... " << result.skipped.size() - max_skipped << " more in skipped.csv\n";
    }
  }
  return out.str();
}

void WriteSummaryCsv(std::ostream& out, const std::vector<MethodSummary>& summaries) {
  out << "case,detector,method,pairs,keypoints,read_ms_mean,extract_ms_mean,extract_ms_p50,"
         "extract_ms_p90,extract_ms_p99,predict_ms_mean,predict_ms_p50,predict_ms_p90,"
         "predict_ms_p99,match_ms_mean,match_ms_p50,match_ms_p90,match_ms_p99,total_ms_mean,"
         "total_ms_p50,total_ms_p90,total_ms_p99,matches,correct,false,possible,precision,recall,"
         "epipolar_fraction,window_recall\n";
  out << std::setprecision(6);
  for (const auto& s : summaries) {
    out << CsvField(s.case_name) << "," << ToString(s.detector) << "," << ToString(s.method) << ","
        << s.pairs << "," << s.keypoints << "," << s.read_ms.mean;
    for (const StageStats* st : {&s.extract_ms, &s.predict_ms, &s.match_ms, &s.total_ms}) {
      out << "," << st->mean << "," << st->p50 << "," << st->p90 << "," << st->p99;
    }
    out << "," << s.matches << "," << s.correct << "," << s.wrong << "," << s.possible << ","
        << s.precision << "," << s.recall << "," << s.epipolar_fraction << "," << s.window_recall
        << "\n";
  }
}

void WritePairsCsv(std::ostream& out, const std::vector<DetectorPairRecord>& records,
                   double threshold_px) {
  out << "case,pair,frame_a,frame_b,t_a_ns,t_b_ns,detector,method,keypoints_a,keypoints_b,"
         "keypoints_a_with_depth,read_ms,extract_ms,motion_ms,predict_ms,match_ms,matches,correct,"
         "false,possible,precision,recall,motion_rotation_error_deg,motion_translation_error_m,"
         "has_depth,window_recall,from_tracks,from_descriptors\n";
  out << std::setprecision(6);
  for (const auto& r : records) {
    for (const auto& run : r.runs) {
      const RunCounts c = CountRun(r, run, threshold_px);
      out << CsvField(r.case_name) << "," << r.pair_index << "," << r.frame_a << "," << r.frame_b
          << "," << r.t_a_ns << "," << r.t_b_ns << "," << ToString(r.detector) << ","
          << ToString(run.method) << "," << r.keypoints_a << "," << r.keypoints_b << ","
          << r.keypoints_a_with_depth << "," << r.read_ms << "," << r.extract_ms << ","
          << (UsesPrediction(run.method) ? r.motion_ms : 0.0) << "," << run.predict_ms << ","
          << run.match_ms << "," << c.counts.matches << "," << c.counts.correct << ","
          << c.counts.wrong << "," << c.possible << "," << c.precision << "," << c.recall << ","
          << r.motion_rotation_error_deg << "," << r.motion_translation_error_m << ","
          << (r.has_depth ? 1 : 0) << "," << ComputeWindowRecall(r, run, threshold_px).Recall()
          << "," << run.from_tracks << "," << run.from_descriptors << "\n";
    }
  }
}

void WriteSkippedCsv(std::ostream& out, const std::vector<SkippedPair>& skipped) {
  out << "case,pair,frame_a,frame_b,detector,reason\n";
  for (const auto& s : skipped) {
    out << CsvField(s.case_name) << "," << s.pair_index << "," << s.frame_a << "," << s.frame_b
        << "," << CsvField(s.detector) << "," << CsvField(s.reason) << "\n";
  }
}

nlohmann::json ReportToJson(const EvaluationResult& result, const ReportContext& context) {
  using nlohmann::json;
  const double thr = context.threshold.threshold_px;
  json j;
  j["title"] = context.title;
  json t = {{"threshold_px", thr}, {"description", context.threshold.description}};
  if (context.threshold.automatic) {
    const AutoThreshold& a = *context.threshold.automatic;
    t["automatic"] = {
        {"median_px", a.median_px}, {"mad_sigma_px", a.mad_sigma_px}, {"k", a.k},
        {"gate_px", a.gate_px},     {"samples", a.samples},           {"clamped", a.clamped},
        {"fallback", a.fallback}};
  }
  j["threshold"] = t;
  json config = json::object();
  for (const auto& [k, v] : context.config) config[k] = v;
  j["config"] = config;
  j["pairs_total"] = result.pairs_total;
  j["wall_s"] = result.wall_s;
  j["notes"] = result.notes;
  j["warnings"] = result.warnings;
  json summary = json::array();
  for (const auto& s : Summarize(result.records, thr)) {
    summary.push_back({{"case", s.case_name},
                       {"detector", ToString(s.detector)},
                       {"method", ToString(s.method)},
                       {"pairs", s.pairs},
                       {"keypoints", s.keypoints},
                       {"read_ms", StatsJson(s.read_ms)},
                       {"extract_ms", StatsJson(s.extract_ms)},
                       {"predict_ms", StatsJson(s.predict_ms)},
                       {"match_ms", StatsJson(s.match_ms)},
                       {"total_ms", StatsJson(s.total_ms)},
                       {"matches", s.matches},
                       {"correct", s.correct},
                       {"false", s.wrong},
                       {"possible", s.possible},
                       {"precision", s.precision},
                       {"recall", s.recall},
                       {"epipolar_fraction", s.epipolar_fraction},
                       {"window_recall", s.window_recall},
                       {"window_checked", s.window_checked}});
  }
  j["summary"] = summary;
  json pairs = json::array();
  for (const auto& r : result.records) {
    for (const auto& run : r.runs) {
      const RunCounts c = CountRun(r, run, thr);
      pairs.push_back({{"case", r.case_name},
                       {"pair", r.pair_index},
                       {"frame_a", r.frame_a},
                       {"frame_b", r.frame_b},
                       {"t_a_ns", r.t_a_ns},
                       {"t_b_ns", r.t_b_ns},
                       {"detector", ToString(r.detector)},
                       {"method", ToString(run.method)},
                       {"keypoints_a", r.keypoints_a},
                       {"keypoints_b", r.keypoints_b},
                       {"extract_ms", r.extract_ms},
                       {"motion_ms", UsesPrediction(run.method) ? r.motion_ms : 0.0},
                       {"predict_ms", run.predict_ms},
                       {"match_ms", run.match_ms},
                       {"matches", c.counts.matches},
                       {"correct", c.counts.correct},
                       {"false", c.counts.wrong},
                       {"possible", c.possible},
                       {"precision", c.precision},
                       {"recall", c.recall}});
      if (IsTracking(run.method)) {
        const TrackStats& ts = run.track_stats;
        pairs.back()["tracking"] = {{"from_tracks", run.from_tracks},
                                    {"from_descriptors", run.from_descriptors},
                                    {"tracked", ts.tracked},
                                    {"no_prediction", ts.no_prediction},
                                    {"border", ts.border},
                                    {"texture", ts.texture},
                                    {"no_convergence", ts.no_convergence},
                                    {"forward_backward", ts.forward_backward},
                                    {"low_correlation", ts.low_correlation},
                                    {"ambiguous", ts.ambiguous},
                                    {"outside_window", ts.outside_window}};
      }
    }
  }
  j["pairs"] = pairs;
  json skipped = json::array();
  for (const auto& s : result.skipped) {
    skipped.push_back({{"case", s.case_name},
                       {"pair", s.pair_index},
                       {"frame_a", s.frame_a},
                       {"frame_b", s.frame_b},
                       {"detector", s.detector},
                       {"reason", s.reason}});
  }
  j["skipped"] = skipped;
  json precision_at = json::array();
  for (double th : context.fixed_thresholds) {
    for (const auto& s : Summarize(result.records, th)) {
      precision_at.push_back({{"threshold_px", th},
                              {"case", s.case_name},
                              {"detector", ToString(s.detector)},
                              {"method", ToString(s.method)},
                              {"precision", s.precision},
                              {"recall", s.recall}});
    }
  }
  j["precision_at"] = precision_at;
  if (context.end_to_end && context.end_to_end->frames > 0) {
    const EndToEndTiming& e = *context.end_to_end;
    j["end_to_end"] = {{"frames", e.frames},
                       {"width", e.width},
                       {"height", e.height},
                       {"threads", e.threads},
                       {"sequential_ms_per_frame", e.sequential_ms_per_frame},
                       {"sequential_latency_ms", e.sequential_latency_ms},
                       {"imumatch_ms_per_frame", e.imumatch_ms_per_frame},
                       {"imumatch_latency_ms", e.imumatch_latency_ms},
                       {"overlapped_ms_per_frame", e.overlapped_ms_per_frame},
                       {"overlapped_latency_ms", e.overlapped_latency_ms},
                       {"throughput_ratio", e.Throughput()},
                       {"latency_ratio", e.LatencyRatio()},
                       {"sequential_matches", e.sequential_matches},
                       {"imumatch_matches", e.imumatch_matches},
                       {"motion_failures", e.motion_failures}};
  } else {
    j["end_to_end"] = nullptr;
  }
  return j;
}

std::vector<std::string> WriteReportFiles(const std::string& dir, const EvaluationResult& result,
                                          const ReportContext& context) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error("cannot create output folder " + dir + ": " + ec.message());
  std::vector<std::string> written;
  auto write = [&](const std::string& name, const auto& fill) {
    const std::string path = (std::filesystem::path(dir) / name).string();
    std::ostringstream out;
    fill(out);
    WriteFileAtomic(path, out.str());  // temporary file + rename: never half a report
    written.push_back(path);
  };
  const double thr = context.threshold.threshold_px;
  write("report.md", [&](std::ostream& o) { o << MarkdownReport(result, context, 1000); });
  write("report.json",
        [&](std::ostream& o) { o << ReportToJson(result, context).dump(2) << "\n"; });
  write("summary.csv",
        [&](std::ostream& o) { WriteSummaryCsv(o, Summarize(result.records, thr)); });
  write("pairs.csv", [&](std::ostream& o) { WritePairsCsv(o, result.records, thr); });
  write("skipped.csv", [&](std::ostream& o) { WriteSkippedCsv(o, result.skipped); });
  return written;
}

}  // namespace imumatch
