// Uses the installed library: integrates a simulated IMU spinning about the optical axis, then
// runs the README's per-frame loop (guided matching, the second look by the image patch,
// sub-pixel refinement) on two frames related by that rotation, and judges every match against
// the exact pixel motion.
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/guided_pipeline.h"
#include "imumatch/matching/patch_matching.h"
#include "imumatch/matching/subpixel_refinement.h"
#include "imumatch/sim/imu_simulator.h"
#include "imumatch/sim/trajectory.h"

int main() {
  using namespace imumatch;
  // 0.5 rad/s about the camera's z axis for 0.5 s: a roll of 0.25 rad.
  ConstantRateTrajectory spin(Rigid3d(), Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d::Zero(), 1.0);
  ImuSimulatorOptions opt;
  opt.add_noise = opt.add_bias_walk = false;
  ImuBuffer buffer;
  for (const ImuSample& s : SimulateImu(spin, ImuParams::Ideal(), opt)) buffer.Push(s);
  const ImuPreintegration pim =
      Preintegrate(buffer.Slice(0, 500'000'000), ImuBias(), ImuParams::Ideal());
  const double angle = RotationAngle(pim.delta_rotation);
  std::printf("IMU rotation %.6f rad (expected 0.25)\n", angle);
  if (std::abs(angle - 0.25) > 1e-9) return 1;

  // Frame A: blurred noise; frame B: A as the camera sees it after the roll (the image turns
  // the other way about the principal point).
  PinholeCamera camera;
  camera.width = 320;
  camera.height = 240;
  camera.fx = camera.fy = 300.0;
  camera.cx = 160.0;
  camera.cy = 120.0;
  cv::Mat noise(camera.height, camera.width, CV_32F), gray_a, gray_b;
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.8);
  cv::normalize(noise, noise, 15, 240, cv::NORM_MINMAX);
  noise.convertTo(gray_a, CV_8U);
  CameraMotion motion;  // the rotation of camera A into camera B: the spin's inverse
  motion.t_b_ns = 500'000'000;
  motion.cam_b_from_cam_a = Rigid3d(pim.delta_rotation.conjugate(), Eigen::Vector3d::Zero());
  const Eigen::Matrix3d r = motion.cam_b_from_cam_a.rotation.toRotationMatrix();
  const cv::Mat warp = (cv::Mat_<double>(2, 3) << r(0, 0), r(0, 1),
                        camera.cx - r(0, 0) * camera.cx - r(0, 1) * camera.cy, r(1, 0), r(1, 1),
                        camera.cy - r(1, 0) * camera.cx - r(1, 1) * camera.cy);
  cv::warpAffine(gray_a, gray_b, warp, gray_a.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);

  const cv::Ptr<cv::ORB> orb = cv::ORB::create(500);
  std::vector<cv::KeyPoint> kps_a, kps_b;
  cv::Mat desc_a, desc_b;
  orb->detectAndCompute(gray_a, cv::noArray(), kps_a, desc_a);
  orb->detectAndCompute(gray_b, cv::noArray(), kps_b, desc_b);

  GuidedMatcherWorkspace workspace;
  const GuidedMatcherOptions matcher_options;
  MatchResult result = workspace.Match(camera, motion, kps_a, desc_a, cv::Mat(), kps_b, desc_b,
                                       PredictionOptions(), matcher_options);
  const PatchMatchingStats look =
      MatchByPatch(workspace, kps_a, desc_a, kps_b, desc_b, gray_a, gray_b, camera, matcher_options,
                   PatchMatchingOptions(), &result);
  RefineMatches(gray_a, gray_b, kps_a, kps_b, workspace.predictions(), camera, SubpixelOptions(),
                result.matches);
  int correct = 0;
  for (const Match& m : result.matches) {
    const cv::Point2f& pa = kps_a[static_cast<size_t>(m.query_idx)].pt;
    const cv::Point2f& pb = kps_b[static_cast<size_t>(m.train_idx)].pt;
    const Eigen::Vector2d truth(
        warp.at<double>(0, 0) * pa.x + warp.at<double>(0, 1) * pa.y + warp.at<double>(0, 2),
        warp.at<double>(1, 0) * pa.x + warp.at<double>(1, 1) * pa.y + warp.at<double>(1, 2));
    const Eigen::Vector2d uv = std::isfinite(m.refined_uv_b.x()) ? m.refined_uv_b.cast<double>()
                                                                 : Eigen::Vector2d(pb.x, pb.y);
    correct += (uv - truth).norm() < 1.0;
  }
  const int n = static_cast<int>(result.matches.size());
  std::printf("%zu / %zu keypoints, %d matches (%d by the patch look), %d within 1 px\n",
              kps_a.size(), kps_b.size(), n, look.matched, correct);
  return (n > static_cast<int>(kps_a.size()) / 3 && correct >= n - n / 50) ? 0 : 1;
}
