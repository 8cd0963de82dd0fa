#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/brute_force_kernels.h"
#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/grid_index.h"
#include "imumatch/matching/guided_candidates.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch {

struct GuidedMatcherOptions {
  // Lowe's ratio test on distances (not squared): best < ratio * min(second, threshold). The
  // distance threshold below acts as a virtual second-best, so a lone candidate in the window must
  // still be distinctive: inside a small window the true second-best of the whole image is absent,
  // and without this rule gross errors slip through on long (2 s) IMU intervals. 1 disables it.
  double ratio = 0.8;
  // Absolute thresholds on the best distance. Hamming: max_hamming_fraction of the descriptor's
  // bits (0.35 -> 89.6 of 256 for ORB, near ORB-SLAM's TH_HIGH = 100 for guided search; with the
  // ratio rule above a lone candidate needs < 71.7 bits). L2: the distance relative to the
  // descriptors' size, |a - b| <= max_l2_relative * sqrt((|a|^2 + |b|^2) / 2), so it works for unit
  // descriptors and for OpenCV's SIFT (norm ~512) alike.
  double max_hamming_fraction = 0.35;
  double max_l2_relative = 0.8;
  // Candidates in the window that fail the orientation or scale check cannot be the match but
  // still compete as second-best in the ratio test, as every keypoint does in a brute-force ratio
  // test. Measured on the demo's seed cases (SIFT, SURF, ORB, AKAZE): guided SURF precision at
  // 1 / 8 px 0.689 / 0.934 -> 0.746 / 0.979, SIFT 0.974 -> 0.979, for 1.3 % fewer correct matches.
  bool inconsistent_candidates_in_ratio = true;
  // Candidates within duplicate_radius_px x (the best candidate's size / the smallest keypoint size
  // of B) of the best candidate are not its rivals in the ratio test: they are the same physical
  // point detected again (ORB finds a corner on several pyramid levels, SIFT gives one point
  // several orientations), and either is a correct partner. Whole-image brute force cannot tell
  // such a twin from a distant look-alike and rejects both; the ratio test exists for the
  // look-alikes. 0 disables.
  double duplicate_radius_px = 2.0;
  // Reverse pass: keep i -> j only when, among the keypoints of A whose windows contain j and pass
  // the consistency checks, i is the one closest to j.
  bool mutual = false;
  // |angle_b - angle_a - predicted change| <= tolerance, when both keypoints have an angle.
  bool check_orientation = true;
  double orientation_tolerance_deg = 30.0;
  // size_b / size_a within [scale_min / factor, scale_max * factor] of the predicted ratio, when
  // both keypoints have a size.
  bool check_scale = true;
  double scale_tolerance_factor = 2.0;
  // Grid cell size of the index over frame B (pixels). Measured on the TUM pair (ORB 1000-8000,
  // typical windows +-4..10 px): 8 px beats 16 and 24 px by 1.3-2x, because real keypoints cluster
  // and a coarse cell makes every query scan its cluster; 4-6 px gains little more.
  double grid_cell_size = 8.0;
  // Instruction-set path of the window tests (window_scan.h): kAuto picks the fastest the CPU
  // has; every path gives the same matches. kPopcnt runs the portable test.
  BruteForceKernel kernel = BruteForceKernel::kAuto;

  void Check() const;
};

// Matches predicted keypoints of A to the keypoints of B found in their windows. predictions[i]
// belongs to keypoints_a[i] / descriptors_a row i; grid_b indexes keypoints_b. Visits only the grid
// cells each window touches: O(n * candidates-per-window), never O(n * m). Throws InvalidArgument
// on size mismatches or incompatible descriptors.
MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a,
                        const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
                        const DescriptorView& descriptors_b, const GuidedMatcherOptions& options);

// The working memory of MatchGuided: the queries' visiting order, the reverse bests, per-query
// results (about 100 bytes per keypoint), and B prepared by the overloads that take B's keypoints
// (candidates). Passing the same scratch to successive calls (one per thread) reuses it: fresh
// large buffers every frame cost page faults and zeroing that grow faster than the keypoint count.
struct GuidedSearchScratch {
  GuidedCandidates candidates;
  std::vector<float> reverse_cost;
  std::vector<int> reverse_idx;
  std::vector<int> consistent_slot, rival_slot;
  std::vector<float> consistent_cost, rival_cost;
  std::vector<int> order, position_of, cell_start, cell;
  std::vector<int> accepted_slot;
  std::vector<float> accepted_cost, accepted_second;
};
// The search against a prepared frame B (the scratch's own candidates are not used).
MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a, const GuidedCandidates& candidates_b,
                        const GuidedMatcherOptions& options, GuidedSearchScratch* scratch);
// The same, preparing B into scratch->candidates first.
MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a,
                        const std::vector<KeypointInfo>& keypoints_b, const GridIndex& grid_b,
                        const DescriptorView& descriptors_b, const GuidedMatcherOptions& options,
                        GuidedSearchScratch* scratch);
// The same with the grid over frame B's keypoints (ideal pixels of a width x height camera) built
// here, for callers that match frame B once.
MatchResult MatchGuided(const std::vector<KeypointPrediction>& predictions,
                        const std::vector<KeypointInfo>& keypoints_a,
                        const DescriptorView& descriptors_a,
                        const std::vector<KeypointInfo>& keypoints_b,
                        const DescriptorView& descriptors_b, int width, int height,
                        const GuidedMatcherOptions& options);

}  // namespace imumatch
