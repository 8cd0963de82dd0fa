#include "imumatch/eval/report_tables.h"

#include <algorithm>
#include <iomanip>
#include <map>
#include <sstream>
#include <tuple>

namespace imumatch {
namespace {

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

// Accumulators per case, detector and method, for the tables of per-pair run details: cases in
// the order they first appear, then detector and method enum order.
template <typename Acc>
class RunTable {
 public:
  Acc& At(const DetectorPairRecord& record, const MethodRun& run) {
    NoteCase(record);
    return acc_[{record.case_name, static_cast<int>(record.detector),
                 static_cast<int>(run.method)}];
  }
  // A case keeps its place in the order even without rows.
  void NoteCase(const DetectorPairRecord& record) {
    if (std::find(order_.begin(), order_.end(), record.case_name) == order_.end())
      order_.push_back(record.case_name);
  }
  bool empty() const { return acc_.empty(); }
  // Writes "| case | detector | method | " and then row(out, acc) for every row.
  template <typename RowFn>
  void Write(std::ostream& out, RowFn row) const {
    for (const auto& c : order_) {
      for (const auto& [key, a] : acc_) {
        if (std::get<0>(key) != c) continue;
        out << "| " << c << " | " << ToString(static_cast<DetectorKind>(std::get<1>(key))) << " | "
            << DisplayName(static_cast<MatchMethod>(std::get<2>(key))) << " | ";
        row(out, a);
      }
    }
  }

