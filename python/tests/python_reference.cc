// The C++ side of the Python equality tests: runs the pipeline the tests run through the bindings
// (features, prediction, guided matching with refinement, brute force) on the TUM pair and on a
// synthetic pair, through the C++ API, and prints the results as JSON.
//   python_reference tum <tum_fr1_xyz_pair folder>
//   python_reference synthetic

#include <iostream>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/eval/evaluation.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/io/trajectory_io.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/guided_pipeline.h"
#include "imumatch/matching/subpixel_refinement.h"
#include "imumatch/sim/synthetic_sequence.h"

using namespace imumatch;
using nlohmann::json;

namespace {

json Keypoints(const std::vector<cv::KeyPoint>& kps) {
  json a = json::array();
  for (const auto& k : kps)
    a.push_back({k.pt.x, k.pt.y, k.size, k.angle, k.response, k.octave, k.class_id});
  return a;
}

json Matches(const std::vector<Match>& matches) {
  json a = json::array();
  for (const auto& m : matches) {
    a.push_back({m.query_idx, m.train_idx, m.distance, m.refined_uv_b.x(), m.refined_uv_b.y()});
  }
  return a;
}

json Run(const PinholeCamera& camera, const CameraMotion& motion, const cv::Mat& gray_a,
         const cv::Mat& gray_b, const cv::Mat& depth_a, DetectorKind kind) {
  FeatureOptions fo;
  fo.kind = kind;
  fo.max_keypoints = 1000;
  const Features fa = ExtractFeatures(gray_a, fo);
  const Features fb = ExtractFeatures(gray_b, fo);
  const cv::Mat da = PadBinaryDescriptors(fa.descriptors);
  const cv::Mat db = PadBinaryDescriptors(fb.descriptors);
  GuidedMatcherWorkspace workspace;
  MatchResult guided = workspace.Match(camera, motion, fa.keypoints, da, depth_a, fb.keypoints, db,
                                       PredictionOptions(), GuidedMatcherOptions());
  RefineMatches(gray_a, gray_b, fa.keypoints, fb.keypoints, workspace.predictions(), camera,
                SubpixelOptions(), guided.matches);
  json predicted = json::array();
  for (const auto& p : workspace.predictions()) predicted.push_back({p.uv.x(), p.uv.y()});
  json outcomes = json::array();
  for (QueryOutcome o : guided.outcomes) outcomes.push_back(ToString(o));
  BruteForceOptions bf;
  bf.ratio = 0.8;
  json out;
  out["keypoints_a"] = Keypoints(fa.keypoints);
  out["keypoints_b"] = Keypoints(fb.keypoints);
  out["guided"] = Matches(guided.matches);
  out["outcomes"] = outcomes;
  out["predicted_uv"] = predicted;
  out["bf_opencv"] = Matches(MatchOpenCvKnnRatio(da, db, 0.8));
  out["bf_own"] = Matches(MatchBruteForce(da, db, bf));
  const Rigid3d& r = motion.cam_b_from_cam_a;
  out["motion"] = {r.rotation.w(),    r.rotation.x(),    r.rotation.y(),   r.rotation.z(),
                   r.translation.x(), r.translation.y(), r.translation.z()};
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string what = argc > 1 ? argv[1] : "";
    json out;
    if (what == "tum" && argc > 2) {
      const std::string dir = argv[2];
      const cv::Mat a = cv::imread(dir + "/img_prev.png", cv::IMREAD_GRAYSCALE);
      const cv::Mat b = cv::imread(dir + "/img_curr.png", cv::IMREAD_GRAYSCALE);
      const cv::Mat depth = cv::imread(dir + "/dep_prev.png", cv::IMREAD_UNCHANGED);
      const CameraMotion motion = CameraMotionFromPoses(0, ReadTumPose(dir + "/pose_prev.txt"), 1,
                                                        ReadTumPose(dir + "/pose_curr.txt"));
      out = Run(PinholeCamera::TumFreiburg1(), motion, a, b, depth, DetectorKind::kOrb);
    } else if (what == "synthetic") {
      SyntheticSequenceOptions so;
      so.motion = "front1m";
      so.frame_times_s = {1.0, 1.1};
      const SyntheticSequence seq = MakeSyntheticSequence(so);
      ImuBuffer imu;
      for (const ImuSample& s : seq.imu) imu.Push(s, "synthetic imu");
      const SyntheticFrame& fa = seq.frames[0];
      const SyntheticFrame& fb = seq.frames[1];
      ImuStateAtFrame state{fa.world_from_imu, fa.imu_velocity_in_world, seq.imu_initial_bias};
      const CameraMotion motion = ComputeCameraMotion(imu, fa.t_ns, fb.t_ns, state, seq.imu_params,
                                                      seq.cam_from_imu, CameraMotionOptions());
      cv::Mat gray_a, gray_b;
      cv::cvtColor(fa.rgb, gray_a, cv::COLOR_BGR2GRAY);
      cv::cvtColor(fb.rgb, gray_b, cv::COLOR_BGR2GRAY);
      out = Run(seq.camera, motion, gray_a, gray_b, fa.depth, DetectorKind::kSift);
    } else {
      std::cerr << "usage: python_reference tum <folder> | synthetic\n";
      return 2;
    }
    std::cout << out.dump() << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "python_reference: " << e.what() << "\n";
    return 1;
  }
}
