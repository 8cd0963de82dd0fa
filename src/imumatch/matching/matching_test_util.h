#pragma once

// Test-only helpers shared by the matching tests (not installed): a synthetic frame pair of
// keypoints and descriptors with its true partners, and textures with similarity warps for the
// tests that align image patches (KLT, sub-pixel refinement, the patch look).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/so3.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/matching/match_types.h"

namespace imumatch::testing {

// A synthetic pair: random 3D points in front of camera A, projected into A and B with a known
// motion; binary descriptors random in A and copied to B with a few flipped bits; extra distractor
// keypoints with random descriptors in B.
struct SyntheticPair {
  PinholeCamera camera;
  CameraMotion motion;  // the motion given to the matcher
  std::vector<KeypointInfo> kps_a, kps_b;
  std::vector<float> depth_a;
  cv::Mat desc_a, desc_b;
  std::vector<int> partner;  // partner[i] = index in B of A's keypoint i
};

inline cv::Mat RandomDescriptor(std::mt19937& rng) {
  cv::Mat d(1, 32, CV_8U);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int k = 0; k < 32; ++k) d.at<uint8_t>(0, k) = static_cast<uint8_t>(byte(rng));
  return d;
}

// true_motion moves the points; the returned pair carries `given` (nominal) as its motion.
inline SyntheticPair MakePair(int n_points, int n_distractors, const Rigid3d& true_motion,
                              const CameraMotion& given, uint32_t seed, int flipped_bits = 3) {
  SyntheticPair s;
  s.camera = PinholeCamera::KinectDefault();
  s.motion = given;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uu(0, 639), uv(0, 479), uz(0.8, 4.0);
  std::vector<cv::Mat> rows_a, rows_b;
  while (static_cast<int>(s.kps_a.size()) < n_points) {
    const Eigen::Vector2d pa(uu(rng), uv(rng));
    const double z = uz(rng);
    const Eigen::Vector3d p_b = true_motion * s.camera.Unproject(pa, z);
    const auto pb = s.camera.Project(p_b);
    if (!pb || !s.camera.IsInside(*pb, 1.0)) continue;
    s.kps_a.push_back(
        KeypointInfo{static_cast<float>(pa.x()), static_cast<float>(pa.y()), -1, 0, 0});
    s.kps_b.push_back(
        KeypointInfo{static_cast<float>(pb->x()), static_cast<float>(pb->y()), -1, 0, 0});
    s.depth_a.push_back(static_cast<float>(z));
    cv::Mat da = RandomDescriptor(rng), db = da.clone();
    // Exactly flipped_bits distinct bits.
    std::vector<int> bits(256);
    for (int b = 0; b < 256; ++b) bits[b] = b;
    std::shuffle(bits.begin(), bits.end(), rng);
    for (int f = 0; f < flipped_bits; ++f) {
      db.at<uint8_t>(0, bits[f] / 8) ^= static_cast<uint8_t>(1u << (bits[f] % 8));
    }
    rows_a.push_back(da);
    rows_b.push_back(db);
  }
  for (int k = 0; k < n_distractors; ++k) {
    s.kps_b.push_back(
        KeypointInfo{static_cast<float>(uu(rng)), static_cast<float>(uv(rng)), -1, 0, 0});
    rows_b.push_back(RandomDescriptor(rng));
  }
  // Shuffle B so partner indices are not the identity.
  std::vector<int> perm(s.kps_b.size());
  for (size_t k = 0; k < perm.size(); ++k) perm[k] = static_cast<int>(k);
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<KeypointInfo> kb(perm.size());
  std::vector<cv::Mat> rb(perm.size());
  std::vector<int> new_pos(perm.size());
  for (size_t k = 0; k < perm.size(); ++k) {
    kb[k] = s.kps_b[perm[k]];
    rb[k] = rows_b[perm[k]];
    new_pos[perm[k]] = static_cast<int>(k);
  }
  s.kps_b = kb;
  for (int i = 0; i < n_points; ++i) s.partner.push_back(new_pos[i]);
  cv::vconcat(rows_a, s.desc_a);
  cv::vconcat(rb, s.desc_b);
  return s;
}

// A 320 x 240 8-bit texture without repetition: Gaussian noise blurred with sigma_px, stretched
// to [lo, hi].
inline cv::Mat SmoothTexture(int seed, double sigma_px = 2.0, double lo = 20.0, double hi = 235.0) {
  cv::Mat noise(240, 320, CV_32F);
  cv::RNG rng(static_cast<uint64_t>(seed));
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), sigma_px);
  cv::normalize(noise, noise, lo, hi, cv::NORM_MINMAX);
  cv::Mat out;
  noise.convertTo(out, CV_8U);
  return out;
}

// Image B and the exact position in B of every point of A: p_b = a p_a + t.
struct WarpedImage {
  cv::Mat b;
  Eigen::Matrix2d a;
  Eigen::Vector2d t;
  Eigen::Vector2d Map(const Eigen::Vector2d& p) const { return a * p + t; }
};

// B = gain * A moved by the similarity p_b = centre + scale R(angle) (p_a - centre) + shift,
// + bias (cv::warpAffine, cubic, reflected border; centre = the image's centre (160, 120)).
inline WarpedImage WarpSimilarity(const cv::Mat& img, double angle_deg, double scale,
                                  const Eigen::Vector2d& shift, double gain = 1.0,
                                  double bias = 0.0) {
  const double th = angle_deg * kPi / 180.0;
  WarpedImage w;
  w.a << scale * std::cos(th), -scale * std::sin(th), scale * std::sin(th), scale * std::cos(th);
  const Eigen::Vector2d centre(160.0, 120.0);
  w.t = centre - w.a * centre + shift;
  const cv::Mat m =
      (cv::Mat_<double>(2, 3) << w.a(0, 0), w.a(0, 1), w.t.x(), w.a(1, 0), w.a(1, 1), w.t.y());
  cv::Mat warped;
  cv::warpAffine(img, warped, m, img.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  warped.convertTo(w.b, -1, gain, bias);
  return w;
}

}  // namespace imumatch::testing
