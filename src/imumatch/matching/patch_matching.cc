#include "imumatch/matching/patch_matching.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "imumatch/core/error.h"
#include "imumatch/matching/patch_alignment.h"
#include "imumatch/matching/subpixel_refinement.h"

namespace imumatch {

void PatchMatchingOptions::Check() const {
  IMUMATCH_CHECK(half_size >= 2 && half_size <= 15,
                 "PatchMatchingOptions.half_size must be in [2, 15], got " << half_size);
  IMUMATCH_CHECK(max_iterations >= 1 && max_iterations <= 100,
                 "PatchMatchingOptions.max_iterations must be in [1, 100], got " << max_iterations);
  IMUMATCH_CHECK(std::isfinite(convergence_px) && convergence_px > 0.0,
                 "PatchMatchingOptions.convergence_px must be > 0, got " << convergence_px);
  IMUMATCH_CHECK(std::isfinite(min_texture) && min_texture >= 0.0,
                 "PatchMatchingOptions.min_texture must be >= 0, got " << min_texture);
  IMUMATCH_CHECK(std::isfinite(max_shift_px) && max_shift_px > 0.0,
                 "PatchMatchingOptions.max_shift_px must be > 0, got " << max_shift_px);
  IMUMATCH_CHECK(
      min_correlation >= -1.0 && min_correlation <= 1.0,
      "PatchMatchingOptions.min_correlation must be in [-1, 1], got " << min_correlation);
  IMUMATCH_CHECK(
      max_candidates >= 1 && max_candidates <= 4096,
      "PatchMatchingOptions.max_candidates must be in [1, 4096], got " << max_candidates);
}

namespace {

// The queries worth a second look: candidates in the window, none accepted for a reason that the
// detector's own direction or scale can cause.
bool Rejected(QueryOutcome outcome) {
  return outcome == QueryOutcome::kOrientation || outcome == QueryOutcome::kDistanceThreshold ||
         outcome == QueryOutcome::kRatioTest;
}

void MoveToMatched(QueryOutcome outcome, MatchStats* stats) {
  switch (outcome) {
    case QueryOutcome::kOrientation:
      --stats->orientation;
      break;
    case QueryOutcome::kDistanceThreshold:
      --stats->distance_threshold;
      break;
    case QueryOutcome::kRatioTest:
      --stats->ratio_test;
      break;
    default:
      break;
  }
  ++stats->matched;
}

struct Found {
  int query, train;
  float correlation, cost;
  Eigen::Vector2f xy;
};

}  // namespace

PatchMatchingStats MatchByPatch(
    const std::vector<KeypointPrediction>& predictions, const std::vector<KeypointInfo>& ideal_a,
    const std::vector<cv::KeyPoint>& keypoints_a, const DescriptorView& descriptors_a,
    const std::vector<KeypointInfo>& ideal_b, const GridIndex& grid_b,
    const std::vector<cv::KeyPoint>& keypoints_b, const DescriptorView& descriptors_b,
    const cv::Mat& gray_a, const cv::Mat& gray_b, const PinholeCamera& camera,
    const GuidedMatcherOptions& guided, const PatchMatchingOptions& options, MatchResult* result) {
  IMUMATCH_CHECK(result != nullptr, "MatchByPatch needs a result");
  guided.Check();
  options.Check();
  const size_t n = ideal_a.size(), m = ideal_b.size();
  IMUMATCH_CHECK(predictions.size() == n && keypoints_a.size() == n &&
                     descriptors_a.rows == static_cast<int>(n) && result->outcomes.size() == n,
                 "MatchByPatch: frame A has "
                     << n << " keypoints, " << keypoints_a.size() << " image keypoints, "
                     << predictions.size() << " predictions, " << descriptors_a.rows
                     << " descriptors, " << result->outcomes.size() << " outcomes");
  IMUMATCH_CHECK(keypoints_b.size() == m && descriptors_b.rows == static_cast<int>(m) &&
                     grid_b.size() == static_cast<int>(m),
                 "MatchByPatch: frame B has " << m << " keypoints, " << keypoints_b.size()
                                              << " image keypoints, " << descriptors_b.rows
                                              << " descriptors, a grid of " << grid_b.size());
  IMUMATCH_CHECK(
      !gray_a.empty() && !gray_b.empty() && gray_a.type() == CV_8UC1 && gray_b.type() == CV_8UC1,
      "MatchByPatch needs two non-empty 8-bit gray images");
  CheckCompatible(descriptors_a, descriptors_b);
  PatchMatchingStats stats;
  if (n == 0 || m == 0) return stats;

  const DescriptorNorm norm = descriptors_a.norm;
  const bool l2 = norm == DescriptorNorm::kL2;
  const int bytes = descriptors_a.bytes;
  const DescriptorCostFn cost = SelectCostFunction(norm, bytes);
  const std::vector<uint8_t> zeros(static_cast<size_t>(bytes), 0);
  const float max_hamming = static_cast<float>(guided.max_hamming_fraction * bytes * 8);
  const float max_l2_rel2 = static_cast<float>(guided.max_l2_relative * guided.max_l2_relative);
  const float scale_tol = static_cast<float>(guided.scale_tolerance_factor);
  const float max_shift2 = static_cast<float>(options.max_shift_px * options.max_shift_px);
  const float min_corr = static_cast<float>(options.min_correlation);
  PatchAlignOptions align;
  align.max_iterations = options.max_iterations;
  align.convergence_px = static_cast<float>(options.convergence_px);
  align.min_texture = static_cast<float>(options.min_texture);

  const float reference_a = ReferenceKeypointSize(ideal_a);
  const float reference_b = ReferenceKeypointSize(ideal_b);
  // A keypoint's squared localisation factor f^2 (see shift_grows_with_scale; 1 when off).
  const auto factor2 = [&options](float size, float reference) {
    if (!options.shift_grows_with_scale) return 1.0f;
    const double f = SizeSigmaFactor(size, reference, 1.0);
    return static_cast<float>(f * f);
  };

  std::vector<char> taken(m, 0);
  for (const Match& mt : result->matches) taken[static_cast<size_t>(mt.train_idx)] = 1;

  PatchTemplate tpl(2 * options.half_size);
  std::vector<int> slots, candidates;
  std::vector<Found> found;
  for (size_t i = 0; i < n; ++i) {
    const KeypointPrediction& p = predictions[i];
    if (!Rejected(result->outcomes[i]) || !p.HasWindow()) continue;
    const KeypointInfo& ka = ideal_a[i];
    const bool check_size = guided.check_scale && ka.size > 0.0f;
    const float size_lo = ka.size * p.scale_min / scale_tol;
    const float size_hi = ka.size * p.scale_max * scale_tol;
    slots.clear();
    grid_b.CollectSlotsInBox(p.min_x, p.min_y, p.max_x, p.max_y, &slots);
    candidates.clear();
    for (const int slot : slots) {
      const int j = grid_b.slot_index(slot);
      const KeypointInfo& kb = ideal_b[static_cast<size_t>(j)];
      if (taken[static_cast<size_t>(j)] || !p.Contains(kb.x, kb.y)) continue;
      if (check_size && kb.size > 0.0f && !(kb.size >= size_lo && kb.size <= size_hi)) continue;
      candidates.push_back(j);
    }
    if (candidates.empty() || static_cast<int>(candidates.size()) > options.max_candidates) {
      continue;
    }
    ++stats.queries;
    // A's patch warped as the prediction says B shows it (the lens's Jacobian at the first
    // candidate: the window is small against the lens's variation).
    const cv::KeyPoint& kpa = keypoints_a[i];
    const Eigen::Vector2f pa(kpa.pt.x, kpa.pt.y);
    const cv::KeyPoint& first = keypoints_b[static_cast<size_t>(candidates[0])];
    const Eigen::Matrix2f affine =
        PatchWarpInImage(p, camera, pa, Eigen::Vector2f(first.pt.x, first.pt.y));
    if (!(std::fabs(affine.determinant()) > 1e-3f)) continue;
    const Eigen::Matrix2f inv = affine.inverse();
    AlignStatus built = tpl.Build(gray_a, pa, inv, options.half_size, align.min_texture);
    if (built == AlignStatus::kTexture) {
      built = tpl.Build(gray_a, pa, inv, 2 * options.half_size, align.min_texture);
    }
    if (built != AlignStatus::kAligned) continue;
    // Every candidate: where the template aligns from it, and how well. Two places are distinct
    // when farther apart than the limit of two keypoints of A's scale.
    const float fa2 = factor2(ka.size, reference_a);
    const float place_spacing2 = max_shift2 * fa2;
    int best = -1, places = 0;
    float best_corr = -2.0f, best_d2 = 0.0f;
    Eigen::Vector2f place = Eigen::Vector2f::Zero(), best_xy = Eigen::Vector2f::Zero();
    int64_t iterations = 0;
    for (const int j : candidates) {
      const cv::KeyPoint& kb = keypoints_b[static_cast<size_t>(j)];
      const Eigen::Vector2f pb(kb.pt.x, kb.pt.y);
      Eigen::Vector2f xy;
      ++stats.aligned;
      if (tpl.Align(gray_b, pb, align, &xy, &iterations) != AlignStatus::kAligned) continue;
      const float d2 = (xy - pb).squaredNorm();
      const float fb2 = factor2(ideal_b[static_cast<size_t>(j)].size, reference_b);
      if (d2 > max_shift2 * 0.5f * (fa2 + fb2)) continue;
      const float corr = tpl.Correlation(gray_b, xy);
      if (!(corr >= min_corr)) continue;
      if (places == 0 || (xy - place).squaredNorm() > place_spacing2) {
        ++places;
        place = xy;
      }
      // The keypoint nearest to where the patch aligns is the match.
      if (best < 0 || d2 < best_d2) {
        best = j;
        best_d2 = d2;
        best_xy = xy;
        best_corr = corr;
      }
    }
    if (places == 0) continue;
    if (places > 1) {
      ++stats.ambiguous;
      continue;
    }
    const uint8_t* da = descriptors_a.Row(static_cast<int>(i));
    const uint8_t* db = descriptors_b.Row(best);
    const float c = cost(da, db, bytes);
    if (options.require_distance_threshold) {
      const float max_cost =
          l2 ? max_l2_rel2 * 0.5f * (cost(da, zeros.data(), bytes) + cost(db, zeros.data(), bytes))
             : max_hamming;
      if (c > max_cost) continue;
    }
    found.push_back({static_cast<int>(i), best, best_corr, c, best_xy});
  }

  // One query per keypoint of B: the highest correlation (then the lower query) keeps it.
  std::vector<int> owner(m, -1);
  for (size_t f = 0; f < found.size(); ++f) {
    int& o = owner[static_cast<size_t>(found[f].train)];
    if (o < 0 || found[f].correlation > found[static_cast<size_t>(o)].correlation) {
      o = static_cast<int>(f);
    }
  }
  for (size_t f = 0; f < found.size(); ++f) {
    const Found& fd = found[f];
    if (owner[static_cast<size_t>(fd.train)] != static_cast<int>(f)) {
      ++stats.taken;
      continue;
    }
    Match match;
    match.query_idx = fd.query;
    match.train_idx = fd.train;
    match.distance = CostToDistance(norm, fd.cost);
    match.predicted_uv = predictions[static_cast<size_t>(fd.query)].uv;
    match.refined_uv_b = fd.xy;
    MoveToMatched(result->outcomes[static_cast<size_t>(fd.query)], &result->stats);
    result->outcomes[static_cast<size_t>(fd.query)] = QueryOutcome::kMatched;
    result->matches.push_back(match);
    ++stats.matched;
  }
  std::sort(result->matches.begin(), result->matches.end(),
            [](const Match& a, const Match& b) { return a.query_idx < b.query_idx; });
  return stats;
}

PatchMatchingStats MatchByPatch(const GuidedMatcherWorkspace& workspace,
                                const std::vector<cv::KeyPoint>& keypoints_a,
                                const cv::Mat& descriptors_a,
                                const std::vector<cv::KeyPoint>& keypoints_b,
                                const cv::Mat& descriptors_b, const cv::Mat& gray_a,
                                const cv::Mat& gray_b, const PinholeCamera& camera,
                                const GuidedMatcherOptions& guided,
                                const PatchMatchingOptions& options, MatchResult* result) {
  IMUMATCH_CHECK(keypoints_a.size() == workspace.ideal_keypoints_a().size() &&
                     keypoints_b.size() == workspace.ideal_keypoints_b().size(),
                 "MatchByPatch: " << keypoints_a.size() << " / " << keypoints_b.size()
                                  << " keypoints, but the workspace's last Match() had "
                                  << workspace.ideal_keypoints_a().size() << " / "
                                  << workspace.ideal_keypoints_b().size());
  return MatchByPatch(workspace.predictions(), workspace.ideal_keypoints_a(), keypoints_a,
                      DescriptorView::FromMat(descriptors_a), workspace.ideal_keypoints_b(),
                      workspace.grid_b(), keypoints_b, DescriptorView::FromMat(descriptors_b),
                      gray_a, gray_b, camera, guided, options, result);
}

}  // namespace imumatch
