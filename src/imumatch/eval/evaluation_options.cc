#include "imumatch/eval/evaluation_options.h"

#include <cctype>
#include <cmath>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace

std::string ToString(MatchMethod method) {
  switch (method) {
    case MatchMethod::kBruteForce:
      return "bf";
    case MatchMethod::kGuided:
      return "guided";
    case MatchMethod::kFixedWindow:
      return "fixed10";
    case MatchMethod::kOwnBruteForce:
      return "bf_own";
    case MatchMethod::kKltUnseeded:
      return "klt0";
    case MatchMethod::kKlt:
      return "klt";
    case MatchMethod::kHybrid:
      return "hybrid";
  }
  return "?";
}

std::string DisplayName(MatchMethod method) {
  switch (method) {
    case MatchMethod::kBruteForce:
      return "BF knn+ratio (OpenCV)";
    case MatchMethod::kGuided:
      return "IMU-guided";
    case MatchMethod::kFixedWindow:
      return "IMU fixed +-10 px";
    case MatchMethod::kOwnBruteForce:
      return "BF ratio (imumatch)";
    case MatchMethod::kKltUnseeded:
      return "KLT unseeded (OpenCV)";
    case MatchMethod::kKlt:
      return "KLT IMU-seeded";
    case MatchMethod::kHybrid:
      return "Hybrid KLT + guided";
  }
  return "?";
}

MatchMethod ParseMatchMethod(std::string_view name) {
  const std::string n = Lower(name);
  if (n == "bf" || n == "bf_opencv") return MatchMethod::kBruteForce;
  if (n == "guided") return MatchMethod::kGuided;
  if (n == "fixed10" || n == "fixed") return MatchMethod::kFixedWindow;
  if (n == "bf_own") return MatchMethod::kOwnBruteForce;
  if (n == "klt0") return MatchMethod::kKltUnseeded;
  if (n == "klt") return MatchMethod::kKlt;
  if (n == "hybrid") return MatchMethod::kHybrid;
  throw InvalidArgument("unknown method '" + std::string(name) +
                        "' (valid: bf, guided, fixed10, bf_own, klt0, klt, hybrid)");
}

bool UsesPrediction(MatchMethod method) {
  return method == MatchMethod::kGuided || method == MatchMethod::kFixedWindow ||
         method == MatchMethod::kKlt || method == MatchMethod::kHybrid;
}

KltOptions VinsKltOptions() {
  KltOptions o;
  o.half_size = 10;
  o.max_level = 3;
  o.warp_patch = false;
  o.gate_by_window = false;
  o.min_correlation = -1.0;  // VINS-Fusion checks no correlation
  o.convergence_px = 0.01;   // cv::TermCriteria(COUNT + EPS, 30, 0.01)
  return o;
}

bool IsBruteForce(MatchMethod method) {
  return method == MatchMethod::kBruteForce || method == MatchMethod::kOwnBruteForce;
}

bool IsTracking(MatchMethod method) {
  return method == MatchMethod::kKltUnseeded || method == MatchMethod::kKlt ||
         method == MatchMethod::kHybrid;
}

MotionSource ParseMotionSource(std::string_view name) {
  const std::string n = Lower(name);
  if (n == "imu") return MotionSource::kImu;
  if (n == "gt" || n == "groundtruth") return MotionSource::kGroundTruth;
  throw InvalidArgument("unknown motion source '" + std::string(name) + "' (valid: imu, gt)");
}

const char* ToString(MotionSource source) { return source == MotionSource::kImu ? "imu" : "gt"; }

void EvaluationOptions::Check() const {
  IMUMATCH_CHECK(!detectors.empty(), "no detector selected");
  IMUMATCH_CHECK(!methods.empty(), "no method selected");
  features.Check();
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio = " << ratio);
  motion.Check();
  prediction.Check();
  guided.Check();
  subpixel.Check();
  gyro_bias_filter.Check();
  patch.Check();
  neighbour_depth.Check();
  klt.Check();
  klt_unseeded.Check();
  IMUMATCH_CHECK(std::isfinite(gain_b) && gain_b > 0.0 && gain_b <= 100.0, "gain_b = " << gain_b);
  ground_truth.Check();
  IMUMATCH_CHECK(std::isfinite(still_init_s) && still_init_s >= 0.0,
                 "still_init_s = " << still_init_s);
  IMUMATCH_CHECK(keep_visuals >= 0, "keep_visuals = " << keep_visuals);
  IMUMATCH_CHECK(queue_capacity >= 0 && queue_capacity <= 16,
                 "queue_capacity = " << queue_capacity);
}

}  // namespace imumatch
