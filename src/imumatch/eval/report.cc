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

std::string MarkdownReport(const EvaluationResult& result, const ReportContext& context,
                           size_t max_skipped) {
  const auto summaries = Summarize(result.records, context.threshold.threshold_px);
  std::ostringstream out;
  out << "# " << context.title << "\n\n";
  for (const auto& [k, v] : context.config) out << "- " << k << ": " << v << "\n";
  out << "- pairs: " << result.pairs_total << " selected, " << result.skipped.size()
      << " skipped entries; wall time " << FormatFixed(result.wall_s, 1) << " s\n";
  out << "- correct match: " << context.threshold.description << "\n";
  for (const auto& w : result.warnings) out << "- **warning**: " << w << "\n";
  for (const auto& n : result.notes) out << "- note: " << n << "\n";
  out << "\n## Table I: time per pair, match ms / total ms (mean)\n\n"
      << "total = feature extraction of both frames + IMU motion + prediction + matching\n\n"
      << MarkdownTimeTable(summaries);
  out << "\n## Table II: matches / false matches per pair (mean, threshold "
      << FormatFixed(context.threshold.threshold_px, 2) << " px)\n\n"
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
  const std::string fate =
      MarkdownBruteForceFateTable(result.records, context.threshold.threshold_px);
  if (!fate.empty()) {
    out << "\n## Brute force's correct matches in the guided runs (all pairs)\n\n"
        << "Of the brute-force matches judged correct: how many the method matched correctly "
           "too (kept), to a wrong partner, or not at all and why (its query's outcome); gained: "
           "its correct matches whose query brute force did not match correctly; net = gained - "
           "(BF correct - kept).\n\n"
        << fate;
  }
  const std::string scene_near = MarkdownSceneNearTable(result.records);
  if (!scene_near.empty()) {
    out << "\n## Epipolar segments: near end from the scene\n\n"
        << "Keypoints without depth are searched along the epipolar segment from this depth to "
           "infinity: half the nearest depth that a pilot of 100 keypoints, matched along the full "
           "segments, needs (never nearer than the configured --z-min).\n\n"
        << scene_near;
  }
  const std::string second_pass = MarkdownSecondPassTable(result.records);
  if (!second_pass.empty()) {
    out << "\n## Second pass: windows from the motion fitted to the first pass\n\n"
        << "The guided method fits the motion to its first matches (the IMU's motion as the prior, "
           "reprojection errors with depth, epipolar distances without; Cauchy-weighted) and "
           "matches again in the windows of the fitted motion's covariance when they search less "
           "than the first pass's; the first pass stands when the fit strays beyond the IMU's "
           "uncertainty or its windows are not smaller (--single-pass: never tried).\n\n"
        << second_pass;
  }
  const std::string patch_look =
      MarkdownPatchLookTable(result.records, context.threshold.threshold_px);
  if (!patch_look.empty()) {
    out << "\n## Second look by the image patch (mean per pair)\n\n"
        << "The queries the guided search left unmatched although their window held candidates "
           "(orientation, distance or ratio rejections) are looked at again: A's patch, warped "
           "as the prediction says, is aligned at each candidate; a candidate passes when the "
           "patch converges within 2 px of it with a correlation of at least 0.9, and the query "
           "is matched when those that pass point to one place (--no-patch-look: off).\n\n"
        << patch_look;
  }
  const std::string refinement = MarkdownRefinementTable(result.records);
  if (!refinement.empty()) {
    out << "\n## Sub-pixel refinement (mean per pair)\n\n"
        << "Each match's position in B is refined by aligning A's patch (warped by the "
           "prediction); a flat patch, or one that drifts, is tried again at twice the size, and "
           "after a drift it counts only at a high correlation (SubpixelOptions; defaults: 9 x 9 "
           "samples, ZNCC >= 0.8). Matches whose patch is not found within the shift limit (4 px) "
           "are dropped (--no-refine: no refinement, no drop).\n\n"
        << refinement;
  }
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
         "has_depth,window_recall,from_tracks,from_descriptors,segment_near_m,second_pass,"
         "refit_sigma_px,window_px,narrowed_segments\n";
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
          << "," << run.from_tracks << "," << run.from_descriptors << ","
          << (run.stats.predicted_without_depth > 0 ? run.scene_near.segment_min_depth_m : 0.0)
          << "," << ToString(run.second_pass) << "," << (run.refit.ok ? run.refit.sigma_px : 0.0)
          << "," << run.window_px << "," << run.narrowed_segments << "\n";
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
  json offsets = json::array();  // the camera's clock offset from the IMU's, t_imu = t_cam + offset
  for (const EvaluationResult::TimeOffset& offset : result.time_offsets) {
    offsets.push_back(
        {{"case", offset.case_name},
         {"detector", ToString(offset.detector)},
         {"measured", offset.estimate.measured},
         // Not measured: null, not the grid's value with a zero sigma.
         {"offset_s", offset.estimate.measured ? json(offset.estimate.offset_s) : json(nullptr)},
         {"sigma_s", offset.estimate.measured ? json(offset.estimate.sigma_s) : json(nullptr)},
         // The block jackknife's part of it (sigma_s is the larger of it and the parabola's).
         {"jackknife_sigma_s", offset.estimate.measured && offset.estimate.jackknife_sigma_s > 0.0
                                   ? json(offset.estimate.jackknife_sigma_s)
                                   : json(nullptr)},
         {"observations", offset.estimate.observations},
         {"inliers", offset.estimate.inliers},
         {"reason", offset.estimate.reason}});
  }
  j["time_offsets"] = offsets;
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
      if (run.stats.predicted_without_depth > 0) {
        pairs.back()["segment_near_m"] = run.scene_near.segment_min_depth_m;
        pairs.back()["pilot_matches"] = run.scene_near.pilot_matches;
      }
      const SubpixelStats& rs = run.refine_stats;
      if (rs.refined + rs.failed_texture + rs.failed_border + rs.failed_convergence > 0) {
        pairs.back()["refinement"] = {{"aligned", rs.refined},
                                      {"recovered_larger", rs.recovered_larger},
                                      {"unrefined_flat", rs.failed_texture},
                                      {"unrefined_border", rs.failed_border},
                                      {"dropped", rs.failed_convergence},
                                      {"iterations", rs.iterations}};
      }
      if (run.second_pass != SecondPassOutcome::kNotTried) {
        pairs.back()["second_pass"] = {{"outcome", ToString(run.second_pass)},
                                       {"fit_note", run.refit.reason},
                                       {"fit_sigma_px", run.refit.sigma_px},
                                       {"fit_inliers", run.refit.inliers},
                                       {"fit_iterations", run.refit.iterations},
                                       {"fit_ms", run.refit_ms},
                                       {"fit_rotation_error_deg", run.refit_rotation_error_deg},
                                       {"fit_translation_error_m", run.refit_translation_error_m},
                                       {"fit_truth_mahalanobis2", run.refit_truth_mahalanobis2},
                                       {"fit_matches_with_depth", run.refit.with_depth},
                                       {"first_window_px", run.first_window_px},
                                       {"window_px", run.window_px},
                                       {"narrowed_segments", run.narrowed_segments}};
      }
      if (!run.bf_query_match.empty()) {
        const BruteForceFate f = ComputeBruteForceFate(r, run, thr);
        json fate = json::object();
        for (const auto& [name, count] : f.Named()) fate[name] = count;
        pairs.back()["bf_correct_fate"] = fate;
      }
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
                       {"repetitions", e.repetitions},
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