 private:
  std::map<std::tuple<std::string, int, int>, Acc> acc_;
  std::vector<std::string> order_;
};

}  // namespace

std::string FormatFixed(double v, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << v;
  return out.str();
}

std::string MarkdownTimeTable(const std::vector<MethodSummary>& summaries) {
  return CaseTable(summaries, [](const MethodSummary& s) {
    return FormatFixed(s.match_ms.mean, 2) + " / " + FormatFixed(s.total_ms.mean, 1);
  });
}

std::string MarkdownMatchTable(const std::vector<MethodSummary>& summaries) {
  return CaseTable(summaries, [](const MethodSummary& s) {
    return FormatFixed(s.matches, 1) + " / " + FormatFixed(s.wrong, 1);
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
        << " | " << s.pairs << " | " << FormatFixed(s.keypoints, 0) << " | "
        << FormatFixed(s.read_ms.mean, 1) << " | " << FormatFixed(s.extract_ms.mean, 1) << " | "
        << FormatFixed(s.predict_ms.mean, 2) << " | " << FormatFixed(s.match_ms.mean, 2) << " / "
        << FormatFixed(s.match_ms.p50, 2) << " / " << FormatFixed(s.match_ms.p90, 2) << " / "
        << FormatFixed(s.match_ms.p99, 2) << " | " << FormatFixed(s.total_ms.mean, 1) << " | "
        << FormatFixed(s.matches, 1) << " | " << FormatFixed(s.correct, 1) << " | "
        << FormatFixed(s.wrong, 1) << " | " << FormatFixed(s.precision, 3) << " | "
        << (s.possible > 0.0 ? FormatFixed(s.recall, 3) : std::string("n/a (no depth)")) << " |\n";
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
      out << "| " << c << " | " << ToString(d) << " | " << FormatFixed(b->match_ms.mean, 2) << " | "
          << FormatFixed(guided_ms, 2) << " | x"
          << FormatFixed(guided_ms > 0 ? b->match_ms.mean / guided_ms : 0.0, 1) << " | "
          << FormatFixed(b->correct, 1) << " | " << FormatFixed(g->correct, 1) << " | "
          << FormatFixed(b->precision, 3) << " | " << FormatFixed(g->precision, 3) << " | "
          << (g->window_recall >= 0.0 ? FormatFixed(g->window_recall, 4) : std::string("n/a"))
          << " |\n";
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
  RunTable<Acc> table;
  for (const auto& r : records) {
    table.NoteCase(r);
    for (const auto& run : r.runs) {
      if (!UsesPrediction(run.method)) continue;
      const WindowRecall w = ComputeWindowRecall(r, run, threshold_px);
      if (w.checked == 0) continue;
      Acc& a = table.At(r, run);
      a.w.Add(w);
      a.per_pair.push_back(w.Recall());
    }
  }
  std::ostringstream out;
  out << "| Case | Detector | Method | BF correct checked | pooled | worst pair | missed: with "
         "depth / epipolar (beyond its ends) / no prediction "
         "|\n|---|---|---|---:|---:|---:|---:|\n";
  table.Write(out, [](std::ostream& o, const Acc& a) {
    o << a.w.checked << " | " << FormatFixed(a.w.Recall(), 4) << " | "
      << FormatFixed(*std::min_element(a.per_pair.begin(), a.per_pair.end()), 3) << " | "
      << a.w.missed_with_depth << " / " << a.w.missed_without_depth << " ("
      << a.w.missed_beyond_segment << ") / " << a.w.missed_no_prediction << " |\n";
  });
  return out.str();
}

std::string MarkdownBruteForceFateTable(const std::vector<DetectorPairRecord>& records,
                                        double threshold_px) {
  RunTable<BruteForceFate> table;
  for (const auto& r : records) {
    table.NoteCase(r);
    for (const auto& run : r.runs) {
      if (!UsesPrediction(run.method)) continue;
      const BruteForceFate f = ComputeBruteForceFate(r, run, threshold_px);
      if (f.checked == 0 && f.gained == 0) continue;
      table.At(r, run).Add(f);
    }
  }
  if (table.empty()) return "";
  std::ostringstream out;
  out << "| Case | Detector | Method | BF correct | kept | matched wrong | not matched: ratio / "
         "inconsistent / distance / no candidate / no prediction / mutual / refinement | gained "
         "| net |\n|---|---|---|---:|---:|---:|---:|---:|---:|\n";
  table.Write(out, [](std::ostream& o, const BruteForceFate& f) {
    const int net = f.gained - (f.checked - f.kept);
    o << f.checked << " | " << f.kept << " | " << f.matched_wrong << " | " << f.ratio << " / "
      << f.inconsistent << " / " << f.distance << " / " << f.no_candidate << " / "
      << f.no_prediction << " / " << f.mutual << " / " << f.refine_dropped << " | " << f.gained
      << " | " << (net >= 0 ? "+" : "") << net << " |\n";
  });
  return out.str();
}

// Where the epipolar segments of keypoints without depth started (PredictKeypointsInScene), per
// case, detector and method; empty when no pair had keypoints without depth.
std::string MarkdownSceneNearTable(const std::vector<DetectorPairRecord>& records) {
  struct Acc {
    std::vector<double> near;  // segment_min_depth_m per pair
    double pilot_matches = 0.0;
    int moved = 0;
  };
  RunTable<Acc> table;
  for (const auto& r : records) {
    for (const auto& run : r.runs) {
      if (run.stats.predicted_without_depth == 0) continue;
      Acc& a = table.At(r, run);
      a.near.push_back(run.scene_near.segment_min_depth_m);
      a.pilot_matches += run.scene_near.pilot_matches;
      a.moved += run.scene_near.moved ? 1 : 0;
    }
  }
  if (table.empty()) return "";
  std::ostringstream out;
  out << "| Case | Detector | Method | pairs | near end m: min / median / max | pairs moved | "
         "pilot matches (mean) |\n|---|---|---|---:|---:|---:|---:|\n";
  table.Write(out, [](std::ostream& o, const Acc& a) {
    const StageStats st = ComputeStageStats(a.near);
    const double pairs = static_cast<double>(a.near.size());
    o << a.near.size() << " | " << FormatFixed(*std::min_element(a.near.begin(), a.near.end()), 2)
      << " / " << FormatFixed(st.p50, 2) << " / "
      << FormatFixed(*std::max_element(a.near.begin(), a.near.end()), 2) << " | " << a.moved
      << " | " << FormatFixed(a.pilot_matches / pairs, 1) << " |\n";
  });
  return out.str();
}

// The second pass of the guided method per case, detector and method: how often it ran, why it
// did not, the fit's residual and the windows before and after; empty when it never was tried.
std::string MarkdownSecondPassTable(const std::vector<DetectorPairRecord>& records) {
  struct Acc {
    int tried = 0, ran = 0, disagreed = 0, not_tighter = 0, no_fit = 0;
    std::vector<double> sigma, first_window, window, truth_m2;
  };
  RunTable<Acc> table;
  for (const auto& r : records) {
    for (const auto& run : r.runs) {
      if (run.second_pass == SecondPassOutcome::kNotTried) continue;
      Acc& a = table.At(r, run);
      ++a.tried;
      a.first_window.push_back(run.first_window_px);
      a.window.push_back(run.window_px);
      if (run.refit.ok) {
        a.sigma.push_back(run.refit.sigma_px);
        a.truth_m2.push_back(run.refit_truth_mahalanobis2);
      }
      a.ran += run.second_pass == SecondPassOutcome::kRan ? 1 : 0;
      a.disagreed += run.second_pass == SecondPassOutcome::kFitDisagreed ? 1 : 0;
      a.not_tighter += run.second_pass == SecondPassOutcome::kNotTighter ? 1 : 0;
      a.no_fit += run.second_pass == SecondPassOutcome::kNoFit ? 1 : 0;
    }
  }
  if (table.empty()) return "";
  std::ostringstream out;
  out << "| Case | Detector | Method | pairs | second pass ran | first pass kept: fit disagreed "
         "with the IMU / windows not smaller / no fit (residuals beyond the keypoints' noise, too "
         "few) | fit residual sigma px: median / max | "
         "ground truth from the fit, squared Mahalanobis (6 dof): median / fits beyond 22.46 "
         "(99.9 %) | window half size px: first pass -> final (median) |\n"
         "|---|---|---|---:|---:|---:|---:|---:|---:|\n";
  table.Write(out, [](std::ostream& o, const Acc& a) {
    o << a.tried << " | " << a.ran << " | " << a.disagreed << " / " << a.not_tighter << " / "
      << a.no_fit << " | ";
    if (a.sigma.empty()) {
      o << "- | - | ";
    } else {
      o << FormatFixed(ComputeStageStats(a.sigma).p50, 2) << " / "
        << FormatFixed(*std::max_element(a.sigma.begin(), a.sigma.end()), 2) << " | "
        << FormatFixed(ComputeStageStats(a.truth_m2).p50, 2) << " / "
        << std::count_if(a.truth_m2.begin(), a.truth_m2.end(), [](double m2) { return m2 > 22.46; })
        << " | ";
    }
    o << FormatFixed(ComputeStageStats(a.first_window).p50, 1) << " -> "
      << FormatFixed(ComputeStageStats(a.window).p50, 1) << " |\n";
  });
  return out.str();
}

// The sub-pixel refinement per case, detector and method, mean per pair: matches aligned (and of
// them, those a drifting 9 x 9 patch only aligned at twice the size), left unrefined for lack of
// texture or at the border, dropped because A's patch was not found near B's keypoint. Empty
// when no run was refined.
std::string MarkdownRefinementTable(const std::vector<DetectorPairRecord>& records) {
  struct Acc {
    int pairs = 0;
    double refined = 0, recovered = 0, flat = 0, border = 0, dropped = 0, iterations = 0;
  };
  RunTable<Acc> table;
  for (const auto& r : records) {
    for (const auto& run : r.runs) {
      const SubpixelStats& st = run.refine_stats;
      if (st.refined + st.failed_texture + st.failed_border + st.failed_convergence == 0) continue;
      Acc& a = table.At(r, run);
      ++a.pairs;
      a.refined += st.refined;
      a.recovered += st.recovered_larger;
      a.flat += st.failed_texture;
      a.border += st.failed_border;
      a.dropped += st.failed_convergence;
      a.iterations += static_cast<double>(st.iterations);
    }
  }
  if (table.empty()) return "";
  std::ostringstream out;
  out << "| Case | Detector | Method | pairs | aligned | of them by the larger patch after a drift "
         "| unrefined: flat / border | dropped: not aligned within the shift | Gauss-Newton steps "
         "per aligned match |\n|---|---|---|---:|---:|---:|---:|---:|---:|\n";
  table.Write(out, [](std::ostream& o, const Acc& a) {
    const double n = a.pairs;
    o << a.pairs << " | " << FormatFixed(a.refined / n, 1) << " | "
      << FormatFixed(a.recovered / n, 1) << " | " << FormatFixed(a.flat / n, 1) << " / "
      << FormatFixed(a.border / n, 1) << " | " << FormatFixed(a.dropped / n, 1) << " | "
      << (a.refined > 0 ? FormatFixed(a.iterations / a.refined, 1) : std::string("-")) << " |\n";
  });
  return out.str();
}

std::string MarkdownPatchLookTable(const std::vector<DetectorPairRecord>& records,
                                   double threshold_px) {
  struct Acc {
    int pairs = 0;
    double queries = 0, aligned = 0, ambiguous = 0, matched = 0, kept = 0, correct = 0, ms = 0;
  };
  RunTable<Acc> table;
  for (const auto& r : records) {
    for (const auto& run : r.runs) {
      if (run.match_by_patch.empty() && run.patch.queries == 0) continue;
      Acc& a = table.At(r, run);
      ++a.pairs;
      a.queries += run.patch.queries;
      a.aligned += run.patch.aligned;
      a.ambiguous += run.patch.ambiguous;
      a.matched += run.patch.matched;
      a.ms += run.patch_ms;
      for (size_t j = 0; j < run.match_by_patch.size() && j < run.residuals.size(); ++j) {
        if (!run.match_by_patch[j]) continue;
        a.kept += 1;
        a.correct += run.residuals[j].CorrectAt(threshold_px) ? 1 : 0;
      }
    }
  }
  if (table.empty()) return "";
  std::ostringstream out;
  out << "| Case | Detector | Method | pairs | queries looked at again | candidates aligned | "
         "ambiguous | matches added | after refinement | of them correct | ms |\n"
         "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  table.Write(out, [](std::ostream& o, const Acc& a) {
    const double n = a.pairs;
    o << a.pairs << " | " << FormatFixed(a.queries / n, 1) << " | " << FormatFixed(a.aligned / n, 1)
      << " | " << FormatFixed(a.ambiguous / n, 1) << " | " << FormatFixed(a.matched / n, 1) << " | "
      << FormatFixed(a.kept / n, 1) << " | " << FormatFixed(a.correct / n, 1) << " | "
      << FormatFixed(a.ms / n, 2) << " |\n";
  });
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
    out << "| " << c << " | " << sr.count << " | " << FormatFixed(sr.p50, 4) << " / "
        << FormatFixed(sr.p90, 4) << " / " << FormatFixed(max_r, 4) << " | "
        << FormatFixed(st.p50, 2) << " / " << FormatFixed(st.p90, 2) << " / "
        << FormatFixed(max_t, 2) << " |\n";
  }
  return out.str();
}

