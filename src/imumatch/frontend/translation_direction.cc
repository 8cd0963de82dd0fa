#include "imumatch/frontend/translation_direction.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include <Eigen/Eigenvalues>

#include "imumatch/core/error.h"
#include "imumatch/core/statistics.h"

namespace imumatch {

double MedianEpipolarDistancePx(const std::vector<Eigen::Vector3d>& ra,
                                const std::vector<Eigen::Vector3d>& xb, const Eigen::Vector3d& t,
                                double f, std::vector<double>& scratch) {
  scratch.clear();
  for (size_t i = 0; i < ra.size(); ++i) {
    const Eigen::Vector3d l = t.cross(ra[i]);
    const double n2 = l.x() * l.x() + l.y() * l.y();
    if (n2 > 0.0) scratch.push_back(f * std::fabs(xb[i].dot(l)) / std::sqrt(n2));
  }
  if (scratch.empty()) return std::numeric_limits<double>::infinity();
  return UpperMedianInPlace(scratch);
}

Eigen::Vector3d EpipolarTranslationDirection(const std::vector<Eigen::Vector3d>& ra,
                                             const std::vector<Eigen::Vector3d>& xb,
                                             const Eigen::Vector3d& start, double f,
                                             double min_sigma, double cauchy_scale,
                                             std::vector<double>& scratch) {
  Eigen::Vector3d t = start.normalized();
  for (int round = 0; round < 3; ++round) {
    const double sigma =
        std::max(1.4826 * MedianEpipolarDistancePx(ra, xb, t, f, scratch), min_sigma);
    const double c2 = cauchy_scale * cauchy_scale * sigma * sigma;
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    for (size_t i = 0; i < ra.size(); ++i) {
      const Eigen::Vector3d l = t.cross(ra[i]);
      const double n2 = l.x() * l.x() + l.y() * l.y();
      if (!(n2 > 0.0)) continue;
      const Eigen::Vector3d nrm = ra[i].cross(xb[i]);
      const double e = f * xb[i].dot(l) / std::sqrt(n2);
      const double w = 1.0 / ((1.0 + e * e / c2) * n2);
      m.noalias() += w * nrm * nrm.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m);
    if (es.info() != Eigen::Success) break;
    Eigen::Vector3d next = es.eigenvectors().col(0);
    if (!next.allFinite()) break;
    t = next.dot(start) < 0.0 ? Eigen::Vector3d(-next) : next;
  }
  return t;
}

double TranslationDirectionCost(const std::vector<Eigen::Vector3d>& ra,
                                const std::vector<Eigen::Vector3d>& xb, const Eigen::Vector3d& t,
                                double f, double sigma, double cauchy_scale,
                                const Eigen::Vector3d& t_prior, const Eigen::Matrix3d& t_info) {
  const double c2 = cauchy_scale * cauchy_scale * sigma * sigma;
  // The sum of log(1 + u_i) as the logarithm of products of up to 16 factors: one logarithm per
  // 16 correspondences instead of one each (the logarithms were a quarter of the fit's time). A
  // product stays far below the double range: a factor above 1e30 (an error of 1e15 sigmas) is
  // taken alone.
  double cost = 0.0, product = 1.0;
  int factors = 0;
  for (size_t i = 0; i < ra.size(); ++i) {
    const Eigen::Vector3d l = t.cross(ra[i]);
    const double n2 = l.x() * l.x() + l.y() * l.y();
    if (!(n2 > 0.0)) continue;
    const double e = f * xb[i].dot(l);
    const double factor = 1.0 + e * e / (n2 * c2);
    if (!(factor <= 1e30)) {
      cost += std::log(factor);
      continue;
    }
    product *= factor;
    if (++factors == 16) {
      cost += std::log(product);
      product = 1.0;
      factors = 0;
    }
  }
  cost += std::log(product);
  const Eigen::Vector3d d = t - t_prior;
  return 0.5 * cauchy_scale * cauchy_scale * cost + 0.5 * d.dot(t_info * d);
}

TranslationSearchResult SearchTranslationDirection(
    const std::vector<Eigen::Vector3d>& ra, const std::vector<Eigen::Vector3d>& xb,
    const Eigen::Vector3d& start, const Eigen::Vector3d& t_prior, const Eigen::Matrix3d& t_info,
    double f, double sigma, double cauchy_scale, int hypotheses, std::vector<double>& scratch) {
  IMUMATCH_CHECK(ra.size() == xb.size(), ra.size() << " bearings in A, " << xb.size() << " in B");
  const double length = t_prior.norm();
  IMUMATCH_CHECK(length > 1e-9, "prior translation of length " << length);
  // The hypotheses are scored on at most kScored correspondences (an even stride through them):
  // the score only has to rank directions tens of degrees apart; Gauss-Newton refines on all.
  constexpr size_t kScored = 128;
  const size_t stride = (ra.size() + kScored - 1) / kScored;
  std::vector<Eigen::Vector3d> ra_s, xb_s;
  ra_s.reserve(kScored);
  xb_s.reserve(kScored);
  for (size_t i = 0; i < ra.size(); i += stride) {
    ra_s.push_back(ra[i]);
    xb_s.push_back(xb[i]);
  }
  auto cost_scored = [&](const Eigen::Vector3d& dir) {
    return TranslationDirectionCost(ra_s, xb_s, length * dir, f, sigma, cauchy_scale, t_prior,
                                    t_info);
  };
  // (score on the scored subset, direction)
  std::vector<std::pair<double, Eigen::Vector3d>> candidates;
  auto consider = [&](const Eigen::Vector3d& dir) {
    if (dir.allFinite()) candidates.emplace_back(cost_scored(dir), dir);
  };
  consider(t_prior / length);
  // Two-correspondence hypotheses, in a fixed pseudo-random order.
  std::vector<int> order(ra.size());
  std::vector<Eigen::Vector3d> normal(ra.size());
  for (size_t i = 0; i < ra.size(); ++i) {
    order[i] = static_cast<int>(i);
    normal[i] = ra[i].cross(xb[i]);
  }
  if (ra.size() >= 2) {
    const int pool = std::max(2, static_cast<int>(ra.size()) / 2);
    std::nth_element(order.begin(), order.begin() + (pool - 1), order.end(), [&](int a, int b) {
      return normal[a].squaredNorm() > normal[b].squaredNorm();
    });
    uint64_t state = 0x9E3779B97F4A7C15ull;  // splitmix64, fixed seed
    auto next = [&state](int n) {
      uint64_t z = (state += 0x9E3779B97F4A7C15ull);
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      return static_cast<int>((z ^ (z >> 31)) % static_cast<uint64_t>(n));
    };
    for (int h = 0; h < hypotheses; ++h) {
      const int i = order[next(pool)], j = order[next(pool)];
      Eigen::Vector3d dir = normal[i].cross(normal[j]);
      const double norm = dir.norm();
      if (i == j || !(norm > 1e-12)) continue;
      dir /= norm;
      consider(dir.dot(t_prior) < 0.0 ? Eigen::Vector3d(-dir) : dir);
    }
  }
  // The few best on the subset, each refined by EpipolarTranslationDirection on the subset,
  // against the start on all correspondences.
  auto cost_all = [&](const Eigen::Vector3d& dir) {
    return TranslationDirectionCost(ra, xb, length * dir, f, sigma, cauchy_scale, t_prior, t_info);
  };
  constexpr size_t kRefined = 3;
  const size_t refined = std::min(kRefined, candidates.size());
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(refined),
                    candidates.end(),
                    [](const auto& a, const auto& b) { return a.first < b.first; });
  Eigen::Vector3d best = start.normalized();
  double best_cost = cost_all(best);
  for (size_t k = 0; k < refined; ++k) {
    const Eigen::Vector3d dir = EpipolarTranslationDirection(
        ra_s, xb_s, length * candidates[k].second, f, sigma, cauchy_scale, scratch);
    for (const Eigen::Vector3d& d : {candidates[k].second, dir}) {
      if (!d.allFinite()) continue;
      const double c = cost_all(d);
      if (c < best_cost) {
        best_cost = c;
        best = d;
      }
    }
  }
  return {length * best, best_cost};
}

}  // namespace imumatch
