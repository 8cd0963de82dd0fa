#include "imumatch/eval/summary.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>
#include <tuple>

#include "imumatch/core/error.h"

namespace imumatch {

ThresholdChoice ChooseThreshold(const EvaluationResult& result, bool exact_ground_truth,
                                std::optional<double> explicit_px) {
  ThresholdChoice choice;
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  if (explicit_px) {
    IMUMATCH_CHECK(std::isfinite(*explicit_px) && *explicit_px > 0.0,
                   "threshold = " << *explicit_px);
    choice.threshold_px = *explicit_px;
    out << "threshold " << choice.threshold_px << " px (given)";
  } else if (exact_ground_truth) {
    choice.threshold_px = 1.5;
    out << "threshold 1.50 px (exact synthetic ground truth)";
  } else {
    std::vector<float> residuals;
    for (const DetectorPairRecord& rec : result.records) {
      for (const MethodRun& run : rec.runs) {
        if (run.method != MatchMethod::kBruteForce && run.method != MatchMethod::kOwnBruteForce)
          continue;
        for (const MatchResidual& r : run.residuals) {
          if (r.kind == ResidualKind::kDepth) residuals.push_back(r.residual_px);
        }
        break;  // one brute-force method per record is enough
      }
    }
    const AutoThreshold a = ComputeAutoThreshold(residuals);
    choice.automatic = a;
    choice.threshold_px = a.threshold_px;
    out << a.Describe();
  }
  choice.description = out.str();
  return choice;
}

// ---------------------------------------------------------------------------------------------

StageStats ComputeStageStats(std::vector<double> values) {
  StageStats s;
  s.count = static_cast<int>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  double sum = 0.0;
  for (double v : values) sum += v;
  s.mean = sum / static_cast<double>(values.size());
  auto rank = [&](double q) {
    const size_t k = static_cast<size_t>(std::ceil(q * static_cast<double>(values.size())));
    return values[std::min(values.size() - 1, k == 0 ? 0 : k - 1)];
  };
  s.p50 = rank(0.50);
  s.p90 = rank(0.90);
  s.p99 = rank(0.99);
  return s;
}

RunCounts CountRun(const DetectorPairRecord& record, const MethodRun& run, double threshold_px) {
  RunCounts c;
  c.counts = CountCorrect(run.residuals, threshold_px);
  c.possible = CountPossibleCorrespondences(record.candidates, threshold_px);
  c.precision =
      c.counts.matches > 0 ? static_cast<double>(c.counts.correct) / c.counts.matches : 0.0;
  c.recall = c.possible > 0
                 ? std::min(1.0, static_cast<double>(c.counts.correct_by_depth) / c.possible)
                 : 0.0;
  return c;
}

void WindowRecall::Add(const WindowRecall& other) {
  checked += other.checked;
  inside += other.inside;
  missed_with_depth += other.missed_with_depth;
  missed_without_depth += other.missed_without_depth;
  missed_beyond_segment += other.missed_beyond_segment;
  missed_no_prediction += other.missed_no_prediction;
}

WindowRecall ComputeWindowRecall(const DetectorPairRecord& record, const MethodRun& run,
                                 double threshold_px) {
  WindowRecall w;
  if (record.bf_run < 0 || run.bf_partner_in_window.empty()) return w;
  const MethodRun& bf = record.runs[static_cast<size_t>(record.bf_run)];
  if (bf.residuals.size() != run.bf_partner_in_window.size()) return w;
  for (size_t k = 0; k < bf.residuals.size(); ++k) {
    if (!bf.residuals[k].CorrectAt(threshold_px)) continue;
    ++w.checked;
    if (run.bf_partner_in_window[k]) {
      ++w.inside;
      continue;
    }
    switch (run.bf_partner_prediction[k]) {
      case PredictionStatus::kWithDepth:
        ++w.missed_with_depth;
        break;
      case PredictionStatus::kWithoutDepth:
        ++w.missed_without_depth;
        if (k < run.bf_partner_beyond_segment.size() && run.bf_partner_beyond_segment[k]) {
          ++w.missed_beyond_segment;
        }
        break;
      default:
        ++w.missed_no_prediction;
        break;
    }
  }
  return w;
}

namespace {
// BruteForceFate's counts and their names, once for Add() and Named().
constexpr std::pair<const char*, int BruteForceFate::*> kFateFields[] = {
    {"checked", &BruteForceFate::checked},
    {"kept", &BruteForceFate::kept},
    {"matched_wrong", &BruteForceFate::matched_wrong},
    {"refine_dropped", &BruteForceFate::refine_dropped},
    {"no_prediction", &BruteForceFate::no_prediction},
    {"no_candidate", &BruteForceFate::no_candidate},
    {"inconsistent", &BruteForceFate::inconsistent},
    {"distance", &BruteForceFate::distance},
    {"ratio", &BruteForceFate::ratio},
    {"mutual", &BruteForceFate::mutual},
    {"gained", &BruteForceFate::gained}};
}  // namespace

void BruteForceFate::Add(const BruteForceFate& other) {
  for (const auto& [name, field] : kFateFields) this->*field += other.*field;
}

std::vector<std::pair<const char*, int>> BruteForceFate::Named() const {
  std::vector<std::pair<const char*, int>> out;
  for (const auto& [name, field] : kFateFields) out.emplace_back(name, this->*field);
  return out;
}

BruteForceFate ComputeBruteForceFate(const DetectorPairRecord& record, const MethodRun& run,
                                     double threshold_px) {
  BruteForceFate f;
  if (record.bf_run < 0 || run.bf_query_match.empty()) return f;
  const MethodRun& bf = record.runs[static_cast<size_t>(record.bf_run)];
  if (bf.residuals.size() != run.bf_query_match.size() ||
      run.match_bf_match.size() != run.residuals.size()) {
    return f;
  }
  for (size_t k = 0; k < bf.residuals.size(); ++k) {
    if (!bf.residuals[k].CorrectAt(threshold_px)) continue;
    ++f.checked;
    const int j = run.bf_query_match[k];
    if (j >= 0) {
      ++(run.residuals[static_cast<size_t>(j)].CorrectAt(threshold_px) ? f.kept : f.matched_wrong);
      continue;
    }
    switch (run.bf_query_outcome[k]) {
      case QueryOutcome::kMatched:
        ++f.refine_dropped;
        break;
      case QueryOutcome::kNoPrediction:
      case QueryOutcome::kBehindCamera:
      case QueryOutcome::kOutsideImage:
        ++f.no_prediction;
        break;
      case QueryOutcome::kNoCandidateInWindow:
        ++f.no_candidate;
        break;
      case QueryOutcome::kOrientation:
      case QueryOutcome::kScale:
        ++f.inconsistent;
        break;
      case QueryOutcome::kDistanceThreshold:
        ++f.distance;
        break;
      case QueryOutcome::kRatioTest:
        ++f.ratio;
        break;
      case QueryOutcome::kMutual:
        ++f.mutual;
        break;
    }
  }
  for (size_t j = 0; j < run.residuals.size(); ++j) {
    if (!run.residuals[j].CorrectAt(threshold_px)) continue;
    const int k = run.match_bf_match[j];
    if (k < 0 || !bf.residuals[static_cast<size_t>(k)].CorrectAt(threshold_px)) ++f.gained;
  }
  return f;
}

std::vector<DetectorPairRecord> SplitByDepth(const std::vector<DetectorPairRecord>& records) {
  std::vector<DetectorPairRecord> out = records;
  for (DetectorPairRecord& r : out) r.case_name += r.has_depth ? " [depth]" : " [no depth]";
  return out;
}

std::vector<MethodSummary> Summarize(const std::vector<DetectorPairRecord>& records,
                                     double threshold_px) {
  // Keys in order of first appearance of the case, then detector and method enum order.
  std::vector<std::string> cases;
  for (const auto& r : records) {
    if (std::find(cases.begin(), cases.end(), r.case_name) == cases.end())
      cases.push_back(r.case_name);
  }
  struct Acc {
    std::vector<double> read, extract, predict, match, total;
    double keypoints = 0, matches = 0, correct = 0, wrong = 0, possible = 0, correct_depth = 0,
           epipolar = 0;
    WindowRecall window;
    int pairs = 0;
  };
  std::map<std::tuple<size_t, int, int>, Acc> acc;
  for (const auto& r : records) {
    const size_t case_index =
        static_cast<size_t>(std::find(cases.begin(), cases.end(), r.case_name) - cases.begin());
    for (const MethodRun& run : r.runs) {
      Acc& a = acc[{case_index, static_cast<int>(r.detector), static_cast<int>(run.method)}];
      const RunCounts c = CountRun(r, run, threshold_px);
      const double motion = UsesPrediction(run.method) ? r.motion_ms : 0.0;
      a.read.push_back(r.read_ms);
      a.extract.push_back(r.extract_ms);
      a.predict.push_back(run.predict_ms + motion);
      a.match.push_back(run.match_ms + run.refine_ms);  // refinement is part of matching
      a.total.push_back(r.extract_ms + motion + run.predict_ms + run.match_ms + run.refine_ms);
      a.keypoints += 0.5 * (r.keypoints_a + r.keypoints_b);
      a.matches += c.counts.matches;
      a.correct += c.counts.correct;
      a.wrong += c.counts.wrong;
      a.possible += c.possible;
      a.correct_depth += c.counts.correct_by_depth;
      a.epipolar += c.counts.matches - c.counts.judged_by_depth;
      a.window.Add(ComputeWindowRecall(r, run, threshold_px));
      ++a.pairs;
    }
  }
  std::vector<MethodSummary> out;
  for (const auto& [key, a] : acc) {
    MethodSummary s;
    s.case_name = cases[std::get<0>(key)];
    s.detector = static_cast<DetectorKind>(std::get<1>(key));
    s.method = static_cast<MatchMethod>(std::get<2>(key));
    s.pairs = a.pairs;
    const double n = std::max(1, a.pairs);
    s.keypoints = a.keypoints / n;
    s.read_ms = ComputeStageStats(a.read);
    s.extract_ms = ComputeStageStats(a.extract);
    s.predict_ms = ComputeStageStats(a.predict);
    s.match_ms = ComputeStageStats(a.match);
    s.total_ms = ComputeStageStats(a.total);
    s.matches = a.matches / n;
    s.correct = a.correct / n;
    s.wrong = a.wrong / n;
    s.possible = a.possible / n;
    s.precision = a.matches > 0 ? a.correct / a.matches : 0.0;
    s.recall = a.possible > 0 ? std::min(1.0, a.correct_depth / a.possible) : 0.0;
    s.epipolar_fraction = a.matches > 0 ? a.epipolar / a.matches : 0.0;
    s.window_checked = a.window.checked;
    s.window_missed = a.window.checked - a.window.inside;
    s.window_recall = a.window.Recall();
    out.push_back(s);
  }
  return out;
}

}  // namespace imumatch
