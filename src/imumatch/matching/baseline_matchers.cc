#include "imumatch/matching/baseline_matchers.h"

#include <cmath>
#include <limits>

#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

#include "imumatch/core/error.h"
#include "imumatch/matching/descriptor_distance.h"

namespace imumatch {

void BruteForceOptions::Check() const {
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio=" << ratio << " must be in (0, 1]");
  IMUMATCH_CHECK(max_distance >= 0.0, "max_distance=" << max_distance);
}

void FlannLshOptions::Check() const {
  IMUMATCH_CHECK(table_number >= 1, "table_number=" << table_number);
  IMUMATCH_CHECK(key_size >= 1 && key_size <= 32, "key_size=" << key_size);
  IMUMATCH_CHECK(multi_probe_level >= 0, "multi_probe_level=" << multi_probe_level);
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio=" << ratio);
}

namespace {

int CvNorm(const cv::Mat& d) { return d.depth() == CV_8U ? cv::NORM_HAMMING : cv::NORM_L2; }

void CheckPair(const cv::Mat& a, const cv::Mat& b) {
  CheckCompatible(DescriptorView::FromMat(a), DescriptorView::FromMat(b));
}

Match FromDMatch(const cv::DMatch& d) {
  Match m;
  m.query_idx = d.queryIdx;
  m.train_idx = d.trainIdx;
  m.distance = d.distance;
  return m;
}

std::vector<Match> KnnToRatioMatches(const std::vector<std::vector<cv::DMatch>>& knn,
                                     double ratio) {
  std::vector<Match> out;
  out.reserve(knn.size());
  for (const auto& nn : knn) {
    if (nn.empty()) continue;
    Match m = FromDMatch(nn[0]);
    if (nn.size() >= 2) {
      m.second_distance = nn[1].distance;
      if (!(nn[0].distance < ratio * nn[1].distance)) continue;
    }
    out.push_back(m);
  }
  return out;
}

}  // namespace

std::vector<Match> MatchBruteForce(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                   const BruteForceOptions& options) {
  options.Check();
  const DescriptorView a = DescriptorView::FromMat(descriptors_a);
  const DescriptorView b = DescriptorView::FromMat(descriptors_b);
  CheckCompatible(a, b);
  std::vector<Match> out;
  if (a.rows == 0 || b.rows == 0) return out;
  Nearest2 fwd;
  NearestTwo(a, b, options.kernel, fwd);
  Nearest2 rev;
  if (options.cross_check) NearestTwo(b, a, options.kernel, rev);
  const DescriptorNorm norm = a.norm;
  const float ratio_cost = static_cast<float>(
      norm == DescriptorNorm::kL2 ? options.ratio * options.ratio : options.ratio);
  const float max_cost = std::isinf(options.max_distance)
                             ? std::numeric_limits<float>::infinity()
                             : DistanceToCost(norm, static_cast<float>(options.max_distance));
  const float inf = std::numeric_limits<float>::infinity();
  out.reserve(a.rows);
  for (int i = 0; i < a.rows; ++i) {
    const int j = fwd.best_idx[i];
    if (j < 0 || fwd.best[i] > max_cost) continue;
    if (options.ratio < 1.0 && fwd.second[i] < inf && !(fwd.best[i] < ratio_cost * fwd.second[i])) {
      continue;
    }
    if (options.cross_check && rev.best_idx[j] != i) continue;
    Match m;
    m.query_idx = i;
    m.train_idx = j;
    m.distance = CostToDistance(norm, fwd.best[i]);
    m.second_distance = fwd.second[i] < inf ? CostToDistance(norm, fwd.second[i]) : inf;
    out.push_back(m);
  }
  return out;
}

std::vector<Match> MatchOpenCvBruteForce(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b) {
  CheckPair(descriptors_a, descriptors_b);
  std::vector<Match> out;
  if (descriptors_a.empty() || descriptors_b.empty()) return out;
  cv::BFMatcher matcher(CvNorm(descriptors_a), false);
  std::vector<cv::DMatch> dm;
  matcher.match(descriptors_a, descriptors_b, dm);
  out.reserve(dm.size());
  for (const cv::DMatch& d : dm) out.push_back(FromDMatch(d));
  return out;
}

std::vector<Match> MatchOpenCvKnnRatio(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                       double ratio) {
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio=" << ratio);
  CheckPair(descriptors_a, descriptors_b);
  if (descriptors_a.empty() || descriptors_b.empty()) return {};
  cv::BFMatcher matcher(CvNorm(descriptors_a), false);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(descriptors_a, descriptors_b, knn, 2);
  return KnnToRatioMatches(knn, ratio);
}

std::vector<Match> MatchOpenCvCrossCheck(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b) {
  CheckPair(descriptors_a, descriptors_b);
  std::vector<Match> out;
  if (descriptors_a.empty() || descriptors_b.empty()) return out;
  cv::BFMatcher matcher(CvNorm(descriptors_a), true);
  std::vector<cv::DMatch> dm;
  matcher.match(descriptors_a, descriptors_b, dm);
  for (const cv::DMatch& d : dm) out.push_back(FromDMatch(d));
  return out;
}

std::vector<Match> MatchFlannLsh(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                 const FlannLshOptions& options) {
  options.Check();
  CheckPair(descriptors_a, descriptors_b);
  IMUMATCH_CHECK(descriptors_a.empty() || descriptors_a.depth() == CV_8U,
                 "FLANN LSH needs binary (CV_8U) descriptors");
  if (descriptors_a.empty() || descriptors_b.empty()) return {};
  cv::FlannBasedMatcher matcher(
      cv::makePtr<cv::flann::LshIndexParams>(options.table_number, options.key_size,
                                             options.multi_probe_level),
      cv::makePtr<cv::flann::SearchParams>());
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(descriptors_a, descriptors_b, knn, 2);
  return KnnToRatioMatches(knn, options.ratio);
}

}  // namespace imumatch
