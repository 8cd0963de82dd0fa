#include "imumatch/camera/pinhole_camera.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include <Eigen/LU>

#include "imumatch/core/error.h"

namespace imumatch {

void PinholeCamera::Check() const {
  IMUMATCH_CHECK(width > 0 && height > 0 && width <= kMaxSide && height <= kMaxSide,
                 "image size " << width << "x" << height << " (1.." << kMaxSide << " a side)");
  IMUMATCH_CHECK(std::isfinite(fx) && fx > 0 && std::isfinite(fy) && fy > 0,
                 "focal lengths fx=" << fx << " fy=" << fy);
  IMUMATCH_CHECK(std::isfinite(cx) && std::isfinite(cy), "principal point");
  IMUMATCH_CHECK(std::isfinite(depth_scale) && depth_scale > 0, "depth_scale=" << depth_scale);
  for (double d : distortion) IMUMATCH_CHECK(std::isfinite(d), "distortion coefficient");
}

bool PinholeCamera::HasDistortion() const {
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
  auto extend = [&](double u, double v) {
    const Eigen::Vector2d p = PixelToIdeal(Eigen::Vector2d(u, v));
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
    out << " d=[" << distortion[0] << " " << distortion[1] << " " << distortion[2] << " "
        << distortion[3] << " " << distortion[4] << "]";
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
    while (fields >> token) {
      char* end = nullptr;
      const double d = std::strtod(token.c_str(), &end);
      if (end != token.c_str() + token.size() || !std::isfinite(d)) {
        throw InputError(source_name, line_no, "'" + token + "' is not a finite number");
      }
      v.push_back(d);
    }
    if (v.empty()) continue;
    if (v.size() != 4 && (v.size() < 6 || v.size() > 11)) {
      throw InputError(source_name, line_no,
                       "expected 'fx fy cx cy [width height [k1 k2 p1 p2 [k3]]]', got " +
                           std::to_string(v.size()) + " numbers");
    }
    PinholeCamera c;
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
