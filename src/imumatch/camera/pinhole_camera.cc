#include "imumatch/camera/pinhole_camera.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include <Eigen/LU>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"

namespace imumatch {

const char* ToString(DistortionModel model) {
  return model == DistortionModel::kEquidistant ? "equidistant" : "radial-tangential";
}

std::optional<DistortionModel> DistortionModelFromName(const std::string& name) {
  if (name == "radial-tangential" || name == "radtan" || name == "plumb_bob") {
    return DistortionModel::kRadialTangential;
  }
  if (name == "equidistant" || name == "equi" || name == "fisheye") {
    return DistortionModel::kEquidistant;
  }
  return std::nullopt;
}

namespace {

// The equidistant (Kannala-Brandt) radius on the z=1 plane at ray angle theta, and its derivative.
double KbRadius(const std::array<double, 5>& k, double theta, double* derivative) {
  const double t2 = theta * theta;
  const double poly = 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
  if (derivative != nullptr) {
    // d/dtheta [theta poly(t2)] = poly + theta * 2 theta poly'(t2).
    const double dpoly = k[0] + t2 * (2.0 * k[1] + t2 * (3.0 * k[2] + t2 * 4.0 * k[3]));
    *derivative = poly + 2.0 * t2 * dpoly;
  }
  return theta * poly;
}

// The ray angle in [0, pi/2) whose equidistant radius is `radius` (Newton from theta = radius,
// kept inside the bracket), or NaN when there is none below pi/2 (or the map is not increasing
// on the way).
double KbAngle(const std::array<double, 5>& k, double radius) {
  if (!(radius >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  // Within the field of view the map increases (PinholeCamera::Check); beyond it, up to 90 deg,
  // it may not, and a root there is only one of the rays that share the point.
  const double field = PinholeCamera::kMaxFieldAngleDeg * kPi / 180.0;
  const bool in_field = radius <= KbRadius(k, field, nullptr);
  double lo = in_field ? 0.0 : field, hi = in_field ? field : 0.5 * kPi;
  if (!in_field && !(KbRadius(k, hi, nullptr) > radius)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double theta = std::clamp(radius, lo, 0.5 * (lo + hi));
  for (int it = 0; it < 60; ++it) {
    double slope = 0.0;
    const double f = KbRadius(k, theta, &slope) - radius;
    (f > 0.0 ? hi : lo) = theta;
    if (std::abs(f) <= 1e-15 * std::max(1.0, radius)) break;
    double next = slope > 0.0 ? theta - f / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // a Newton step out of the bracket
    if (next == theta) break;
    theta = next;
  }
  return theta;
}

}  // namespace

double PinholeCamera::EquidistantRadius(double theta, double* derivative) const {
  return KbRadius(distortion, theta, derivative);
}
double PinholeCamera::EquidistantAngle(double radius) const { return KbAngle(distortion, radius); }

void PinholeCamera::Check() const {
  IMUMATCH_CHECK(
      width > 0 && height > 0 && width <= kMaxSide && height <= kMaxSide,
      "image size " << width << "x" << height << " must be 1.." << kMaxSide << " pixels a side");
  IMUMATCH_CHECK(std::isfinite(fx) && fx > 0 && std::isfinite(fy) && fy > 0,
                 "focal lengths fx=" << fx << " fy=" << fy << " must be finite and positive");
  IMUMATCH_CHECK(std::isfinite(cx) && std::isfinite(cy),
                 "principal point cx=" << cx << " cy=" << cy << " is not finite");
  IMUMATCH_CHECK(
      std::isfinite(depth_scale) && depth_scale > 0,
      "depth_scale=" << depth_scale << " must be finite and positive (raw depth units per metre)");
  for (size_t i = 0; i < distortion.size(); ++i) {
    IMUMATCH_CHECK(std::isfinite(distortion[i]),
                   "distortion coefficient " << i + 1 << " of 5 is " << distortion[i]);
  }
  IMUMATCH_CHECK(
      model == DistortionModel::kRadialTangential || model == DistortionModel::kEquidistant,
      "unknown distortion model " << static_cast<int>(model));
  if (model != DistortionModel::kEquidistant) return;
  IMUMATCH_CHECK(distortion[4] == 0.0,
                 "an equidistant lens has four coefficients k1..k4 (the fifth must be 0)");
  // The farthest image point from the axis is a corner (the squared normalised radius is convex).
  double corner = 0.0;
  for (const double u : {-0.5, width - 0.5}) {
    for (const double v : {-0.5, height - 0.5}) {
      corner = std::max(corner, std::hypot((u - cx) / fx, (v - cy) / fy));
    }
  }
  const double max_theta = kMaxFieldAngleDeg * kPi / 180.0;
  // theta (1 + ...) must increase from 0 to the corner's angle (else two rays share an image
  // point), checked every 0.5 deg; beyond the field of view the image is not used.
  for (double theta = 0.0; theta <= max_theta + 1e-12; theta += 0.5 * kPi / 180.0) {
    double slope = 0.0;
    const double radius = KbRadius(distortion, std::min(theta, max_theta), &slope);
    if (!(slope > 0.0)) {
      std::ostringstream m;
      m << "equidistant lens k=[" << distortion[0] << " " << distortion[1] << " " << distortion[2]
        << " " << distortion[3] << "]: the image radius stops growing at " << theta * 180.0 / kPi
        << " deg from the optical axis, before the image corners and the field of view's edge ("
        << kMaxFieldAngleDeg << " deg): two rays would share a pixel";
      throw InvalidArgument(m.str());
    }
    if (radius >= corner) return;
  }
}

namespace {
// The radius on the normalised image plane at the field's edge (kMaxFieldAngleDeg).
double FieldRadius(const PinholeCamera& c) {
  return KbRadius(c.distortion, PinholeCamera::kMaxFieldAngleDeg * kPi / 180.0, nullptr);
}
}  // namespace

bool PinholeCamera::WiderThanField() const {
  if (model != DistortionModel::kEquidistant) return false;
  const double field = FieldRadius(*this);
  for (const double u : {-0.5, width - 0.5}) {
    for (const double v : {-0.5, height - 0.5}) {
      if (std::hypot((u - cx) / fx, (v - cy) / fy) > field) return true;
    }
  }
  return false;
}

bool PinholeCamera::InField(const Eigen::Vector2d& uv) const {
  if (model != DistortionModel::kEquidistant) return true;
  return IdealToNormalized(uv).norm() <= FieldRadius(*this);
}

bool PinholeCamera::HasDistortion() const {
  if (model == DistortionModel::kEquidistant) return true;
  for (double d : distortion) {
    if (d != 0.0) return true;
  }
  return false;
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

Eigen::Vector2d PinholeCamera::DistortNormalized(const Eigen::Vector2d& xy,
                                                 Eigen::Matrix2d* jacobian) const {
  if (model == DistortionModel::kEquidistant) {
    // xy_d = s(r) xy with r = |xy|, s = radius(atan r) / r; J = s I + (s'(r) / r) xy xy^T.
    const double r2 = xy.squaredNorm();
    if (r2 < 1e-24) {  // on the axis: s -> 1, s' -> 0
      if (jacobian != nullptr) jacobian->setIdentity();
      return xy;
    }
    const double r = std::sqrt(r2), theta = std::atan(r);
    double dradius_dtheta = 0.0;
    const double radius = KbRadius(distortion, theta, &dradius_dtheta);
    const double s = radius / r;
    if (jacobian != nullptr) {
      const double dradius_dr = dradius_dtheta / (1.0 + r2);
      const double ds_dr_over_r = (dradius_dr - s) / r2;  // (r radius' - radius) / r^3
      *jacobian = s * Eigen::Matrix2d::Identity() + ds_dr_over_r * xy * xy.transpose();
    }
    return s * xy;
  }
  const auto& [k1, k2, p1, p2, k3] = distortion;
  const RadTan e = EvalRadTan(k1, k2, p1, p2, k3, xy.x(), xy.y());
  if (jacobian != nullptr) *jacobian << e.j00, e.j01, e.j01, e.j11;
  return Eigen::Vector2d(e.dx, e.dy);
}

Eigen::Vector2d PinholeCamera::NormalizedToPixel(const Eigen::Vector2d& xy) const {
  if (!HasDistortion()) return NormalizedToIdeal(xy);
  return NormalizedToIdeal(DistortNormalized(xy));
}

Eigen::Vector2d PinholeCamera::PixelToNormalized(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d distorted = IdealToNormalized(uv);
  if (!HasDistortion()) return distorted;
  if (model == DistortionModel::kEquidistant) {
    // Radial: the ray angle of the distorted radius, then r = tan(theta) along the same direction.
    const double radius = distorted.norm();
    if (radius < 1e-12) return distorted;
    const double theta = KbAngle(distortion, radius);
    return distorted * (std::tan(theta) / radius);  // NaN beyond 90 deg
  }
  // Newton on the distortion model with its analytic Jacobian; converges in a few steps for points
  // inside the image (the model is monotonic there).
  Eigen::Vector2d xy = distorted;
  for (int it = 0; it < 20; ++it) {
    Eigen::Matrix2d j;
    const Eigen::Vector2d r = DistortNormalized(xy, &j) - distorted;
    if (!(r.squaredNorm() >= 1e-28)) break;  // converged (or NaN)
    xy -= j.inverse() * r;
  }
  return xy;
}

Eigen::Matrix2d PinholeCamera::IdealFromPixelJacobian(const Eigen::Vector2d& ideal) const {
  if (!HasDistortion()) return Eigen::Matrix2d::Identity();
  Eigen::Matrix2d j;
  DistortNormalized(IdealToNormalized(ideal), &j);
  // ideal = K xy, pixel = K d(xy): d ideal / d pixel = K J^-1 K^-1.
  const Eigen::Matrix2d k = Eigen::Vector2d(fx, fy).asDiagonal();
  const Eigen::Matrix2d k_inv = Eigen::Vector2d(1.0 / fx, 1.0 / fy).asDiagonal();
  return k * j.inverse() * k_inv;
}

std::optional<Eigen::Vector2d> PinholeCamera::Project(const Eigen::Vector3d& p_in_cam) const {
  if (!(p_in_cam.z() > 0.0)) return std::nullopt;
  return NormalizedToPixel(p_in_cam.head<2>() / p_in_cam.z());
}

Eigen::Vector3d PinholeCamera::Unproject(const Eigen::Vector2d& uv, double depth_m) const {
  const Eigen::Vector2d xy = PixelToNormalized(uv);
  return Eigen::Vector3d(xy.x() * depth_m, xy.y() * depth_m, depth_m);
}

double PinholeCamera::DepthFromRaw(uint16_t raw) const {
  if (raw == 0) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(raw) / depth_scale;
}

bool PinholeCamera::IsInside(const Eigen::Vector2d& uv, double margin) const {
  return uv.x() >= -0.5 + margin && uv.y() >= -0.5 + margin && uv.x() < width - 0.5 - margin &&
         uv.y() < height - 0.5 - margin;
}

void PinholeCamera::IdealImageBounds(double step_px, Eigen::Vector2d* min_xy,
                                     Eigen::Vector2d* max_xy) const {
  IMUMATCH_CHECK(std::isfinite(step_px) && step_px > 0.0, "step_px=" << step_px);
  const double w = width - 0.5, h = height - 0.5;
  if (!HasDistortion()) {
    *min_xy = Eigen::Vector2d(-0.5, -0.5);
    *max_xy = Eigen::Vector2d(w, h);
    return;
  }
  *min_xy = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  *max_xy = -*min_xy;
  const bool wide = WiderThanField();
  const double field_radius = wide ? FieldRadius(*this) : 0.0;
  const double field_tan = std::tan(kMaxFieldAngleDeg * kPi / 180.0);
  auto extend = [&](double u, double v) {
    Eigen::Vector2d p;
    const Eigen::Vector2d distorted = IdealToNormalized(Eigen::Vector2d(u, v));
    if (wide && distorted.norm() > field_radius) {
      p = NormalizedToIdeal(distorted.normalized() * field_tan);  // the field's edge on this ray
    } else {
      p = PixelToIdeal(Eigen::Vector2d(u, v));
    }
    *min_xy = min_xy->cwiseMin(p);
    *max_xy = max_xy->cwiseMax(p);
  };
  for (double u = -0.5; u < w; u += step_px) {
    extend(u, -0.5);
    extend(u, h);
  }
  for (double v = -0.5; v < h; v += step_px) {
    extend(-0.5, v);
    extend(w, v);
  }
  extend(w, h);
}

PinholeCamera PinholeCamera::KinectDefault() { return PinholeCamera{}; }

PinholeCamera PinholeCamera::EurocCam0() {
  PinholeCamera c;
  c.width = 752;
  c.height = 480;
  c.fx = 458.654;
  c.fy = 457.296;
  c.cx = 367.215;
  c.cy = 248.375;
  c.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0};
  return c;
}

PinholeCamera PinholeCamera::TumViCam0() {
  PinholeCamera c;
  c.width = 512;
  c.height = 512;
  c.fx = 190.97847715128717;
  c.fy = 190.9733070521226;
  c.cx = 254.93170605935475;
  c.cy = 256.8974428996504;
  c.model = DistortionModel::kEquidistant;
  c.distortion = {0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202,
                  0.00020293673591811182, 0.0};
  return c;
}

PinholeCamera PinholeCamera::TumFreiburg1() {
  PinholeCamera c;
  c.fx = 517.3;
  c.fy = 516.5;
  c.cx = 318.6;
  c.cy = 255.3;
  c.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  return c;
}

PinholeCamera PinholeCamera::ScaledToWidth(int new_width) const {
  IMUMATCH_CHECK(new_width >= 1 && width >= 1,
                 "cannot scale a " << width << " px wide camera to " << new_width << " px");
  const double s = static_cast<double>(new_width) / width;
  PinholeCamera c = *this;
  c.width = new_width;
  c.height = static_cast<int>(std::lround(height * s));
  c.fx = fx * s;
  c.fy = fy * s;
  c.cx = (cx + 0.5) * s - 0.5;
  c.cy = (cy + 0.5) * s - 0.5;
  return c;
}

std::string PinholeCamera::ToString() const {
  std::ostringstream out;
  out << width << "x" << height << " fx=" << fx << " fy=" << fy << " cx=" << cx << " cy=" << cy;
  if (HasDistortion()) {
    if (model == DistortionModel::kEquidistant) out << " equidistant";
    out << " d=[" << distortion[0] << " " << distortion[1] << " " << distortion[2] << " "
        << distortion[3];
    if (model != DistortionModel::kEquidistant) out << " " << distortion[4];  // k1..k4 only
    out << "]";
  }
  out << " depth_scale=" << depth_scale;
  return out.str();
}

PinholeCamera ParseCameraFromText(const std::string& text, const std::string& source_name) {
  // A UTF-8 byte-order mark (written by some Windows editors) is skipped.
  std::istringstream in(text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? text.substr(3) : text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream fields(line);
    std::vector<double> v;
    std::string token;
    // An optional first word names the lens model (default radial-tangential).
    DistortionModel model = DistortionModel::kRadialTangential;
    bool first = true;
    while (fields >> token) {
      if (first) {
        if (const std::optional<DistortionModel> named = DistortionModelFromName(token)) {
          model = *named;
          first = false;
          continue;
        }
      }
      first = false;
      char* end = nullptr;
      const double d = std::strtod(token.c_str(), &end);
      if (end != token.c_str() + token.size() || !std::isfinite(d)) {
        throw InputError(source_name, line_no, "'" + token + "' is not a finite number");
      }
      v.push_back(d);
    }
    if (v.empty() && model == DistortionModel::kRadialTangential) continue;
    if (model == DistortionModel::kEquidistant && v.size() != 10) {
      throw InputError(source_name, line_no,
                       "expected 'equidistant fx fy cx cy width height k1 k2 k3 k4', got " +
                           std::to_string(v.size()) + " numbers");
    }
    if (v.size() != 4 && (v.size() < 6 || v.size() > 11)) {
      throw InputError(source_name, line_no,
                       "expected '[radtan|equidistant] fx fy cx cy [width height [k1 k2 p1 p2 "
                       "[k3]]]', got " +
                           std::to_string(v.size()) + " numbers");
    }
    PinholeCamera c;
    c.model = model;
    c.fx = v[0];
    c.fy = v[1];
    c.cx = v[2];
    c.cy = v[3];
    if (v.size() >= 6) {
      if (v[4] != std::floor(v[4]) || v[5] != std::floor(v[5]) || !(v[4] >= 1 && v[5] >= 1) ||
          v[4] > PinholeCamera::kMaxSide || v[5] > PinholeCamera::kMaxSide) {
        throw InputError(source_name, line_no,
                         "width and height must be whole numbers in [1, " +
                             std::to_string(PinholeCamera::kMaxSide) + "]");
      }
      c.width = static_cast<int>(v[4]);
      c.height = static_cast<int>(v[5]);
    }
    for (size_t i = 6; i < v.size(); ++i) c.distortion[i - 6] = v[i];
    try {
      c.Check();
    } catch (const InvalidArgument& e) {
      throw InputError(source_name, line_no, e.what());
    }
    return c;
  }
  throw InputError(source_name, "no intrinsics found (expected a line 'fx fy cx cy')");
}

PinholeCamera ReadCameraFromText(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open camera intrinsics file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParseCameraFromText(buffer.str(), path);
}

}  // namespace imumatch
