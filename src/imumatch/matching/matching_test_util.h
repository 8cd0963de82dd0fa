#pragma once

// Test-only helpers for the matching tests that align image patches (KLT, sub-pixel refinement);
// not installed.

#include <cmath>
#include <cstdint>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/so3.h"

namespace imumatch::testing {

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
