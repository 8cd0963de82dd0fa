#include "imumatch/eval/report.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "imumatch/core/error.h"
#include "imumatch/eval/plots.h"

namespace imumatch {
namespace {

// Two pairs of ORB with two methods; residuals chosen so the counts are known by hand.
EvaluationResult HandMadeResult() {
  EvaluationResult result;
  result.pairs_total = 2;
  for (int pair = 0; pair < 2; ++pair) {
    DetectorPairRecord r;
    r.case_name = "front,1m";  // a comma, to exercise CSV quoting
    r.pair_index = static_cast<size_t>(pair);
    r.frame_a = static_cast<size_t>(pair);
    r.frame_b = static_cast<size_t>(pair + 1);
    r.detector = DetectorKind::kOrb;
    r.keypoints_a = r.keypoints_b = 100;
    r.extract_ms = 10.0;
    r.motion_ms = 0.5;
    // Possible correspondences: 4 one-to-one candidates within 1 px.
    r.candidates = {{0, 0, 0.1f}, {1, 1, 0.2f}, {2, 2, 0.3f}, {3, 3, 0.4f}};
    MethodRun bf;
    bf.method = MatchMethod::kBruteForce;
    bf.match_ms = pair == 0 ? 4.0 : 6.0;
    // 3 matches: 2 correct at 1.5 px, 1 false.
    bf.residuals = {
        {ResidualKind::kDepth, 0.2f}, {ResidualKind::kDepth, 1.0f}, {ResidualKind::kDepth, 9.0f}};
    MethodRun guided;
    guided.method = MatchMethod::kGuided;
    guided.predict_ms = 0.25;
    guided.match_ms = 1.0;
    guided.residuals = {{ResidualKind::kDepth, 0.2f},
                        {ResidualKind::kDepth, 0.3f},
                        {ResidualKind::kDepth, 0.4f},
                        {ResidualKind::kEpipolar, 0.1f}};
    // Refinement outcomes of 6 and 4 matches, leaving the 4 above: pair 0 aligned 3 (1 by the
    // larger patch), 1 flat, 2 dropped; pair 1 aligned 3, 1 at the border.
    guided.refine_stats.refined = 3;
    guided.refine_stats.recovered_larger = pair == 0 ? 1 : 0;
    guided.refine_stats.failed_texture = pair == 0 ? 1 : 0;
    guided.refine_stats.failed_border = pair == 0 ? 0 : 1;
    guided.refine_stats.failed_convergence = pair == 0 ? 2 : 0;
    guided.refine_stats.iterations = pair == 0 ? 12 : 20;
    r.runs = {bf, guided};
    result.records.push_back(r);
  }
  result.skipped.push_back({"front,1m", 2, 2, 3, "", "IMU interval not available: gap"});
  return result;
}

ReportContext Context() {
  ReportContext c;
  c.threshold.threshold_px = 1.5;
  c.threshold.description = "threshold 1.50 px (test)";
  c.config = {{"detectors", "orb"}};
  return c;
}

TEST(ReportTest, SummaryCountsAndTimes) {
  const auto s = Summarize(HandMadeResult().records, 1.5);
  ASSERT_EQ(s.size(), 2u);
  const MethodSummary& bf = s[0];
  EXPECT_EQ(bf.method, MatchMethod::kBruteForce);
  EXPECT_EQ(bf.pairs, 2);
  EXPECT_DOUBLE_EQ(bf.matches, 3.0);
  EXPECT_DOUBLE_EQ(bf.correct, 2.0);
  EXPECT_DOUBLE_EQ(bf.wrong, 1.0);
  EXPECT_NEAR(bf.precision, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(bf.recall, 2.0 / 4.0, 1e-12);
  EXPECT_DOUBLE_EQ(bf.match_ms.mean, 5.0);
  EXPECT_DOUBLE_EQ(bf.match_ms.p50, 4.0);
  EXPECT_DOUBLE_EQ(bf.match_ms.p99, 6.0);
  EXPECT_DOUBLE_EQ(bf.total_ms.mean, 15.0);  // no motion/prediction for brute force
  const MethodSummary& g = s[1];
  EXPECT_DOUBLE_EQ(g.precision, 1.0);
  EXPECT_DOUBLE_EQ(g.recall, 3.0 / 4.0);  // the epipolar-judged match does not count for recall
  EXPECT_DOUBLE_EQ(g.total_ms.mean, 10.0 + 0.5 + 0.25 + 1.0);
  EXPECT_DOUBLE_EQ(g.epipolar_fraction, 0.25);
  // A stricter threshold: bf keeps 1 correct of 3.
  EXPECT_DOUBLE_EQ(Summarize(HandMadeResult().records, 0.5)[0].correct, 1.0);
}

TEST(ReportTest, StageStatsNearestRank) {
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(i);
  const StageStats s = ComputeStageStats(v);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  EXPECT_DOUBLE_EQ(s.p50, 50.0);
  EXPECT_DOUBLE_EQ(s.p90, 90.0);
  EXPECT_DOUBLE_EQ(s.p99, 99.0);
  EXPECT_EQ(ComputeStageStats({}).count, 0);
}

TEST(ReportTest, MarkdownTablesHaveTheSeedShape) {
  const auto s = Summarize(HandMadeResult().records, 1.5);
  const std::string t1 = MarkdownTimeTable(s);
  EXPECT_NE(t1.find("| Detector | Method | front,1m |"), std::string::npos) << t1;
  EXPECT_NE(t1.find("| orb | BF knn+ratio (OpenCV) | 5.00 / 15.0 |"), std::string::npos) << t1;
  const std::string t2 = MarkdownMatchTable(s);
  EXPECT_NE(t2.find("| orb | BF knn+ratio (OpenCV) | 3.0 / 1.0 |"), std::string::npos) << t2;
  EXPECT_NE(t2.find("| orb | IMU-guided | 4.0 / 0.0 |"), std::string::npos) << t2;
  const std::string report = MarkdownReport(HandMadeResult(), Context());
  EXPECT_NE(report.find("Table I"), std::string::npos);
  EXPECT_NE(report.find("Table II"), std::string::npos);
  EXPECT_NE(report.find("IMU interval not available"), std::string::npos);
  // Means per pair: aligned (3 + 3) / 2, by the larger patch 1 / 2, flat 1 / 2, border 1 / 2,
  // dropped 2 / 2, steps (12 + 20) / 6 aligned; brute force has no row.
  const std::string refine = MarkdownRefinementTable(HandMadeResult().records);
  EXPECT_NE(refine.find("| front,1m | orb | IMU-guided | 2 | 3.0 | 0.5 | 0.5 / 0.5 | 1.0 | 5.3 |"),
            std::string::npos)
      << refine;
  EXPECT_EQ(refine.find("BF knn"), std::string::npos) << refine;
  EXPECT_NE(report.find("## Sub-pixel refinement"), std::string::npos);
  const std::string thr = MarkdownThresholdTable(HandMadeResult().records, {1.0, 10.0});
  EXPECT_NE(thr.find("| orb | BF knn+ratio (OpenCV) | 0.667 | 1.000 |"), std::string::npos) << thr;
}

TEST(ReportTest, CsvQuotesAndCounts) {
  std::ostringstream out;
  WritePairsCsv(out, HandMadeResult().records, 1.5);
  std::istringstream in(out.str());
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("case,pair,frame_a", 0), 0u);
  std::getline(in, line);
  EXPECT_EQ(line.rfind("\"front,1m\",0,0,1,", 0), 0u) << line;
  EXPECT_NE(line.find(",bf,"), std::string::npos);
  EXPECT_NE(line.find(",3,2,1,4,"), std::string::npos) << line;  // matches,correct,false,possible
  int rows = 1;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 4);  // 2 pairs x 2 methods
  EXPECT_EQ(CsvField("a\"b"), "\"a\"\"b\"");
  EXPECT_EQ(CsvField("plain"), "plain");
  std::ostringstream skipped;
  WriteSkippedCsv(skipped, HandMadeResult().skipped);
  EXPECT_NE(skipped.str().find("\"front,1m\",2,2,3,,IMU interval not available: gap\n"),
            std::string::npos)
      << skipped.str();
}

TEST(ReportTest, JsonRoundTrip) {
  ReportContext ctx = Context();
  ctx.fixed_thresholds = {1.0, 10.0};
  const std::string text = ReportToJson(HandMadeResult(), ctx).dump();
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_DOUBLE_EQ(j["threshold"]["threshold_px"].get<double>(), 1.5);
  ASSERT_EQ(j["summary"].size(), 2u);
  EXPECT_EQ(j["summary"][0]["method"], "bf");
  EXPECT_NEAR(j["summary"][0]["precision"].get<double>(), 2.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(j["summary"][1]["correct"].get<double>(), 4.0);
  EXPECT_EQ(j["pairs"].size(), 4u);
  EXPECT_EQ(j["pairs"][0]["case"], "front,1m");
  int with_refinement = 0;
  for (const auto& p : j["pairs"]) {
    if (!p.contains("refinement")) continue;
    ++with_refinement;
    EXPECT_EQ(p["method"], "guided");
    // The matches that stayed (4 per run) were aligned or left unrefined.
    EXPECT_EQ(p["refinement"]["aligned"].get<int>() + p["refinement"]["unrefined_flat"].get<int>() +
                  p["refinement"]["unrefined_border"].get<int>(),
              p["matches"].get<int>());
  }
  EXPECT_EQ(with_refinement, 2);
  EXPECT_EQ(j["skipped"].size(), 1u);
  EXPECT_EQ(j["config"]["detectors"], "orb");
  EXPECT_TRUE(j["end_to_end"].is_null());
  EXPECT_EQ(j["precision_at"].size(), 4u);  // 2 thresholds x 2 rows
  EXPECT_TRUE(j["time_offsets"].empty());   // none measured (no recorded IMU)
  // A measured clock offset is written per case and detector.
  EvaluationResult with_offset = HandMadeResult();
  TimeOffsetEstimate est;
  est.measured = true;
  est.offset_s = 0.0098;
  est.sigma_s = 2e-4;
  est.jackknife_sigma_s = 1.5e-4;
  est.observations = 149;
  est.inliers = 141;
  with_offset.time_offsets.push_back({"front,1m", DetectorKind::kOrb, est});
  const nlohmann::json k = ReportToJson(with_offset, ctx);
  ASSERT_EQ(k["time_offsets"].size(), 1u);
  EXPECT_EQ(k["time_offsets"][0]["case"], "front,1m");
  EXPECT_EQ(k["time_offsets"][0]["detector"], "orb");
  EXPECT_TRUE(k["time_offsets"][0]["measured"].get<bool>());
  EXPECT_DOUBLE_EQ(k["time_offsets"][0]["offset_s"].get<double>(), 0.0098);
  EXPECT_DOUBLE_EQ(k["time_offsets"][0]["sigma_s"].get<double>(), 2e-4);
  EXPECT_DOUBLE_EQ(k["time_offsets"][0]["jackknife_sigma_s"].get<double>(), 1.5e-4);
  EXPECT_EQ(k["time_offsets"][0]["inliers"].get<int>(), 141);
  // Not measured: no number that could be read as exact, the reason instead.
  TimeOffsetEstimate unmeasured;
  unmeasured.offset_s = 0.05;  // where a search's grid stopped
  unmeasured.reason = "the cost falls towards the edge of the +-50 ms searched";
  with_offset.time_offsets.push_back({"front,1m", DetectorKind::kSift, unmeasured});
  const nlohmann::json u = ReportToJson(with_offset, ctx)["time_offsets"][1];
  EXPECT_FALSE(u["measured"].get<bool>());
  EXPECT_TRUE(u["offset_s"].is_null());
  EXPECT_TRUE(u["sigma_s"].is_null());
  EXPECT_TRUE(u["jackknife_sigma_s"].is_null());
  EXPECT_EQ(u["reason"], unmeasured.reason);
}

TEST(ReportTest, WritesFilesAndPlots) {
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("imumatch_report_test_" + std::to_string(::getpid())))
                              .string();
  const auto files = WriteReportFiles(dir, HandMadeResult(), Context());
  EXPECT_EQ(files.size(), 5u);
  std::ifstream json(dir + "/report.json");
  const nlohmann::json j = nlohmann::json::parse(json);
  EXPECT_EQ(j["summary"].size(), 2u);
  const auto plots = WritePerPairPlots(dir, HandMadeResult().records, 1.5);
  EXPECT_EQ(plots.size(), 2u);
  for (const auto& p : plots) EXPECT_GT(std::filesystem::file_size(p), 1000u);
  std::filesystem::remove_all(dir);
}

TEST(PlotsTest, NiceTicks) {
  const auto t = NiceTicks(0.0, 1.0, 5);
  ASSERT_EQ(t.size(), 6u);  // step 0.2
  EXPECT_DOUBLE_EQ(t[1], 0.2);
  const auto u = NiceTicks(3.0, 97.0, 6);  // step 20: 20 40 60 80
  ASSERT_EQ(u.size(), 4u);
  EXPECT_DOUBLE_EQ(u[0], 20.0);
  EXPECT_DOUBLE_EQ(u[3], 80.0);
}

TEST(PlotsTest, DrawsSeriesInTheirColour) {
  PlotOptions o;
  o.title = "t";
  PlotSeries s{"line", {0, 1, 2}, {0, 1, 2}, cv::Scalar(255, 0, 0)};
  const cv::Mat img = DrawLinePlot({s}, o);
  ASSERT_EQ(img.cols, o.width);
  int blue = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const auto p = img.at<cv::Vec3b>(y, x);
      if (p[0] > 200 && p[1] < 60 && p[2] < 60) ++blue;
    }
  }
  EXPECT_GT(blue, 500);
  PlotSeries bad{"bad", {0, 1}, {0}, cv::Scalar()};
  EXPECT_THROW(DrawLinePlot({bad}, o), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
