#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/core/so3.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/match_types.h"

// Scenes of matches with a known motion for the tests of the motion fit and of what uses it
// (motion_refit_test.cc, rotation_from_fit_test.cc, second_pass_test.cc).
namespace imumatch::refit_test {

inline PinholeCamera Camera() { return PinholeCamera::KinectDefault(); }

// Appends the match of a keypoint of A at uv_a with one of B at uv_b (both of size 7).
inline void AddMatch(const Eigen::Vector2d& uv_a, const Eigen::Vector2d& uv_b,
                     std::vector<cv::KeyPoint>* keypoints_a, std::vector<cv::KeyPoint>* keypoints_b,
                     std::vector<Match>* matches) {
  Match m;
  m.query_idx = static_cast<int>(keypoints_a->size());
  m.train_idx = static_cast<int>(keypoints_b->size());
  keypoints_a->emplace_back(static_cast<float>(uv_a.x()), static_cast<float>(uv_a.y()), 7.0f);
  keypoints_b->emplace_back(static_cast<float>(uv_b.x()), static_cast<float>(uv_b.y()), 7.0f);
  matches->push_back(m);
}

inline Rigid3d TrueMotion() {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.01, -0.03, 0.02)), Eigen::Vector3d(0.05, -0.02, 0.08));
}

// Matches of points 2-6 m in front of A seen from B (the true motion): B's positions with Gaussian
// pixel noise, a share of them replaced by a wrong position a few pixels to 30 px away (inside
// the windows an IMU would give, as a first pass's false matches are). depths: A's depth per
// keypoint (exact).
struct MatchScene {
  std::vector<cv::KeyPoint> keypoints_a, keypoints_b;
  std::vector<Match> matches;
  std::vector<float> depths;
};
inline MatchScene MakeMatchScene(const Rigid3d& b_from_a, int n, double noise_px,
                                 double outlier_share, uint64_t seed = 3) {
  const PinholeCamera c = Camera();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, noise_px);
  MatchScene s;
  while (static_cast<int>(s.matches.size()) < n) {
    const Eigen::Vector2d uv(40 + 560 * u(rng), 40 + 400 * u(rng));
    const double z = 2.0 + 4.0 * u(rng);
    const Eigen::Vector3d q = b_from_a * c.Unproject(uv, z);
    Eigen::Vector2d pb(c.fx * q.x() / q.z() + c.cx, c.fy * q.y() / q.z() + c.cy);
    if (u(rng) < outlier_share) {
      const double a = 2.0 * M_PI * u(rng), r = 3.0 + 27.0 * u(rng);
      pb += r * Eigen::Vector2d(std::cos(a), std::sin(a));
    } else {
      pb += Eigen::Vector2d(gauss(rng), gauss(rng));
    }
    AddMatch(uv, pb, &s.keypoints_a, &s.keypoints_b, &s.matches);
    s.depths.push_back(static_cast<float>(z));
  }
  return s;
}

// The IMU's motion: the truth moved by `offset` ([dtheta; dt]), with a diagonal covariance.
inline CameraMotion Prior(const Eigen::Matrix<double, 6, 1>& offset,
                          const Eigen::Matrix<double, 6, 1>& sigma) {
  CameraMotion m;
  m.cam_b_from_cam_a = Rigid3d(ExpSO3(offset.head<3>()) * TrueMotion().rotation,
                               TrueMotion().translation + offset.tail<3>());
  m.covariance = sigma.cwiseAbs2().asDiagonal();
  return m;
}

inline Eigen::Matrix<double, 6, 1> Vec6(double a, double b, double c, double d, double e,
                                        double f) {
  Eigen::Matrix<double, 6, 1> v;
  v << a, b, c, d, e, f;
  return v;
}

}  // namespace imumatch::refit_test
