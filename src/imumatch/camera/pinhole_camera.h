#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>

namespace imumatch {

// The radial-tangential model evaluated at a point (x, y) of the z=1 plane: the distorted point
// (dx, dy) and the entries of its Jacobian d(dx, dy) / d(x, y) (j01 = j10). The one place the
// model is written: PinholeCamera::DistortNormalized and PixelUndistorter's vectorised loop both
// call it (always inlined, with the coefficients as scalars, so that unused entries cost nothing
// and the vectorised loop keeps them in registers).
struct RadTan {
  double dx, dy, j00, j01, j11;
};
[[gnu::always_inline]] inline RadTan EvalRadTan(double k1, double k2, double p1, double p2,
                                                double k3, double x, double y) {
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  // d radial / d r2, and d r2 / dx = 2x, d r2 / dy = 2y.
  const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
  RadTan e;
  e.dx = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  e.dy = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  e.j00 = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
  e.j01 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
  e.j11 = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
  return e;
}

// The lens models: radial-tangential (OpenCV "plumb bob", Kalibr "radtan": k1 k2 p1 p2 k3 on the
// z=1 plane) and equidistant (Kannala-Brandt KB4, Kalibr "equidistant", OpenCV cv::fisheye: the
// angle theta of a ray from the axis maps to the radius theta (1 + k1 theta^2 + k2 theta^4 +
// k3 theta^6 + k4 theta^8) on the normalised image plane).
enum class DistortionModel { kRadialTangential, kEquidistant };
const char* ToString(DistortionModel model);
// The model a name stands for, by the names calibration tools write: "radial-tangential",
// "radtan" (Kalibr), "plumb_bob" (ROS / OpenCV); "equidistant", "equi" (Kalibr), "fisheye"
// (OpenCV cv::fisheye). nullopt for any other name. Every reader of a lens model (EuRoC / Kalibr
// sensor.yaml, text intrinsics, sequence.json, Python) accepts these and only these.
std::optional<DistortionModel> DistortionModelFromName(const std::string& name);
// For messages: the accepted names.
constexpr const char* kDistortionModelNames =
    "radial-tangential, radtan, plumb_bob, equidistant, equi, fisheye";

// Pinhole camera with optional lens distortion and a depth scale for 16-bit depth images.
//
// Pixel-centre convention (the OpenCV one): integer pixel coordinates are pixel centres. Pixel
// (0,0) covers [-0.5, 0.5) x [-0.5, 0.5); the image spans [-0.5, width-0.5) x [-0.5, height-0.5).
// u grows to the right (columns), v downwards (rows). Camera frame: x right, y down, z forward.
struct PinholeCamera {
  int width = 640;
  int height = 480;
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;
  // Radial-tangential: k1, k2, p1, p2, k3; all zero means no distortion. Equidistant: k1, k2, k3,
  // k4 and a fifth entry that must be 0; an equidistant lens always distorts (theta is not
  // tan theta), also with all coefficients zero.
  DistortionModel model = DistortionModel::kRadialTangential;
  std::array<double, 5> distortion = {0, 0, 0, 0, 0};
  // The matcher's field of view: rays up to this angle (degrees) from the optical axis. The
  // matcher works in "ideal" pixels (a pinhole image, straight epipolar lines), which reach
  // infinity at 90 deg; at 80 deg they are 5.7 focal lengths from the centre. An equidistant lens
  // whose image reaches further (a fisheye such as TUM-VI's or a T265's, 180 deg and more across
  // the diagonal) is accepted: the part of its image beyond the field (FieldMask in features,
  // InField here) is left out of detection and matching, as such images' dark corners usually are.
  static constexpr double kMaxFieldAngleDeg = 80.0;
  // Raw depth units per metre: TUM and Kinect PNGs store 5000 per metre (value / 5000 = metres).
  double depth_scale = 5000.0;

  // The largest image side a camera may have (pixels): bounds every per-pixel buffer.
  static constexpr int kMaxSide = 32768;

  // Throws InvalidArgument for a non-positive size, focal length or depth scale, non-finite
  // values, or an equidistant lens whose angle-to-radius map stops increasing before the image
  // corners or kMaxFieldAngleDeg, whichever comes first (two rays would share an image point).
  void Check() const;

  bool HasDistortion() const;
  // True for an equidistant lens whose image corners lie beyond kMaxFieldAngleDeg.
  bool WiderThanField() const;
  // True when pixel uv's ray lies within kMaxFieldAngleDeg of the optical axis: always for a
  // camera not WiderThanField.
  bool InField(const Eigen::Vector2d& uv) const;
  // Same size, intrinsics and lens (model and coefficients): pixels map to the same rays. The
  // depth scale is not compared. For caches of per-camera tables.
  bool SameImageGeometry(const PinholeCamera& other) const {
    return width == other.width && height == other.height && fx == other.fx && fy == other.fy &&
           cx == other.cx && cy == other.cy && model == other.model &&
           distortion == other.distortion;
  }
  Eigen::Matrix3d K() const;

