#include "imumatch/frontend/pose_estimation.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/statistics.h"

namespace imumatch {

void PoseFitOptions::Check() const {
  IMUMATCH_CHECK(std::isfinite(ransac_px) && ransac_px > 0.0, "ransac_px=" << ransac_px);
  IMUMATCH_CHECK(iterations >= 1 && iterations <= 100000, "iterations=" << iterations);
  IMUMATCH_CHECK(min_inliers >= 3, "min_inliers=" << min_inliers);
}

PoseFit FitPosePnp(const std::vector<Eigen::Vector3d>& points_a,
                   const std::vector<Eigen::Vector2d>& pixels_b,
                   const PixelUndistorter& undistorter, const Rigid3d& guess,
                   const PoseFitOptions& options) {
  options.Check();
  IMUMATCH_CHECK(points_a.size() == pixels_b.size(),
                 points_a.size() << " points for " << pixels_b.size() << " pixels");
  PoseFit fit;
  fit.correspondences = static_cast<int>(points_a.size());
  fit.inlier_mask.assign(points_a.size(), 0);
  if (fit.correspondences < std::max(options.min_inliers, 4)) {
    fit.reason = "too few 3D-2D correspondences (" + std::to_string(fit.correspondences) + ")";
    return fit;
  }
  const PinholeCamera& camera = undistorter.camera();
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (size_t i = 0; i < points_a.size(); ++i) {
    object.emplace_back(static_cast<float>(points_a[i].x()), static_cast<float>(points_a[i].y()),
                        static_cast<float>(points_a[i].z()));
    const Eigen::Vector2d ideal = undistorter.ToIdeal(pixels_b[i]);
    image.emplace_back(static_cast<float>(ideal.x()), static_cast<float>(ideal.y()));
  }
  const cv::Mat k =
      (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  const Eigen::AngleAxisd aa(guess.rotation);
  const Eigen::Vector3d r0 = aa.angle() * aa.axis();
  rvec = (cv::Mat_<double>(3, 1) << r0.x(), r0.y(), r0.z());
  tvec = (cv::Mat_<double>(3, 1) << guess.translation.x(), guess.translation.y(),
          guess.translation.z());
  std::vector<int> inliers;
  cv::setRNGSeed(static_cast<int>(options.seed));
  bool ok = false;
  try {
    ok = cv::solvePnPRansac(object, image, k, cv::noArray(), rvec, tvec, true, options.iterations,
                            static_cast<float>(options.ransac_px), 0.999, inliers,
                            cv::SOLVEPNP_ITERATIVE);
  } catch (const cv::Exception& e) {
    fit.reason = std::string("PnP failed: ") + e.what();
    return fit;
  }
  if (!ok || static_cast<int>(inliers.size()) < options.min_inliers) {
    fit.reason = "PnP: " + std::to_string(inliers.size()) + " inliers";
    return fit;
  }
  const Eigen::Vector3d rv(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2));
  const Eigen::Vector3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  if (!rv.allFinite() || !t.allFinite()) {
    fit.reason = "PnP: non-finite pose";
    return fit;
  }
  fit.cam_b_from_cam_a = Rigid3d(Eigen::Quaterniond(ExpSO3(rv)), t);
  double sum2 = 0.0;
  for (int i : inliers) {
    fit.inlier_mask[static_cast<size_t>(i)] = 1;
    const Eigen::Vector3d q = fit.cam_b_from_cam_a * points_a[static_cast<size_t>(i)];
    const Eigen::Vector2d uv = camera.NormalizedToIdeal(q.hnormalized());
    sum2 += (uv - Eigen::Vector2d(image[static_cast<size_t>(i)].x, image[static_cast<size_t>(i)].y))
                .squaredNorm();
  }
  fit.inliers = static_cast<int>(inliers.size());
  fit.rms_px = std::sqrt(sum2 / fit.inliers);
  fit.ok = true;
  return fit;
}

PoseFit FitPoseEpipolar(const std::vector<Eigen::Vector2d>& pixels_a,
                        const std::vector<Eigen::Vector2d>& pixels_b,
                        const PixelUndistorter& undistorter, const Rigid3d& guess,
                        const PoseFitOptions& options) {
  options.Check();
  IMUMATCH_CHECK(pixels_a.size() == pixels_b.size(),
                 pixels_a.size() << " pixels in A for " << pixels_b.size() << " in B");
  PoseFit fit;
  fit.correspondences = static_cast<int>(pixels_a.size());
  fit.inlier_mask.assign(pixels_a.size(), 0);
  fit.cam_b_from_cam_a = guess;
  const double scale = guess.translation.norm();
  if (!(scale >= 1e-3)) {
    fit.reason = "no baseline (IMU translation " + std::to_string(scale * 1000.0) + " mm)";
    return fit;
  }
  if (fit.correspondences < options.min_inliers) {
    fit.reason = "too few correspondences (" + std::to_string(fit.correspondences) + ")";
    return fit;
  }
  const PinholeCamera& camera = undistorter.camera();
  const double f = 0.5 * (camera.fx + camera.fy);
  const Eigen::Matrix3d r = guess.rotation.toRotationMatrix();
  // Bearings (normalised, z = 1) and the constraint normals n_i = R x_a x x_b: t . n_i = 0.
  std::vector<Eigen::Vector3d> ra(pixels_a.size()), xb(pixels_a.size()), n(pixels_a.size());
  for (size_t i = 0; i < pixels_a.size(); ++i) {
    const Eigen::Vector2d ia = undistorter.ToIdeal(pixels_a[i]);
    const Eigen::Vector2d ib = undistorter.ToIdeal(pixels_b[i]);
    const Eigen::Vector3d xa = camera.IdealToNormalized(ia).homogeneous();
    xb[i] = camera.IdealToNormalized(ib).homogeneous();
    ra[i] = r * xa;
    n[i] = ra[i].cross(xb[i]);
  }
  // Epipolar distance in B (ideal px) of correspondence i for direction t: |x_b . (t x R x_a)|
  // over the norm of the line's normal.
  auto distance = [&](const Eigen::Vector3d& t, size_t i) {
    const Eigen::Vector3d line = t.cross(ra[i]);
    const double d = std::hypot(line.x(), line.y());
    return d > 0.0 ? f * std::fabs(xb[i].dot(line)) / d : 1e9;
  };
  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<size_t> pick(0, pixels_a.size() - 1);
  Eigen::Vector3d best_t = guess.translation.normalized();
  int best_count = -1;
  for (int it = 0; it < options.iterations; ++it) {
    const size_t i = pick(rng), j = pick(rng);
    if (i == j) continue;
    Eigen::Vector3d t = n[i].cross(n[j]);
    if (!(t.norm() > 1e-12)) continue;
    t.normalize();
    int count = 0;
    for (size_t k = 0; k < n.size(); ++k) count += distance(t, k) <= options.ransac_px ? 1 : 0;
    if (count > best_count) {
      best_count = count;
      best_t = t;
    }
  }
  // Refine: the smallest right singular vector of the stacked normals, each weighted by the
  // inverse length of its epipolar line's normal (so that the least squares minimise distances in
  // the image) and by a Cauchy weight whose scale follows the inliers' median residual (an
  // outlier lying near its long epipolar line does not pull the direction); inliers re-selected
  // with every new direction.
  Eigen::Vector3d t = best_t;
  std::vector<size_t> in;
  std::vector<double> resid;
  for (int iteration = 0; iteration < 10; ++iteration) {
    in.clear();
    resid.clear();
    for (size_t k = 0; k < n.size(); ++k) {
      const double dk = distance(t, k);
      if (dk <= options.ransac_px) {
        in.push_back(k);
        resid.push_back(dk);
      }
    }
    if (static_cast<int>(in.size()) < options.min_inliers) break;
    std::vector<double> sorted = resid;
    const double c = std::max(0.05, 1.5 * UpperMedianInPlace(sorted));
    Eigen::MatrixXd a(in.size(), 3);
    for (size_t k = 0; k < in.size(); ++k) {
      const Eigen::Vector3d line = t.cross(ra[in[k]]);
      const double w = 1.0 / std::max(std::hypot(line.x(), line.y()), 1e-9);
      const double rel = resid[k] / c;
      a.row(static_cast<Eigen::Index>(k)) = w / std::sqrt(1.0 + rel * rel) * n[in[k]].transpose();
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
    const Eigen::Vector3d next = svd.matrixV().col(2);
    t = next.dot(t) < 0.0 ? Eigen::Vector3d(-next) : next;
  }
  in.clear();
  for (size_t k = 0; k < n.size(); ++k) {
    if (distance(t, k) <= options.ransac_px) in.push_back(k);
  }
  if (static_cast<int>(in.size()) < options.min_inliers) {
    fit.reason = "epipolar: " + std::to_string(in.size()) + " inliers";
    return fit;
  }
  // Cheirality: x_b z_b = R x_a z_a + t; the sign that puts most points in front of both.
  int front = 0;
  for (size_t k : in) {
    // Depth in A from the two rays (least squares): z_a (R x_a) - z_b x_b = -t.
    Eigen::Matrix<double, 3, 2> m;
    m.col(0) = ra[k];
    m.col(1) = -xb[k];
    const Eigen::Vector2d z = m.colPivHouseholderQr().solve(-t);
    front += (z.x() > 0.0 && z.y() > 0.0) ? 1 : -1;
  }
  if (front < 0) t = -t;
  fit.cam_b_from_cam_a = Rigid3d(guess.rotation, scale * t);
  double sum2 = 0.0;
  for (size_t k : in) {
    fit.inlier_mask[k] = 1;
    const double d = distance(t, k);
    sum2 += d * d;
  }
  fit.inliers = static_cast<int>(in.size());
  fit.rms_px = std::sqrt(sum2 / fit.inliers);
  fit.ok = true;
  return fit;
}

}  // namespace imumatch
