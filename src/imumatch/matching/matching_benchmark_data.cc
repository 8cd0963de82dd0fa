#include "imumatch/matching/matching_benchmark_data.h"

#include <cstdio>
#include <cstdlib>
#include <map>
#include <tuple>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/trajectory_io.h"  // ReadTumPose

#ifndef IMUMATCH_BENCH_DATA_DIR
#define IMUMATCH_BENCH_DATA_DIR "../shared/data"
#endif

namespace imumatch::bench {

std::string DataPath(const std::string& file) {
  const char* env = std::getenv("IMUMATCH_DATA_DIR");
  const std::string dir = (env != nullptr && *env != '\0') ? env : IMUMATCH_BENCH_DATA_DIR;
  return dir + "/tum_fr1_xyz_pair/" + file;
}

const Frames& GetFrames() {
  static const Frames f = [] {
    Frames fr;
    fr.gray_a = cv::imread(DataPath("img_prev.png"), cv::IMREAD_GRAYSCALE);
    fr.gray_b = cv::imread(DataPath("img_curr.png"), cv::IMREAD_GRAYSCALE);
    fr.depth_a = cv::imread(DataPath("dep_prev.png"), cv::IMREAD_UNCHANGED);
    if (fr.gray_a.empty() || fr.gray_b.empty() || fr.depth_a.empty()) {
      std::fprintf(stderr, "missing TUM pair under %s (set IMUMATCH_DATA_DIR)\n",
                   DataPath("").c_str());
      std::exit(1);
    }
    try {
      fr.motion = CameraMotionFromPoses(0, ReadTumPose(DataPath("pose_prev.txt")), 1,
                                        ReadTumPose(DataPath("pose_curr.txt")));
    } catch (const Error& e) {
      std::fprintf(stderr, "cannot read pose: %s\n", e.what());
      std::exit(1);
    }
    return fr;
  }();
  return f;
}

const PairVariant& GetPairVariant(int v) {
  static std::map<int, PairVariant> cache;
  auto it = cache.find(v);
  if (it != cache.end()) return it->second;
  const Frames& f = GetFrames();
  const bool backward = (v & 4) != 0;
  const bool flip_x = (v & 1) != 0, flip_y = (v & 2) != 0;
  PairVariant pv;
  cv::Mat gray_a = backward ? f.gray_b : f.gray_a, gray_b = backward ? f.gray_a : f.gray_b;
  cv::Mat depth_a =
      backward ? cv::imread(DataPath("dep_curr.png"), cv::IMREAD_UNCHANGED) : f.depth_a;
  Rigid3d b_from_a = backward ? f.motion.cam_b_from_cam_a.Inverse() : f.motion.cam_b_from_cam_a;
  const int code = flip_x && flip_y ? -1 : (flip_x ? 1 : 0);
  if (flip_x || flip_y) {
    cv::flip(gray_a, pv.gray_a, code);
    cv::flip(gray_b, pv.gray_b, code);
    cv::flip(depth_a, pv.depth_a, code);
  } else {
    pv.gray_a = gray_a;
    pv.gray_b = gray_b;
    pv.depth_a = depth_a;
  }
  const Eigen::Matrix3d mirror =
      Eigen::Vector3d(flip_x ? -1.0 : 1.0, flip_y ? -1.0 : 1.0, 1.0).asDiagonal();
  pv.motion = f.motion;
  pv.motion.cam_b_from_cam_a = Rigid3d(mirror * b_from_a.rotation.toRotationMatrix() * mirror,
                                       mirror * b_from_a.translation);
  return cache.emplace(v, std::move(pv)).first->second;
}

const FeatureSet& GetFeatures(int kind, int n, int variant) {
  static std::map<std::tuple<int, int, int>, FeatureSet> cache;
  auto it = cache.find({kind, n, variant});
  if (it != cache.end()) return it->second;
  cv::Ptr<cv::Feature2D> f;
  if (kind == 0) {
    f = cv::ORB::create(n, 1.2f, 8, 15, 0, 2, cv::ORB::HARRIS_SCORE, 31, n > 2000 ? 5 : 20);
  } else {
    f = cv::SIFT::create(n);
  }
  FeatureSet s;
  const cv::Mat& a = variant < 0 ? GetFrames().gray_a : GetPairVariant(variant).gray_a;
  const cv::Mat& b = variant < 0 ? GetFrames().gray_b : GetPairVariant(variant).gray_b;
  f->detectAndCompute(a, cv::noArray(), s.kps_a, s.desc_a);
  f->detectAndCompute(b, cv::noArray(), s.kps_b, s.desc_b);
  return cache.emplace(std::make_tuple(kind, n, variant), std::move(s)).first->second;
}

PinholeCamera BenchCamera() { return PinholeCamera::KinectDefault(); }

void SetCounters(benchmark::State& state, const FeatureSet& s, size_t matches) {
  state.counters["kps_a"] = static_cast<double>(s.kps_a.size());
  state.counters["kps_b"] = static_cast<double>(s.kps_b.size());
  state.counters["matches"] = static_cast<double>(matches);
}

void OrbSizes(benchmark::internal::Benchmark* b) {
  for (int n : {500, 1000, 2000, 4000, 8000}) b->Args({0, n});
  b->Args({1, 1000});  // SIFT
  b->ArgNames({"sift", "n"});
}

}  // namespace imumatch::bench
