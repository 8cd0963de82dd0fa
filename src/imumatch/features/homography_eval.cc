#include "imumatch/features/homography_eval.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/features2d.hpp>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

std::vector<cv::Point2f> Project(const std::vector<cv::KeyPoint>& keypoints, const cv::Matx33d& h) {
  std::vector<cv::Point2f> out;
  out.reserve(keypoints.size());
  for (const cv::KeyPoint& kp : keypoints) {
    const cv::Vec3d p = h * cv::Vec3d(kp.pt.x, kp.pt.y, 1.0);
    if (std::abs(p[2]) < 1e-12) {
      out.emplace_back(-1e9f, -1e9f);
    } else {
      out.emplace_back(static_cast<float>(p[0] / p[2]), static_cast<float>(p[1] / p[2]));
    }
  }
  return out;
}

bool Inside(const cv::Point2f& p, cv::Size size) {
  return p.x >= -0.5f && p.y >= -0.5f && p.x < static_cast<float>(size.width) - 0.5f &&
         p.y < static_cast<float>(size.height) - 0.5f;
}

}  // namespace

void HomographyEvalOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(pixel_tolerance) && pixel_tolerance > 0,
                 "HomographyEvalOptions.pixel_tolerance must be > 0, got " << pixel_tolerance);
  IMUMATCH_CHECK(ratio > 0 && ratio <= 1,
                 "HomographyEvalOptions.ratio must be in (0, 1], got " << ratio);
}

HomographyEval EvaluateOnHomography(const Features& features1, const Features& features2,
                                    const cv::Mat& h_2_from_1, cv::Size size1, cv::Size size2,
                                    int norm, const HomographyEvalOptions& options) {
  options.Check();
  IMUMATCH_CHECK(h_2_from_1.rows == 3 && h_2_from_1.cols == 3 && h_2_from_1.channels() == 1,
                 "EvaluateOnHomography: the homography must be 3x3");
  IMUMATCH_CHECK(size1.area() > 0 && size2.area() > 0, "EvaluateOnHomography: empty image size");
  cv::Mat h64;
  h_2_from_1.convertTo(h64, CV_64F);
  const cv::Matx33d h(h64);
  IMUMATCH_CHECK(std::abs(cv::determinant(h)) > 1e-12, "EvaluateOnHomography: singular homography");
  const cv::Matx33d h_inv = h.inv();

  HomographyEval out;
  out.keypoints1 = static_cast<int>(features1.keypoints.size());
  out.keypoints2 = static_cast<int>(features2.keypoints.size());
  const std::vector<cv::Point2f> in2 = Project(features1.keypoints, h);
  const std::vector<cv::Point2f> in1 = Project(features2.keypoints, h_inv);
  const float tol2 = static_cast<float>(options.pixel_tolerance * options.pixel_tolerance);
  for (size_t i = 0; i < in2.size(); ++i) {
    if (!Inside(in2[i], size2)) continue;
    ++out.common1;
    for (const cv::KeyPoint& kp2 : features2.keypoints) {
      const cv::Point2f d = kp2.pt - in2[i];
      if (d.dot(d) <= tol2) {
        ++out.repeated;
        break;
      }
    }
  }
  for (const cv::Point2f& p : in1) out.common2 += Inside(p, size1) ? 1 : 0;
  const int common = std::min(out.common1, out.common2);
  out.repeatability = common > 0 ? std::min(1.0, static_cast<double>(out.repeated) / common) : 0.0;

  if (features1.descriptors.rows >= 1 && features2.descriptors.rows >= 2) {
    cv::BFMatcher matcher(norm);
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(features1.descriptors, features2.descriptors, knn, 2);
    for (const std::vector<cv::DMatch>& m : knn) {
      if (m.size() < 2 || !(m[0].distance < options.ratio * m[1].distance)) continue;
      ++out.matches;
      const cv::Point2f d = features2.keypoints[m[0].trainIdx].pt - in2[m[0].queryIdx];
      if (d.dot(d) <= tol2) ++out.correct_matches;
    }
  }
  out.precision = out.matches > 0 ? static_cast<double>(out.correct_matches) / out.matches : 0.0;
  return out;
}

}  // namespace imumatch