  // Camera point -> pixel. nullopt when z <= 0 (behind or on the camera plane).
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_in_cam) const;
  // Pixel + metric depth (z, along the optical axis) -> camera point. Undistorts first.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& uv, double depth_m) const;
  // Pixel -> bearing on the z=1 plane (undistorted).
  Eigen::Vector2d PixelToNormalized(const Eigen::Vector2d& uv) const;
  // z=1 plane point -> pixel (distorted).
  Eigen::Vector2d NormalizedToPixel(const Eigen::Vector2d& xy) const;
  // The distortion on the z=1 plane, xy -> xy_distorted, and (when jacobian is given) its 2x2
  // Jacobian d xy_distorted / d xy, analytic (symmetric for both models). The identity without
  // distortion. PixelToNormalized inverts it (NaN where an equidistant image point lies 90 deg or
  // more from the axis: no point of the z=1 plane maps there).
  Eigen::Vector2d DistortNormalized(const Eigen::Vector2d& xy,
                                    Eigen::Matrix2d* jacobian = nullptr) const;

  // Equidistant lens: the radius on the normalised image plane of a ray at angle theta from the
  // axis (and its derivative d radius / d theta), and the inverse: the angle in [0, pi/2) of a
  // radius (NaN when no ray below 90 deg lands there).
  double EquidistantRadius(double theta, double* derivative = nullptr) const;
  double EquidistantAngle(double radius) const;

  // "Ideal" pixels: the pinhole image K [x y 1] of the undistorted bearing (x, y). They equal the
  // image pixels for a camera without distortion; in them the epipolar geometry is straight lines.
  Eigen::Vector2d NormalizedToIdeal(const Eigen::Vector2d& xy) const {
    return Eigen::Vector2d(fx * xy.x() + cx, fy * xy.y() + cy);
  }
  Eigen::Vector2d IdealToNormalized(const Eigen::Vector2d& ideal) const {
    return Eigen::Vector2d((ideal.x() - cx) / fx, (ideal.y() - cy) / fy);
  }
  // Ideal pixel -> image pixel (closed form) and image pixel -> ideal pixel (iterative).
  Eigen::Vector2d IdealToPixel(const Eigen::Vector2d& ideal) const {
    return NormalizedToPixel(IdealToNormalized(ideal));
  }
  Eigen::Vector2d PixelToIdeal(const Eigen::Vector2d& uv) const {
    return NormalizedToIdeal(PixelToNormalized(uv));
  }
  // The axis-aligned box in ideal pixels that holds the image [-0.5, w-0.5) x [-0.5, h-0.5): the
  // border mapped to ideal pixels every step_px (a barrel lens reaches further out at the
  // corners than at the edge midpoints), its points beyond the field of view moved in along
  // their ray from the centre to the field's edge. min_xy / max_xy receive the corners.
  void IdealImageBounds(double step_px, Eigen::Vector2d* min_xy, Eigen::Vector2d* max_xy) const;
  // d ideal / d image pixel at the ideal pixel `ideal`: K J^-1 K^-1 with J the distortion's
  // Jacobian. It maps image-pixel noise (keypoint localisation) into ideal pixels.
  Eigen::Matrix2d IdealFromPixelJacobian(const Eigen::Vector2d& ideal) const;

  // Raw 16-bit depth -> metres; 0 (no reading) maps to NaN.
  double DepthFromRaw(uint16_t raw) const;
  // True when uv lies inside the image shrunk by margin pixels on each side.
  bool IsInside(const Eigen::Vector2d& uv, double margin = 0.0) const;

  // EuRoC MAV cam0 (the same calibration in every sequence; mav0/cam0/sensor.yaml): 752x480,
  // fx=458.654 fy=457.296 cx=367.215 cy=248.375, radial-tangential d = -0.28340811 0.07395907
  // 0.00019359 1.76187114e-05.
  static PinholeCamera EurocCam0();
  // The generic Kinect v1 values (fx=fy=525, cx=319.5, cy=239.5) and the TUM fr1 calibration
  // (fx=517.3 fy=516.5 cx=318.6 cy=255.3, d = 0.2624 -0.9531 -0.0054 0.0026 1.1633).
  static PinholeCamera KinectDefault();
  static PinholeCamera TumFreiburg1();
  // TUM-VI cam0 of the 512x512 recordings (Kalibr equidistant: fx=190.978 fy=190.973 cx=254.932
  // cy=256.897, k = 0.0034824 0.00071503 -0.0020532 0.00020294): a fisheye whose image corners lie
  // about 108 deg off-axis, WiderThanField.
  static PinholeCamera TumViCam0();

  // The same camera for an image resized to width x (height * width / this->width), rounded:
  // focal lengths scale by s = new_width / width and the principal point keeps its place under the
  // pixel-centre convention, cx' = (cx + 0.5) s - 0.5. Distortion (on normalised coordinates) and
  // depth scale are unchanged. Throws InvalidArgument for new_width < 1.
  PinholeCamera ScaledToWidth(int new_width) const;

  std::string ToString() const;
};

// Plain text intrinsics: "fx fy cx cy" optionally followed by "width height" and up to five
// distortion coefficients, on one line; '#' starts a comment. Throws InputError(file, line, ...).
PinholeCamera ReadCameraFromText(const std::string& path);
PinholeCamera ParseCameraFromText(const std::string& text, const std::string& source_name);

}  // namespace imumatch
