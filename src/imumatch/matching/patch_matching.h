#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/grid_index.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/guided_pipeline.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

// A second look, by the image patch, at the queries the guided matcher left unmatched.
//
// A descriptor normalises its patch by the direction and scale the detector measured, and those
// are noisy: SIFT's descriptor of a point moves by a fifth of its norm for a 5 deg turn, and a
// keypoint's scale is interpolated between sampled levels. Two detections of one physical point
// in consecutive frames can then describe different neighbourhoods, and the ratio test or the
// distance threshold rejects a correct pair that the images themselves show plainly. Between
// consecutive frames the IMU predicts how the patch around the point is warped (in-plane rotation
// and scale, through the lens): A's patch, warped so, is the template B must show there. Each
// candidate keypoint of the query's window is tested by aligning that template at the candidate
// (translation-only Lucas-Kanade on zero-mean unit-variance intensities: patch_alignment.h); the
// candidate passes when the alignment converges within max_shift_px of it and correlates (ZNCC)
// at least min_correlation there. The query is matched when the candidates that pass all point
// to one place (within max_shift_px of each other): a repeated texture that lets two places of
// the window pass is rejected, as the ratio test rejects two look-alikes.
//
// Only queries rejected by the orientation check, the distance threshold or the ratio test are
// looked at again, so the first look's matches are unchanged. A keypoint of B that a first-look
// match took is not a candidate; of two queries reaching the same keypoint, the one with the
// higher correlation keeps it. Every match found so carries the aligned position as
// Match::refined_uv_b.

namespace imumatch {

struct PatchMatchingOptions {
  int half_size = 4;  // template of (2h+1)^2 samples; a flat one is tried again at 2h
  int max_iterations = 10;
  double convergence_px = 0.03;
  double min_texture = 0.02;  // as SubpixelOptions::min_texture
  // A candidate passes when its alignment converges within max_shift_px of it with a ZNCC of at
  // least min_correlation. 0.9 is stricter than the refinement's 0.8 for a drifted patch: here
  // the patch alone decides.
  double max_shift_px = 2.0;
  double min_correlation = 0.9;
  // max_shift_px holds for two keypoints at their frames' finest detection scale. The alignment
  // lands where B shows A's keypoint; B's keypoint of the same point is off from there by both
  // keypoints' localisation errors, which grow with the detection scale as the predictor's model
  // says (KeypointSigmaScaling::kSize: a keypoint at scale s sits on a grid of step s px). On,
  // the shift limit (and the spacing that makes two passing places distinct) is max_shift_px x
  // sqrt((f_a^2 + f_b^2) / 2), f = SizeSigmaFactor(size, the frame's smallest size, 1 px): 2 px
  // for two finest keypoints, 3 px for two of SIFT's octave 2 (s = 4), 5 px at octave 3.
  bool shift_grows_with_scale = true;
  int max_candidates = 16;  // a query whose window holds more is not looked at
  // Require the candidate to pass the descriptor's distance threshold as well
  // (GuidedMatcherOptions::max_hamming_fraction / max_l2_relative). Off: measured on EuRoC MH_05
  // (199 pairs, six detectors), the patch alone kept the guided precision at 1, 3 and 8 px and
  // on the frames with depth as it was, and the guard halved what the look adds for SIFT, AKAZE
  // and BRISK (their rejected partners are mostly beyond the threshold). With a correlation of
  // 0.8 instead of 0.9, a fifth of SIFT's added matches were false.
  bool require_distance_threshold = false;

  void Check() const;
};

struct PatchMatchingStats {
  int queries = 0;    // unmatched queries looked at again
  int aligned = 0;    // candidate alignments run
  int ambiguous = 0;  // candidates passed at two places or more
  int matched = 0;    // matches added
  int taken = 0;      // lost their keypoint of B to a query with a higher correlation
};

// Adds to result (MatchGuided's output for the same predictions and keypoints) the matches of its
// unmatched queries that the image patches show. keypoints_a / keypoints_b in image pixels as the
// detector gave them (indexed like ideal_a / ideal_b and the descriptors); gray_a / gray_b 8-bit
// single-channel images. Updates result's matches (in A's order), outcomes and stats (a rescued
// query moves from its rejection count to matched). Throws InvalidArgument on size mismatches
// or images that are empty or not 8-bit single-channel.
PatchMatchingStats MatchByPatch(
    const std::vector<KeypointPrediction>& predictions, const std::vector<KeypointInfo>& ideal_a,
    const std::vector<cv::KeyPoint>& keypoints_a, const DescriptorView& descriptors_a,
    const std::vector<KeypointInfo>& ideal_b, const GridIndex& grid_b,
    const std::vector<cv::KeyPoint>& keypoints_b, const DescriptorView& descriptors_b,
    const cv::Mat& gray_a, const cv::Mat& gray_b, const PinholeCamera& camera,
    const GuidedMatcherOptions& guided, const PatchMatchingOptions& options, MatchResult* result);

// The same after GuidedMatcherWorkspace::Match: its predictions, keypoints in ideal pixels and grid
// over B, with the keypoints and descriptors the call was given. result is that call's output.
// The per-frame loop of a caller with images:
//   MatchResult r = workspace.Match(camera, motion, kps_a, desc_a, depth_a, kps_b, desc_b, po, mo);
//   MatchByPatch(workspace, kps_a, desc_a, kps_b, desc_b, gray_a, gray_b, camera, mo,
//                PatchMatchingOptions(), &r);
//   RefineMatches(gray_a, gray_b, kps_a, kps_b, workspace.predictions(), camera,
//                 SubpixelOptions(), r.matches);   // subpixel_refinement.h
// Throws InvalidArgument when the keypoints are not the ones of the workspace's last call (their
// counts differ).
PatchMatchingStats MatchByPatch(const GuidedMatcherWorkspace& workspace,
                                const std::vector<cv::KeyPoint>& keypoints_a,
                                const cv::Mat& descriptors_a,
                                const std::vector<cv::KeyPoint>& keypoints_b,
                                const cv::Mat& descriptors_b, const cv::Mat& gray_a,
                                const cv::Mat& gray_b, const PinholeCamera& camera,
                                const GuidedMatcherOptions& guided,
                                const PatchMatchingOptions& options, MatchResult* result);

}  // namespace imumatch
