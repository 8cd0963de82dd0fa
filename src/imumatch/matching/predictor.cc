#include "imumatch/matching/predictor.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/matching/depth_reading.h"

namespace imumatch {

namespace {
constexpr double kMinForwardDepth = 1e-6;  // q_z below this counts as behind camera B

// Of the symmetric part: a covariance summed from products can come out asymmetric in its last
// bits, and c01 * c10 < 0 then put a negative under the root of an isotropic one (NaN windows for
// a pure rotation without depth).
double MaxEigenvalue(const Eigen::Matrix2d& c) {
  const double half_trace = 0.5 * (c(0, 0) + c(1, 1));
  const double half_diff = 0.5 * (c(0, 0) - c(1, 1));
  const double off = 0.5 * (c(0, 1) + c(1, 0));
  return half_trace + std::sqrt(half_diff * half_diff + off * off);
}

// Liang-Barsky: clips the segment p0 + s (p1 - p0), s in [0, 1], to the box. False when empty.
bool ClipSegment(Eigen::Vector2d& p0, Eigen::Vector2d& p1, double x0, double y0, double x1,
                 double y1) {
  const Eigen::Vector2d d = p1 - p0;
  double s0 = 0.0, s1 = 1.0;
  const std::array<double, 4> p = {-d.x(), d.x(), -d.y(), d.y()};
  const std::array<double, 4> q = {p0.x() - x0, x1 - p0.x(), p0.y() - y0, y1 - p0.y()};
  for (int k = 0; k < 4; ++k) {
    if (p[k] == 0.0) {
      if (q[k] < 0.0) return false;
      continue;
    }
    const double r = q[k] / p[k];
    if (p[k] < 0.0) {
      s0 = std::max(s0, r);
    } else {
      s1 = std::min(s1, r);
    }
    if (s0 > s1) return false;
  }
  const Eigen::Vector2d a = p0 + s0 * d, b = p0 + s1 * d;
  p0 = a;
  p1 = b;
  return true;
}
}  // namespace

void SceneNearDepthOptions::Check() const {
  IMUMATCH_CHECK(pilot_queries >= 1, "scene_near.pilot_queries=" << pilot_queries);
  IMUMATCH_CHECK(pilot_ratio > 0.0 && pilot_ratio <= 1.0, "scene_near.pilot_ratio=" << pilot_ratio);
  IMUMATCH_CHECK(min_samples >= 1, "scene_near.min_samples=" << min_samples);
  IMUMATCH_CHECK(near_quantile >= 0.0 && near_quantile < 1.0,
                 "scene_near.near_quantile=" << near_quantile);
  IMUMATCH_CHECK(near_margin > 0.0 && near_margin <= 1.0, "scene_near.near_margin=" << near_margin);
}

void PredictionOptions::Check() const {
  scene_near.Check();
  IMUMATCH_CHECK(std::isfinite(min_depth) && min_depth > 0.0, "min_depth=" << min_depth);
  IMUMATCH_CHECK(max_depth > min_depth, "max_depth=" << max_depth << " <= min_depth");
  IMUMATCH_CHECK(std::isfinite(segment_min_depth) && segment_min_depth > 0.0,
                 "segment_min_depth=" << segment_min_depth);
  IMUMATCH_CHECK(segment_max_depth > segment_min_depth,
                 "segment_max_depth=" << segment_max_depth << " <= segment_min_depth");
  IMUMATCH_CHECK(std::isfinite(depth_noise_coeff) && depth_noise_coeff >= 0.0,
                 "depth_noise_coeff=" << depth_noise_coeff);
  IMUMATCH_CHECK(std::isfinite(keypoint_sigma_px) && keypoint_sigma_px >= 0.0,
                 "keypoint_sigma_px=" << keypoint_sigma_px);
  IMUMATCH_CHECK(sigma_scaling == KeypointSigmaScaling::kNone ||
                     sigma_scaling == KeypointSigmaScaling::kSize ||
                     sigma_scaling == KeypointSigmaScaling::kOctave,
                 "sigma_scaling");
  IMUMATCH_CHECK(std::isfinite(octave_scale) && octave_scale >= 1.0,
                 "octave_scale=" << octave_scale);
  IMUMATCH_CHECK(gate_probability > 0.0 && gate_probability < 1.0,
                 "gate_probability=" << gate_probability << " must be in (0, 1)");
  IMUMATCH_CHECK(std::isfinite(min_half_size) && min_half_size >= 0.0,
                 "min_half_size=" << min_half_size);
  IMUMATCH_CHECK(std::isfinite(max_half_size) && max_half_size >= min_half_size,
                 "max_half_size=" << max_half_size << " < min_half_size");
  IMUMATCH_CHECK(std::isfinite(fixed_half_size) && fixed_half_size >= 0.0,
                 "fixed_half_size=" << fixed_half_size);
}

double PredictionOptions::GateChiSquare() const { return -2.0 * std::log(1.0 - gate_probability); }

const char* ToString(PredictionStatus status) {
  switch (status) {
    case PredictionStatus::kWithDepth:
      return "with_depth";
    case PredictionStatus::kWithoutDepth:
      return "without_depth";
    case PredictionStatus::kBehindCamera:
      return "behind_camera";
    case PredictionStatus::kOutsideImage:
      return "outside_image";
    case PredictionStatus::kInvalid:
      return "invalid";
  }
  return "?";
}

float KeypointPrediction::SegmentDistanceSquared(float x, float y) const {
  const float dx = segment_end.x() - segment_start.x(), dy = segment_end.y() - segment_start.y();
  const float px = x - segment_start.x(), py = y - segment_start.y();
  const float len2 = dx * dx + dy * dy;
  float s = len2 > 0.0f ? (px * dx + py * dy) / len2 : 0.0f;
  s = std::clamp(s, 0.0f, 1.0f);
  const float ex = px - s * dx, ey = py - s * dy;
  return ex * ex + ey * ey;
}

KeypointPredictor::KeypointPredictor(const PinholeCamera& camera, const CameraMotion& motion,
                                     const PredictionOptions& options)
    : camera_(camera), options_(options) {
  camera.Check();
  distorted_ = camera.HasDistortion();
  // The ideal image's bounding box from its border every 4 px (the box only bounds the search
  // regions; the exact inside test is done on the distorted position).
  Eigen::Vector2d lo, hi;
  camera.IdealImageBounds(4.0, &lo, &hi);
  min_x_ = lo.x();
  min_y_ = lo.y();
  max_x_ = hi.x();
  max_y_ = hi.y();
  Init(motion);
}

KeypointPredictor::KeypointPredictor(const PixelUndistorter& undistorter,
                                     const CameraMotion& motion, const PredictionOptions& options)
    : camera_(undistorter.camera()), undistorter_(&undistorter), options_(options) {
  camera_.Check();
  distorted_ = !undistorter.identity();
  min_x_ = undistorter.ideal_min_x();
  min_y_ = undistorter.ideal_min_y();
  max_x_ = undistorter.ideal_max_x();
  max_y_ = undistorter.ideal_max_y();
  Init(motion);
}

void KeypointPredictor::Init(const CameraMotion& motion) {
  options_.Check();
  IMUMATCH_CHECK(motion.covariance.allFinite(), "motion covariance is not finite");
  r_ = motion.cam_b_from_cam_a.RotationMatrix();
  t_ = motion.cam_b_from_cam_a.translation;
  r_col0_fx_ = r_.col(0) / camera_.fx;
  r_col1_fy_ = r_.col(1) / camera_.fy;
  IMUMATCH_CHECK(r_.allFinite() && t_.allFinite(), "motion is not finite");
  motion_cov_ = motion.covariance;
  has_motion_cov_ = !motion_cov_.isZero(0.0);
  chi2_ = options_.GateChiSquare();
  const double length2 = t_.squaredNorm();
  sign_open_ = !(length2 > chi2_ * t_.dot(motion_cov_.bottomRightCorner<3, 3>() * t_) / length2);
}

Eigen::Matrix2d KeypointPredictor::PixelNoise(const Eigen::Vector2d& uv,
                                              double pixel_variance) const {
  if (!distorted_) return pixel_variance * Eigen::Matrix2d::Identity();
  if (undistorter_ != nullptr) {
    return pixel_variance * undistorter_->NoiseStretchAt(uv.x(), uv.y()).cast<double>();
  }
  const Eigen::Matrix2d m = camera_.IdealFromPixelJacobian(uv);
  return pixel_variance * m * m.transpose();
}

Eigen::Vector2d KeypointPredictor::PinholeProject(const Eigen::Vector3d& q) const {
  return Eigen::Vector2d(camera_.fx * q.x() / q.z() + camera_.cx,
                         camera_.fy * q.y() / q.z() + camera_.cy);
}

Eigen::Matrix3d KeypointPredictor::InfiniteHomography() const {
  const Eigen::Matrix3d k = camera_.K();
  return k * r_ * k.inverse();
}

Eigen::Vector2d KeypointPredictor::RotationOnly(const Eigen::Vector2d& uv_a) const {
  const Eigen::Vector2d xy = camera_.IdealToNormalized(uv_a);
  const Eigen::Vector3d rx = r_ * Eigen::Vector3d(xy.x(), xy.y(), 1.0);
  if (!(rx.z() > kMinForwardDepth)) return Eigen::Vector2d::Constant(std::nan(""));
  return PinholeProject(rx);
}

// q = R x + rho t is the point in B up to the positive factor z (x = [x y 1], rho = 1/z); its pixel
// is pi(q). With R_true = Exp(dtheta) R and t_true = t + dt:
//   dq/dtheta = -Hat(R x),  dq/dt = rho I,  dq/drho = t,  dq/du_a = R e1 / fx,  dq/dv_a = R e2 /
//   fy.
// sigma_rho = sigma_z / z^2 (= depth_noise_coeff for the quadratic Kinect model). The keypoint's
// localisation noise in A enters through dq/du_a, dq/dv_a; B's adds pixel_cov_b.
Eigen::Matrix2d KeypointPredictor::Covariance(const Eigen::Vector3d& rx, double rho,
                                              double rho_variance,
                                              const Eigen::Matrix2d& pixel_cov_a,
                                              const Eigen::Matrix2d& pixel_cov_b) const {
  const Eigen::Vector3d q = rx + rho * t_;
  const double iz = 1.0 / q.z();
  const double u = q.x() * iz, w = q.y() * iz;
  // pi'(q) v, computed directly in 2-D (no 3x3 products for the common terms).
  const auto dpi = [&](const Eigen::Vector3d& v) {
    return Eigen::Vector2d(camera_.fx * (v.x() - u * v.z()) * iz,
                           camera_.fy * (v.y() - w * v.z()) * iz);
  };
  const Eigen::Vector2d jt = dpi(t_);
  const Eigen::Vector2d a0 = dpi(r_col0_fx_), a1 = dpi(r_col1_fy_);
  Eigen::Matrix2d a;
  a << a0, a1;
  Eigen::Matrix2d c = rho_variance * jt * jt.transpose() + pixel_cov_b;
  c.noalias() += a * pixel_cov_a * a.transpose();
  if (has_motion_cov_) {
    Eigen::Matrix<double, 2, 3> jp;
    jp << camera_.fx * iz, 0.0, -camera_.fx * u * iz, 0.0, camera_.fy * iz, -camera_.fy * w * iz;
    Eigen::Matrix<double, 3, 6> jm;
    jm.leftCols<3>() = -Hat(rx);
    jm.rightCols<3>() = rho * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 2, 6> j = jp * jm;
    c.noalias() += j * motion_cov_ * j.transpose();
  }
  return c;
}

void KeypointPredictor::SetWindow(const Eigen::Matrix2d& cov, KeypointPrediction& p) const {
  p.covariance = cov.cast<float>();
  double hw, hh;
  if (options_.window_mode == WindowMode::kFixed) {
    hw = hh = options_.fixed_half_size;
  } else {
    hw = std::clamp(std::sqrt(chi2_ * std::max(cov(0, 0), 0.0)), options_.min_half_size,
                    options_.max_half_size);
    hh = std::clamp(std::sqrt(chi2_ * std::max(cov(1, 1), 0.0)), options_.min_half_size,
                    options_.max_half_size);
  }
  p.min_x = static_cast<float>(p.uv.x() - hw);
  p.max_x = static_cast<float>(p.uv.x() + hw);
  p.min_y = static_cast<float>(p.uv.y() - hh);
  p.max_y = static_cast<float>(p.uv.y() + hh);
}

// The local 2x2 Jacobian A = d uv_b / d uv_a of the mapping induced by a fronto-parallel plane
// through the point (the plane homography K (R + rho t e3^T) K^-1): pi'(q) [R e1 / fx, R e2 / fy].
// Its rotation part atan2(A10 - A01, A00 + A11) is the in-plane rotation of the image patch.
void KeypointPredictor::SetOrientation(const Eigen::Vector3d& q, KeypointPrediction& p) const {
  const double iz = 1.0 / q.z();
  const double ax = iz * iz;
  // pi'(q) applied to a 3-vector v: (fx (v.x q.z - q.x v.z), fy (v.y q.z - q.y v.z)) / q.z^2.
  const auto dpi = [&](const Eigen::Vector3d& v) {
    return Eigen::Vector2d(camera_.fx * (v.x() * q.z() - q.x() * v.z()) * ax,
                           camera_.fy * (v.y() * q.z() - q.y() * v.z()) * ax);
  };
  const Eigen::Vector2d a0 = dpi(r_.col(0)) / camera_.fx;
  const Eigen::Vector2d a1 = dpi(r_.col(1)) / camera_.fy;
  p.angle_change_deg = static_cast<float>(std::atan2(a0.y() - a1.x(), a0.x() + a1.y()) * kRadToDeg);
  p.local_affine << static_cast<float>(a0.x()), static_cast<float>(a1.x()),
      static_cast<float>(a0.y()), static_cast<float>(a1.y());
}

KeypointPredictor KeypointPredictor::WithSegmentMinDepth(double min_depth) const {
  IMUMATCH_CHECK(
      std::isfinite(min_depth) && min_depth > 0.0 && min_depth < options_.segment_max_depth,
      "segment min depth " << min_depth << " outside (0, " << options_.segment_max_depth << ")");
  KeypointPredictor copy = *this;
  copy.options_.segment_min_depth = min_depth;
  return copy;
}

double KeypointPredictor::InverseDepthOf(const Eigen::Vector2d& uv_a,
                                         const Eigen::Vector2d& uv_b) const {
  const Eigen::Vector2d xy_a = camera_.IdealToNormalized(uv_a);
  const Eigen::Vector2d xy_b = camera_.IdealToNormalized(uv_b);
  const Eigen::Vector3d xb(xy_b.x(), xy_b.y(), 1.0);
  const Eigen::Vector3d a = (r_ * Eigen::Vector3d(xy_a.x(), xy_a.y(), 1.0)).cross(xb);
  const Eigen::Vector3d b = t_.cross(xb);
  const double bb = b.squaredNorm();
  if (!(bb > 0.0) || !std::isfinite(bb)) return std::numeric_limits<double>::quiet_NaN();
  return -a.dot(b) / bb;
}

KeypointPrediction KeypointPredictor::Predict(const Eigen::Vector2d& uv_a, double depth_m,
                                              double sigma_scale) const {
  if (!options_.predict_without_depth && !options_.IsUsableDepth(depth_m)) {
    return KeypointPrediction();  // kInvalid
  }
  return PredictWithSegment(uv_a, depth_m, sigma_scale, 1.0 / options_.segment_max_depth,
                            1.0 / options_.segment_min_depth);
}

KeypointPrediction KeypointPredictor::PredictInInverseDepthRange(const Eigen::Vector2d& uv_a,
                                                                 double rho_far, double rho_near,
                                                                 double sigma_scale) const {
  double lo = 1.0 / options_.segment_max_depth, hi = 1.0 / options_.segment_min_depth;
  // Below zero when the translation's sign is open: down to the configured segment mirrored
  // beyond the rotation-only point.
  const double floor = sign_open_ ? std::min(lo, -hi) : lo;
  if (rho_far <= rho_near && rho_near >= floor && rho_far <= hi) {  // overlaps (not NaN)
    lo = std::max(rho_far, floor);
    hi = std::min(rho_near, hi);
  }
  return PredictWithSegment(uv_a, std::numeric_limits<double>::quiet_NaN(), sigma_scale, lo, hi);
}

KeypointPrediction KeypointPredictor::PredictWithSegment(const Eigen::Vector2d& uv_a,
                                                         double depth_m, double sigma_scale,
                                                         double rho_lo, double rho_hi) const {
  KeypointPrediction p;
  if (!uv_a.allFinite() || !std::isfinite(sigma_scale)) return p;
  const Eigen::Vector2d xy = camera_.IdealToNormalized(uv_a);
  const Eigen::Vector3d xa(xy.x(), xy.y(), 1.0);
  const Eigen::Vector3d rx = r_ * xa;
  const double sigma_px = options_.keypoint_sigma_px * sigma_scale;
  const double pixel_var = sigma_px * sigma_px;
  const Eigen::Matrix2d pixel_cov_a = PixelNoise(uv_a, pixel_var);
  const double range_a = xa.norm();  // |p_a| / z

  const bool has_depth = options_.IsUsableDepth(depth_m);
  if (has_depth) {
    const double rho = 1.0 / depth_m;
    const Eigen::Vector3d q = rx + rho * t_;
    if (!(q.z() > kMinForwardDepth)) {
      p.status = PredictionStatus::kBehindCamera;
      return p;
    }
    const Eigen::Vector2d uv = PinholeProject(q);
    p.uv = uv.cast<float>();
    p.segment_start = p.segment_end = p.uv;
    // Inside image B: tested on the distorted position (the ideal image is not a rectangle).
    const bool inside = distorted_
                            ? (uv.x() >= min_x_ && uv.x() <= max_x_ && uv.y() >= min_y_ &&
                               uv.y() <= max_y_ && camera_.IsInside(camera_.IdealToPixel(uv)))
                            : camera_.IsInside(uv);
    if (!inside) {
      p.status = PredictionStatus::kOutsideImage;
      return p;
    }
    p.status = PredictionStatus::kWithDepth;
    const double sigma_rho = options_.depth_noise_coeff;  // sigma_z / z^2 with sigma_z = c z^2
    SetWindow(Covariance(rx, rho, sigma_rho * sigma_rho, pixel_cov_a, PixelNoise(uv, pixel_var)),
              p);
    SetOrientation(q, p);
    p.scale_min = p.scale_max = static_cast<float>(range_a / q.norm());
    return p;
  }

  // The inverse-depth interval [rho_lo, rho_hi] of the swept segment, cut to the part in front of
  // camera B: q_z(rho) = rx.z + rho t.z > kMinForwardDepth.
  if (t_.z() > 0.0) {
    rho_lo = std::max(rho_lo, (kMinForwardDepth - rx.z()) / t_.z());
  } else if (t_.z() < 0.0) {
    rho_hi = std::min(rho_hi, (kMinForwardDepth - rx.z()) / t_.z());
  } else if (!(rx.z() > kMinForwardDepth)) {
    rho_hi = -1.0;  // empty
  }
  if (rx.z() > kMinForwardDepth) p.uv = RotationOnly(uv_a).cast<float>();
  if (!(rho_lo <= rho_hi)) {
    p.status = PredictionStatus::kBehindCamera;
    return p;
  }
  const Eigen::Vector3d q_near = rx + rho_hi * t_;  // the z_min end
  const Eigen::Vector3d q_far = rx + rho_lo * t_;   // the z_max end
  Eigen::Vector2d e0 = PinholeProject(q_near), e1 = PinholeProject(q_far);
  if (!ClipSegment(e0, e1, min_x_, min_y_, max_x_, max_y_)) {
    p.status = PredictionStatus::kOutsideImage;
    return p;
  }
  p.status = PredictionStatus::kWithoutDepth;
  p.segment_start = e0.cast<float>();
  p.segment_end = e1.cast<float>();
  const Eigen::Matrix2d c_near =
      Covariance(rx, rho_hi, 0.0, pixel_cov_a, PixelNoise(e0, pixel_var));
  const Eigen::Matrix2d c_far = Covariance(rx, rho_lo, 0.0, pixel_cov_a, PixelNoise(e1, pixel_var));
  const double l_near = MaxEigenvalue(c_near), l_far = MaxEigenvalue(c_far);
  p.covariance = (l_near >= l_far ? c_near : c_far).cast<float>();
  double r = options_.fixed_half_size;
  if (options_.window_mode == WindowMode::kUncertainty) {
    // The capsule holds the gate ellipse of each end moved along the segment: its radius is the
    // ellipses' extent across the segment, sqrt(chi2 n^T C n), and along it the segment spans
    // both ellipses, each reaching sqrt(chi2 d^T C d) either way from its end. An error of the
    // translation's length (the IMU's scale, which a fit to the images leaves open) moves a
    // point along its epipolar line, not across; when that error is as large as the translation
    // itself (hovering, a slow take-off), the near end's ellipse reaches past the far end: the
    // translation may point the other way, and the partner lie beyond the rotation-only point.
    double across = std::max(l_near, l_far), out_near = 0.0, out_far = 0.0;
    const Eigen::Vector2d along = e1 - e0;
    const double length = along.norm();
    if (length > 1e-9) {
      const Eigen::Vector2d d = along / length;
      const Eigen::Vector2d n(-d.y(), d.x());
      across = std::max(n.dot(c_near * n), n.dot(c_far * n));
      // Clamped as the radius is: no window reaches farther than max_half_size from its
      // prediction.
      out_near =
          std::min(std::sqrt(chi2_ * std::max(d.dot(c_near * d), 0.0)), options_.max_half_size);
      out_far =
          std::min(std::sqrt(chi2_ * std::max(d.dot(c_far * d), 0.0)), options_.max_half_size);
      // Along d from e0 (the near end at 0, the far end at length): the union of the ellipses'
      // spans [-out_near, out_near] and [length - out_far, length + out_far].
      const double lo = std::min(-out_near, length - out_far);
      const double hi = std::max(out_near, length + out_far);
      e1 = e0 + hi * d;
      e0 += lo * d;
      p.segment_start = e0.cast<float>();
      p.segment_end = e1.cast<float>();
    }
    r = std::clamp(std::sqrt(chi2_ * std::max(across, 0.0)), options_.min_half_size,
                   options_.max_half_size);
  }
  p.radius = static_cast<float>(r);
  p.min_x = static_cast<float>(std::min(e0.x(), e1.x()) - r);
  p.max_x = static_cast<float>(std::max(e0.x(), e1.x()) + r);
  p.min_y = static_cast<float>(std::min(e0.y(), e1.y()) - r);
  p.max_y = static_cast<float>(std::max(e0.y(), e1.y()) + r);
  // The patch's rotation at the far end: the IMU's rotation alone for distant points, and
  // the near end (0.1 m by default) would warp most patches by a parallax they do not have.
  SetOrientation(rx + rho_lo * t_, p);
  const double s_near = range_a / q_near.norm(), s_far = range_a / q_far.norm();
  p.scale_min = static_cast<float>(std::min(s_near, s_far));
  p.scale_max = static_cast<float>(std::max(s_near, s_far));
  return p;
}

float ReferenceKeypointSize(const std::vector<KeypointInfo>& keypoints) {
  float ref = std::numeric_limits<float>::infinity();
  for (const KeypointInfo& k : keypoints) {
    if (k.size > 0.0f && k.size < ref) ref = k.size;
  }
  return std::isfinite(ref) ? ref : 0.0f;
}

double KeypointSigmaScale(const PredictionOptions& options, const KeypointInfo& keypoint,
                          float reference_size) {
  switch (options.sigma_scaling) {
    case KeypointSigmaScaling::kNone:
      return 1.0;
    case KeypointSigmaScaling::kSize:
      return SizeSigmaFactor(keypoint.size, reference_size, options.keypoint_sigma_px);
    case KeypointSigmaScaling::kOctave:
      return std::pow(options.octave_scale, static_cast<int8_t>(keypoint.octave & 0xFF));
  }
  return 1.0;
}

double SizeSigmaFactor(float size, float reference_size, double base_sigma_px) {
  if (!(size > 0.0f && reference_size > 0.0f && base_sigma_px > 0.0)) return 1.0;
  // The detector's grid at scale s has a step of s px: rounding to it adds a uniform error of
  // variance s^2 / 12 per axis to the base sigma (s = 1 adds nothing by definition).
  const double s = std::max(1.0, static_cast<double>(size) / reference_size);
  return std::sqrt(1.0 + (s * s - 1.0) / (12.0 * base_sigma_px * base_sigma_px));
}

void ToIdealKeypointInfos(const std::vector<cv::KeyPoint>& keypoints,
                          const PixelUndistorter& undistorter, std::vector<KeypointInfo>* out) {
  out->resize(keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    (*out)[i] = KeypointInfo{k.pt.x, k.pt.y, k.angle, k.size, k.octave};
  }
  // The positions mapped in place, as the x, y members of the records.
  static_assert(offsetof(KeypointInfo, y) == offsetof(KeypointInfo, x) + sizeof(float) &&
                sizeof(KeypointInfo) % sizeof(float) == 0);
  if (!out->empty()) {
    undistorter.ToIdealInPlace(&out->front().x, static_cast<int>(out->size()),
                               static_cast<int>(sizeof(KeypointInfo) / sizeof(float)));
  }
  const PinholeCamera& camera = undistorter.camera();
  if (!camera.WiderThanField()) return;
  // A fisheye wider than the field of view: keypoints beyond it have no ideal position (NaN: no
  // prediction, never in a window).
  for (size_t i = 0; i < keypoints.size(); ++i) {
    if (camera.InField(Eigen::Vector2d(keypoints[i].pt.x, keypoints[i].pt.y))) continue;
    (*out)[i].x = (*out)[i].y = std::numeric_limits<float>::quiet_NaN();
  }
}

std::vector<KeypointInfo> ToIdealKeypointInfos(const std::vector<cv::KeyPoint>& keypoints,
                                               const PixelUndistorter& undistorter) {
  std::vector<KeypointInfo> out;
  ToIdealKeypointInfos(keypoints, undistorter, &out);
  return out;
}

void PredictKeypoints(const KeypointPredictor& predictor,
                      const std::vector<KeypointInfo>& keypoints,
                      const std::vector<float>& depths_m, std::vector<KeypointPrediction>* out) {
  PredictKeypointsInRanges(predictor, keypoints, depths_m, {}, out);
}

int PredictKeypointsInRanges(const KeypointPredictor& predictor,
                             const std::vector<KeypointInfo>& keypoints,
                             const std::vector<float>& depths_m,
                             const std::vector<InverseDepthRange>& ranges,
                             std::vector<KeypointPrediction>* predictions) {
  IMUMATCH_CHECK(predictions != nullptr, "PredictKeypointsInRanges needs predictions");
  const size_t n = keypoints.size();
  IMUMATCH_CHECK(depths_m.empty() || depths_m.size() == n,
                 depths_m.size() << " depths for " << n << " keypoints");
  IMUMATCH_CHECK(ranges.empty() || ranges.size() == n,
                 ranges.size() << " inverse-depth ranges for " << n << " keypoints");
  predictions->resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float reference = ReferenceKeypointSize(keypoints);
  const PredictionOptions& po = predictor.options();
  int in_range = 0;
  for (size_t i = 0; i < n; ++i) {
    const KeypointInfo& k = keypoints[i];
    const Eigen::Vector2d uv(k.x, k.y);
    const float depth = depths_m.empty() ? nan : depths_m[i];
    const double sigma_scale = KeypointSigmaScale(po, k, reference);
    KeypointPrediction& p = (*predictions)[i];
    if (!ranges.empty() && ranges[i].valid() && po.predict_without_depth &&
        !po.IsUsableDepth(depth)) {
      p = predictor.PredictInInverseDepthRange(uv, ranges[i].rho_far, ranges[i].rho_near,
                                               sigma_scale);
      if (p.status == PredictionStatus::kWithoutDepth) {
        ++in_range;
        continue;
      }
    }
    p = predictor.Predict(uv, depth, sigma_scale);
  }
  return in_range;
}

std::vector<KeypointPrediction> PredictKeypoints(const PinholeCamera& camera,
                                                 const CameraMotion& motion,
                                                 const std::vector<KeypointInfo>& keypoints,
                                                 const std::vector<float>& depths_m,
                                                 const PredictionOptions& options) {
  std::vector<KeypointPrediction> out;
  PredictKeypoints(KeypointPredictor(camera, motion, options), keypoints, depths_m, &out);
  return out;
}

std::vector<KeypointPrediction> PredictKeypoints(const PixelUndistorter& undistorter,
                                                 const CameraMotion& motion,
                                                 const std::vector<KeypointInfo>& keypoints,
                                                 const std::vector<float>& depths_m,
                                                 const PredictionOptions& options) {
  std::vector<KeypointPrediction> out;
  PredictKeypoints(KeypointPredictor(undistorter, motion, options), keypoints, depths_m, &out);
  return out;
}

}  // namespace imumatch
