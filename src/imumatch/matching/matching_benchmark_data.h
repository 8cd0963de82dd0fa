#pragma once

// The data of matching_benchmark (its source files share them): the TUM fr1_xyz pair and its
// ground-truth motion, features extracted once per (detector, count, variant), the stream of pair
// variants, the camera.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/imu/camera_motion.h"

namespace imumatch::bench {

// <data dir>/tum_fr1_xyz_pair/<file> (IMUMATCH_DATA_DIR overrides the built-in data dir).
std::string DataPath(const std::string& file);

struct Frames {
  cv::Mat gray_a, gray_b, depth_a;
  CameraMotion motion;
};
// The TUM pair (exits with a message when it is missing: a benchmark has no caller to throw to).
const Frames& GetFrames();

struct FeatureSet {
  std::vector<cv::KeyPoint> kps_a, kps_b;
  cv::Mat desc_a, desc_b;
};

// A benchmark that runs the same frame pair in every iteration lets the CPU learn it: the branch
// predictor memorises the whole pass when it is short (1000 keypoints, not 8000), which flatters
// small sizes by up to 1.5x (measured on the synthetic search, matching_benchmark_scaling.cc). A
// stream never shows the same frame twice, so the per-keypoint figures rotate through
// kStreamVariants different pairs: the TUM pair forward and backward, each also mirrored
// left-right, up-down and both (a mirrored pair is a valid pair of the same camera: cx, cy sit at
// the image centre; the motion is conjugated by the mirror), each with its own keypoints.
constexpr int kStreamVariants = 8;

struct PairVariant {
  cv::Mat gray_a, gray_b, depth_a;
  CameraMotion motion;
};
const PairVariant& GetPairVariant(int v);

// kind 0: ORB with n features (FAST threshold lowered so 8000 are reachable), 1: SIFT.
// variant -1: the TUM pair itself; 0..kStreamVariants-1: GetPairVariant.
const FeatureSet& GetFeatures(int kind, int n, int variant = -1);

// The generic Kinect intrinsics (no distortion): on this pair they fit the ground truth as well
// as the fr1 calibration (see matching_tum_test), and avoid the iterative undistortion.
PinholeCamera BenchCamera();

void SetCounters(benchmark::State& state, const FeatureSet& s, size_t matches);

// Args {kind, n}: ORB 500..8000 and SIFT 1000.
void OrbSizes(benchmark::internal::Benchmark* b);

}  // namespace imumatch::bench