std::string MarkdownThresholdTable(const std::vector<DetectorPairRecord>& records,
                                   const std::vector<double>& thresholds_px) {
  std::ostringstream out;
  out << "| Detector | Method |";
  for (double t : thresholds_px) out << " precision @" << FormatFixed(t, 1) << " px |";
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
      out << " " << (matches > 0 ? FormatFixed(correct / matches, 3) : std::string("-")) << " |";
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
          << DisplayName(m) << " | " << FormatFixed(t.queries / n, 1) << " | "
          << FormatFixed(t.tracked / n, 1) << " | " << FormatFixed(t.no_prediction / n, 1) << " | "
          << FormatFixed(t.border / n, 1) << " / " << FormatFixed(t.texture / n, 1) << " | "
          << FormatFixed(t.no_convergence / n, 1) << " | " << FormatFixed(t.forward_backward / n, 1)
          << " | " << FormatFixed(t.low_correlation / n, 1) << " | "
          << FormatFixed(t.ambiguous / n, 1) << " | " << FormatFixed(t.outside_window / n, 1)
          << " | "
          << (m == MatchMethod::kHybrid ? FormatFixed(a.from_tracks / n, 1) + " / " +
                                              FormatFixed(a.from_descriptors / n, 1)
                                        : std::string("-"))
          << " |\n";
    }
  }
  return out.str();
}

}  // namespace imumatch
