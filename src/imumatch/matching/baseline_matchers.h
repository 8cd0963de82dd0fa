#pragma once

#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/matching/brute_force_kernels.h"
#include "imumatch/matching/match_types.h"

namespace imumatch {

// Unguided baselines on the same descriptors, all returning imumatch::Match (second_distance is
// +inf where the method does not produce one; predicted_uv is NaN).

struct BruteForceOptions {
  // Lowe's ratio test on distances: keep best < ratio * second. 1 disables it (every query keeps
  // its nearest neighbour).
  double ratio = 1.0;
  // Drop matches whose distance exceeds this (Hamming bits or L2 distance).
  double max_distance = std::numeric_limits<double>::infinity();
  // Keep i -> j only when i is also j's nearest neighbour in A.
  bool cross_check = false;
  BruteForceKernel kernel = BruteForceKernel::kAuto;
  void Check() const;
};

// Our own exhaustive matcher: NearestTwo (brute_force_kernels.h: AVX-512, AVX2, POPCNT or portable
// kernels, picked at run time) and then the ratio test, distance bound and cross check. Single
// thread.
std::vector<Match> MatchBruteForce(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                   const BruteForceOptions& options);

// cv::BFMatcher(NORM_HAMMING or NORM_L2)::match: nearest neighbour of every query.
std::vector<Match> MatchOpenCvBruteForce(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b);
// cv::BFMatcher::knnMatch(k=2) + ratio test (best < ratio * second; a single neighbour passes).
std::vector<Match> MatchOpenCvKnnRatio(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                       double ratio);
// cv::BFMatcher(norm, crossCheck=true)::match.
std::vector<Match> MatchOpenCvCrossCheck(const cv::Mat& descriptors_a,
                                         const cv::Mat& descriptors_b);

struct FlannLshOptions {
  int table_number = 6;
  int key_size = 12;
  int multi_probe_level = 1;
  double ratio = 0.8;
  void Check() const;
};
// cv::FlannBasedMatcher with LshIndexParams (binary descriptors only) + knnMatch(k=2) + ratio.
// Approximate: may miss neighbours. Index build is included (trained on B at each call).
std::vector<Match> MatchFlannLsh(const cv::Mat& descriptors_a, const cv::Mat& descriptors_b,
                                 const FlannLshOptions& options);

}  // namespace imumatch
