// core (Rigid3d), camera (PinholeCamera), imu (params, buffer, preintegration, still start,
// camera motion).

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "conversions.h"
#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/error.h"
#include "imumatch/core/rigid3.h"
#include "imumatch/imu/camera_motion.h"
#include "imumatch/imu/imu_buffer.h"
#include "imumatch/imu/imu_integrator.h"
#include "imumatch/imu/imu_params.h"
#include "imumatch/io/dataset.h"

namespace imumatch::python {

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Points = py::array_t<double, py::array::c_style | py::array::forcecast>;

// An N x dim array (or one point of shape (dim,)), read through a callback per point; returns
// N x out_dim (or (out_dim,) for a single point).
template <typename Fn>
py::array_t<double> MapPoints(const Points& in, int dim, int out_dim, const char* what, Fn fn) {
  const bool single = in.ndim() == 1;
  if (!((single && in.shape(0) == dim) || (in.ndim() == 2 && in.shape(1) == dim))) {
    throw InvalidArgument(std::string(what) + ": expected an N x " + std::to_string(dim) +
                          " array or one point of " + std::to_string(dim) + " values");
  }
  const py::ssize_t n = single ? 1 : in.shape(0);
  py::array_t<double> out = single ? py::array_t<double>({py::ssize_t{out_dim}})
                                   : py::array_t<double>({n, py::ssize_t{out_dim}});
  const double* src = in.data();
  double* dst = out.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) fn(src + i * dim, dst + i * out_dim, i);
  return out;
}

template <typename V>
void Put(double* out, const V& v) {
  for (int k = 0; k < v.size(); ++k) out[k] = v[k];
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

void BindGeometry(py::module_& m) {
  // ---------------------------------------------------------------------------------- core
  py::class_<Rigid3d>(m, "Rigid3d", R"(A rigid transform b_from_a: p_in_b = R p_in_a + t.

Names say the frames (``world_from_cam``, ``cam_b_from_cam_a``), as in the C++ library.)")
      .def(py::init<>(), "The identity.")
      .def(py::init(
               [](const Eigen::Matrix3d& r, const Eigen::Vector3d& t) { return Rigid3d(r, t); }),
           py::arg("rotation"), py::arg("translation"),
           "From a 3 x 3 rotation matrix and a translation (the rotation is re-orthonormalised).")
      .def_static(
          "from_matrix", [](const Eigen::Matrix4d& mat) { return Rigid3d::FromMatrix(mat); },
          py::arg("matrix"), "From a 4 x 4 homogeneous matrix; raises ValueError if not rigid.")
      .def_static(
          "from_quaternion",
          [](double qw, double qx, double qy, double qz, const Eigen::Vector3d& t) {
            return Rigid3d(Eigen::Quaterniond(qw, qx, qy, qz), t);
          },
          py::arg("qw"), py::arg("qx"), py::arg("qy"), py::arg("qz"), py::arg("translation"),
          "From a unit quaternion (w, x, y, z; normalised) and a translation.")
      .def_property(
          "rotation", [](const Rigid3d& r) { return r.RotationMatrix(); },
          [](Rigid3d& r, const Eigen::Matrix3d& rot) { r = Rigid3d(rot, r.translation); },
          "3 x 3 rotation matrix.")
      .def_property_readonly(
          "quaternion_wxyz",
          [](const Rigid3d& r) {
            return Eigen::Vector4d(r.rotation.w(), r.rotation.x(), r.rotation.y(), r.rotation.z());
          },
          "The rotation as a unit quaternion (w, x, y, z).")
      .def_readwrite("translation", &Rigid3d::translation, "Translation (3 values).")
      .def("matrix", &Rigid3d::ToMatrix, "4 x 4 homogeneous matrix.")
      .def("inverse", &Rigid3d::Inverse, "a_from_b for this b_from_a.")
      .def(
          "__mul__", [](const Rigid3d& a, const Rigid3d& b) { return a * b; },
          "Composition: c_from_b * b_from_a = c_from_a.")
      .def(
          "transform",
          [](const Rigid3d& r, const Points& p) {
            return MapPoints(p, 3, 3, "transform", [&](const double* in, double* out, py::ssize_t) {
              Put(out, r * Eigen::Vector3d(in[0], in[1], in[2]));
            });
          },
          py::arg("points"), "Applies the transform to 3 values or an N x 3 array of points.")
      .def("__repr__", [](const Rigid3d& r) {
        const Eigen::Vector3d& t = r.translation;
        return "Rigid3d(angle_deg=" + std::to_string(RotationAngle(r.rotation) * 180.0 / M_PI) +
               ", translation=[" + std::to_string(t.x()) + ", " + std::to_string(t.y()) + ", " +
               std::to_string(t.z()) + "])";
      });
  m.def(
      "rotation_distance_deg",
      [](const Rigid3d& a, const Rigid3d& b) {
        return RotationDistance(a.rotation, b.rotation) * 180.0 / M_PI;
      },
      py::arg("a"), py::arg("b"), "Angle of the rotation between two poses' rotations (degrees).");

  // -------------------------------------------------------------------------------- camera
  py::class_<PinholeCamera>(m, "PinholeCamera", R"(Pinhole camera with lens distortion.

Pixel-centre convention: integer coordinates are pixel centres (OpenCV's), so the image spans
[-0.5, width - 0.5]. ``distortion`` is OpenCV's (k1, k2, p1, p2, k3), or (k1, k2, k3, k4, 0)
when ``model`` is 'equidistant'. "Ideal" pixels are
K x the undistorted bearing: where the guided matcher predicts and searches.)")
      .def(py::init<>(), "640 x 480, f = 525, c = (319.5, 239.5), no distortion, depth scale 5000.")
      .def(py::init([](int width, int height, double fx, double fy, double cx, double cy,
                       std::array<double, 5> distortion, double depth_scale) {
             PinholeCamera c;
             c.width = width;
             c.height = height;
             c.fx = fx;
             c.fy = fy;
             c.cx = cx;
             c.cy = cy;
             c.distortion = distortion;
             c.depth_scale = depth_scale;
             c.Check();
             return c;
           }),
           py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"), py::arg("cx"),
           py::arg("cy"), py::arg("distortion") = std::array<double, 5>{0, 0, 0, 0, 0},
           py::arg("depth_scale") = 5000.0, "Raises ValueError on invalid values.")
      .def_readwrite("width", &PinholeCamera::width, "Image width (px).")
      .def_readwrite("height", &PinholeCamera::height, "Image height (px).")
      .def_readwrite("fx", &PinholeCamera::fx, "Focal length x (px).")
      .def_readwrite("fy", &PinholeCamera::fy, "Focal length y (px).")
      .def_readwrite("cx", &PinholeCamera::cx, "Principal point x (px, pixel centres at integers).")
      .def_readwrite("cy", &PinholeCamera::cy, "Principal point y (px).")
      .def_readwrite("distortion", &PinholeCamera::distortion,
                     "(k1, k2, p1, p2, k3); equidistant: (k1, k2, k3, k4, 0)")
      .def_property(
          "model", [](const PinholeCamera& c) { return std::string(ToString(c.model)); },
          [](PinholeCamera& c, const std::string& name) {
            const std::optional<DistortionModel> model = DistortionModelFromName(name);
            if (!model) {
              throw InvalidArgument("model must be one of " + std::string(kDistortionModelNames) +
                                    ", not '" + name + "'");
            }
            c.model = *model;
          },
          "Lens model: 'radial-tangential' (default) or 'equidistant' (Kannala-Brandt, "
          "Kalibr's 'equidistant'); set also by the aliases 'radtan', 'plumb_bob', 'equi', "
          "'fisheye'.")
      .def_readwrite("depth_scale", &PinholeCamera::depth_scale,
                     "Raw depth units per metre (TUM: 5000).")
      .def("check", &PinholeCamera::Check, "Raises ValueError on invalid values.")
      .def_property_readonly("K", &PinholeCamera::K, "3 x 3 intrinsic matrix.")
      .def("has_distortion", &PinholeCamera::HasDistortion,
           "Whether the lens distorts (a non-zero coefficient, or the equidistant model).")
      .def_static("euroc_cam0", &PinholeCamera::EurocCam0, "EuRoC MAV cam0 (752 x 480, distorted).")
      .def_static("kinect_default", &PinholeCamera::KinectDefault,
                  "TUM's default Kinect intrinsics (no distortion).")
      .def_static("tum_freiburg1", &PinholeCamera::TumFreiburg1,
                  "TUM fr1 intrinsics with their distortion.")
      .def_static("tum_vi_cam0", &PinholeCamera::TumViCam0,
                  "TUM-VI cam0 of the 512 x 512 recordings: an equidistant fisheye whose corners "
                  "lie beyond the matcher's 80 deg field of view.")
      .def("wider_than_field", &PinholeCamera::WiderThanField,
           "Whether the image reaches beyond the matcher's field of view (80 deg off-axis): then "
           "keypoints are detected and matched only within it (field_of_view_mask).")
      .def(
          "in_field",
          [](const PinholeCamera& c, const Points& p) {
            IMUMATCH_CHECK(p.ndim() == 2 && p.shape(1) == 2, "in_field: expected an N x 2 array");
            py::array_t<bool> out(p.shape(0));
            auto o = out.mutable_unchecked<1>();
            const auto in = p.unchecked<2>();
            for (py::ssize_t i = 0; i < p.shape(0); ++i) {
              o(i) = c.InField(Eigen::Vector2d(in(i, 0), in(i, 1)));
            }
            return out;
          },
          py::arg("uv"),
          "N x 2 pixels -> N booleans: the pixel's ray is within 80 deg of the axis.")
      .def(
          "project",
          [](const PinholeCamera& c, const Points& p) {
            return MapPoints(p, 3, 2, "project", [&](const double* in, double* out, py::ssize_t) {
              const auto uv = c.Project(Eigen::Vector3d(in[0], in[1], in[2]));
              out[0] = uv ? uv->x() : kNaN;
              out[1] = uv ? uv->y() : kNaN;
            });
          },
          py::arg("points_in_cam"),
          "Image pixels (distorted) of points in the camera frame; NaN for points behind it.")
      .def(
          "unproject",
          [](const PinholeCamera& c, const Points& uv, const py::handle& depth) {
            const auto d = Points::ensure(depth);
            if (!d) throw InvalidArgument("unproject: depth must be numeric");
            const py::ssize_t n = uv.ndim() == 1 ? 1 : uv.shape(0);
            if (d.size() != 1 && d.size() != n) {
              throw InvalidArgument("unproject: one depth, or one per point");
            }
            return MapPoints(uv, 2, 3, "unproject",
                             [&](const double* in, double* out, py::ssize_t i) {
                               const double z = d.data()[d.size() == 1 ? 0 : i];
                               Put(out, c.Unproject(Eigen::Vector2d(in[0], in[1]), z));
                             });
          },
          py::arg("uv"), py::arg("depth_m"),
          "Points in the camera frame (z = depth along the optical axis) of image pixels.")
      .def(
          "undistort",
          [](const PinholeCamera& c, const Points& uv) {
            return MapPoints(uv, 2, 2, "undistort",
                             [&](const double* in, double* out, py::ssize_t) {
                               Put(out, c.PixelToIdeal(Eigen::Vector2d(in[0], in[1])));
                             });
          },
          py::arg("uv"), "Image pixels -> ideal (undistorted) pixels.")
      .def(
          "distort",
          [](const PinholeCamera& c, const Points& ideal) {
            return MapPoints(ideal, 2, 2, "distort",
                             [&](const double* in, double* out, py::ssize_t) {
                               Put(out, c.IdealToPixel(Eigen::Vector2d(in[0], in[1])));
                             });
          },
          py::arg("ideal"), "Ideal (undistorted) pixels -> image pixels.")
      .def(
          "pixel_to_normalized",
          [](const PinholeCamera& c, const Points& uv) {
            return MapPoints(uv, 2, 2, "pixel_to_normalized",
                             [&](const double* in, double* out, py::ssize_t) {
                               Put(out, c.PixelToNormalized(Eigen::Vector2d(in[0], in[1])));
                             });
          },
          py::arg("uv"), "Image pixels -> undistorted normalized coordinates (x/z, y/z).")
      .def("__repr__", &PinholeCamera::ToString, "Size, intrinsics, distortion, depth scale.");
  m.def("read_camera", &ReadCameraFile, py::arg("path"),
        "Reads a camera file: a EuRoC camera sensor.yaml or a Kalibr camchain.yaml's cam0 "
        "(*.yaml) or a text line "
        "('[radtan|equidistant] fx fy cx cy [width height [k...]]'); raises InputError naming "
        "the file and line.");

  // ----------------------------------------------------------------------------------- imu
  py::class_<ImuParams>(m, "ImuParams",
                        R"(IMU noise model (Kalibr's names and units) and gravity.)")
      .def(py::init<>(), "The defaults.")
      .def_readwrite("gyro_noise_density", &ImuParams::gyro_noise_density, "rad/s/sqrt(Hz)")
      .def_readwrite("gyro_random_walk", &ImuParams::gyro_random_walk, "rad/s^2/sqrt(Hz)")
      .def_readwrite("accel_noise_density", &ImuParams::accel_noise_density, "m/s^2/sqrt(Hz)")
      .def_readwrite("accel_random_walk", &ImuParams::accel_random_walk, "m/s^3/sqrt(Hz)")
      .def_readwrite("rate_hz", &ImuParams::rate_hz, "Nominal sample rate (Hz).")
      .def_readwrite("gravity_in_world", &ImuParams::gravity_in_world,
                     "Gravity vector in the world frame (m/s^2).")
      .def("check", &ImuParams::Check,
           "Raises InvalidArgument (a ValueError) when a value is out of range.")
      .def_static("euroc_adis16448", &ImuParams::EurocAdis16448)
      .def_static("consumer_mems", &ImuParams::ConsumerMems)
      .def_static("ideal", &ImuParams::Ideal)
      .def_static("from_name", &ImuParams::FromName, py::arg("name"),
                  "'euroc', 'mems' or 'ideal'.");

  py::class_<ImuBias>(m, "ImuBias", "Gyro and accelerometer biases, subtracted from the samples.")
      .def(py::init<>(), "The defaults.")
      .def(py::init([](const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
             ImuBias b;
             b.gyro = gyro;
             b.accel = accel;
             return b;
           }),
           py::arg("gyro"), py::arg("accel"))
      .def_readwrite("gyro", &ImuBias::gyro, "rad/s")
      .def_readwrite("accel", &ImuBias::accel, "m/s^2");

  py::class_<ImuBuffer>(m, "ImuBuffer",
                        R"(Time-ordered IMU samples (int64 nanoseconds, rad/s, m/s^2).

Push rejects unsorted or duplicate timestamps and non-finite values; a query (interpolate, a slice
for preintegration) across a gap longer than max_gap_ns raises OutOfRange.)")
      .def(py::init([](int64_t max_gap_ns) {
             ImuBufferOptions o;
             o.max_gap_ns = max_gap_ns;
             o.Check();
             return ImuBuffer(o);
           }),
           py::arg("max_gap_ns") = ImuBufferOptions().max_gap_ns,
           "An empty buffer; no query may cross a longer stretch without samples.")
      .def(
          "gaps",
          [](const ImuBuffer& b) {
            py::list out;
            for (const ImuBuffer::Gap& g : b.Gaps())
              out.append(py::make_tuple(g.begin_ns, g.end_ns));
            return out;
          },
          "The stretches longer than max_gap_ns without a sample, as (begin_ns, end_ns).")
      .def(
          "push",
          [](ImuBuffer& b, int64_t t_ns, const py::handle& gyro, const py::handle& accel) {
            b.Push(ImuSampleFromPython(t_ns, gyro, accel), "python");
          },
          py::arg("t_ns"), py::arg("gyro"), py::arg("accel"), "Appends one sample.")
      .def_static(
          "from_arrays",
          [](const py::array_t<int64_t, py::array::c_style | py::array::forcecast>& t_ns,
             const Points& gyro, const Points& accel, int64_t max_gap_ns) {
            const py::ssize_t n = t_ns.size();
            if (gyro.ndim() != 2 || gyro.shape(0) != n || gyro.shape(1) != 3 || accel.ndim() != 2 ||
                accel.shape(0) != n || accel.shape(1) != 3) {
              throw InvalidArgument("from_arrays: expected t_ns (N), gyro (N x 3), accel (N x 3)");
            }
            ImuBufferOptions o;
            o.max_gap_ns = max_gap_ns;
            o.Check();
            ImuBuffer b(o);
            for (py::ssize_t i = 0; i < n; ++i) {
              ImuSample s;
              s.t_ns = t_ns.data()[i];
              s.gyro_rad_s = Eigen::Map<const Eigen::Vector3d>(gyro.data() + 3 * i);
              s.accel_m_s2 = Eigen::Map<const Eigen::Vector3d>(accel.data() + 3 * i);
              b.Push(s, "array", static_cast<int>(i + 1));  // "line" = 1-based row
            }
            return b;
          },
          py::arg("t_ns"), py::arg("gyro"), py::arg("accel"),
          py::arg("max_gap_ns") = ImuBufferOptions().max_gap_ns,
          "From arrays; a bad row raises InputError with file 'array' and line = row + 1.")
      .def("__len__", &ImuBuffer::size, "Number of samples.")
      .def_property_readonly("begin_ns", &ImuBuffer::begin_ns,
                             "Time of the first sample (ns); OutOfRange when empty.")
      .def_property_readonly("end_ns", &ImuBuffer::end_ns,
                             "Time of the last sample (ns); OutOfRange when empty.")
      .def_property_readonly(
          "t_ns",
          [](const ImuBuffer& b) {
            py::array_t<int64_t> a(static_cast<py::ssize_t>(b.size()));
            for (size_t i = 0; i < b.size(); ++i) a.mutable_data()[i] = b.samples()[i].t_ns;
            return a;
          },
          "Timestamps (int64 ns).")
      .def_property_readonly(
          "gyro",
          [](const ImuBuffer& b) {
            RowMatrix g(b.size(), 3);
            for (size_t i = 0; i < b.size(); ++i) g.row(i) = b.samples()[i].gyro_rad_s.transpose();
            return g;
          },
          "N x 3 rad/s.")
      .def_property_readonly(
          "accel",
          [](const ImuBuffer& b) {
            RowMatrix g(b.size(), 3);
            for (size_t i = 0; i < b.size(); ++i) g.row(i) = b.samples()[i].accel_m_s2.transpose();
            return g;
          },
          "N x 3 m/s^2.")
      .def(
          "interpolate",
          [](const ImuBuffer& b, int64_t t_ns) {
            const ImuSample s = b.Interpolate(t_ns);
            return py::make_tuple(s.gyro_rad_s, s.accel_m_s2);
          },
          py::arg("t_ns"), "(gyro, accel) linearly interpolated at t_ns; OutOfRange outside.");

  py::class_<ImuPreintegration>(m, "ImuPreintegration",
                                "Preintegrated IMU between two times (Forster et al.).")
      .def_readonly("t0_ns", &ImuPreintegration::t0_ns, "Start time (ns).")
      .def_readonly("t1_ns", &ImuPreintegration::t1_ns, "End time (ns).")
      .def_property_readonly(
          "delta_rotation",
          [](const ImuPreintegration& p) { return p.delta_rotation.toRotationMatrix(); },
          "imu_i_from_imu_j rotation matrix.")
      .def_readonly("delta_velocity", &ImuPreintegration::delta_velocity,
                    "Velocity increment in the start IMU frame, gravity not removed (m/s).")
      .def_readonly("delta_position", &ImuPreintegration::delta_position,
                    "Position increment in the start IMU frame, gravity not removed (m).")
      .def_readonly("covariance", &ImuPreintegration::covariance,
                    "9 x 9 covariance of (rotation, velocity, position).")
      .def_property_readonly("dt", &ImuPreintegration::dt, "seconds");
  m.def(
      "preintegrate",
      [](const ImuBuffer& buffer, int64_t t0_ns, int64_t t1_ns, const ImuBias& bias,
         const ImuParams& params, double bias_sigma_gyro, double bias_sigma_accel) {
        return Preintegrate(buffer.Slice(t0_ns, t1_ns), bias, params, bias_sigma_gyro,
                            bias_sigma_accel);
      },
      py::arg("buffer"), py::arg("t0_ns"), py::arg("t1_ns"), py::arg("bias") = ImuBias(),
      py::arg("params") = ImuParams(), py::arg("bias_sigma_gyro") = 0.0,
      py::arg("bias_sigma_accel") = 0.0,
      "Preintegrates the buffer's samples between t0_ns and t1_ns (interpolated at both ends) on "
      "SO(3), bias subtracted.");

  py::class_<NavState>(m, "NavState", "Pose and velocity of the IMU at a time.")
      .def(py::init<>(), "The defaults.")
      .def_readwrite("t_ns", &NavState::t_ns, "Time (ns).")
      .def_readwrite("world_from_imu", &NavState::world_from_imu, "Pose of the IMU.")
      .def_readwrite("velocity_in_world", &NavState::velocity_in_world, "Velocity (m/s).");
  m.def("propagate", &Propagate, py::arg("state"), py::arg("preintegration"),
        py::arg("gravity_in_world"),
        "The state at t1 from the state at t0 and the preintegration.");

  py::class_<StillInitialization>(
      m, "StillInitialization",
      "What a still period of the IMU tells: gyro bias, gravity direction.")
      .def_readonly("bias", &StillInitialization::bias, "Gyro bias (accel bias zero).")
      .def_readonly("gravity_in_imu", &StillInitialization::gravity_in_imu,
                    "Gravity in the IMU frame (points down).")
      .def_readonly("world_from_imu", &StillInitialization::world_from_imu,
                    "Roll and pitch from gravity, yaw zero.")
      .def_readonly("gyro_bias_sigma", &StillInitialization::gyro_bias_sigma, "rad/s")
      .def_readonly("num_samples", &StillInitialization::num_samples, "Samples used.")
      .def_readonly("end_ns", &StillInitialization::end_ns,
                    "Where the period ended: t1_ns, or the start of an IMU gap before it.");
  m.def("initialize_from_still", &InitializeFromStill, py::arg("buffer"), py::arg("t0_ns"),
        py::arg("t1_ns"), py::arg("params") = ImuParams(), py::arg("max_gyro_drift") = 0.02,
        py::arg("max_accel_drift") = 0.3,
        "Gyro bias and gravity direction from a still period (up to the first gap in the log); "
        "raises InputError if the IMU moved.");

  py::enum_<IntegrationMode>(m, "IntegrationMode")
      .value("PAPER", IntegrationMode::kPaper,
             "Euler angles added, no gravity or bias (the paper).")
      .value("SO3", IntegrationMode::kSo3, "On SO(3), gravity and bias removed (default).");

  py::class_<CameraMotion>(m, "CameraMotion", "Relative motion of the camera between two frames.")
      .def(py::init<>(), "The defaults.")
      .def(py::init([](const Rigid3d& cam_b_from_cam_a, int64_t t_a_ns, int64_t t_b_ns) {
             CameraMotion c;
             c.cam_b_from_cam_a = cam_b_from_cam_a;
             c.t_a_ns = t_a_ns;
             c.t_b_ns = t_b_ns;
             return c;
           }),
           py::arg("cam_b_from_cam_a"), py::arg("t_a_ns") = 0, py::arg("t_b_ns") = 0,
           "An exact motion (zero covariance).")
      .def_readwrite("t_a_ns", &CameraMotion::t_a_ns, "Time of frame A (ns).")
      .def_readwrite("t_b_ns", &CameraMotion::t_b_ns, "Time of frame B (ns).")
      .def_readwrite("cam_b_from_cam_a", &CameraMotion::cam_b_from_cam_a,
                     "Rigid3d mapping points of camera A into camera B.")
      .def_readwrite("covariance", &CameraMotion::covariance,
                     "6 x 6 covariance of (rotation, translation) of cam_b_from_cam_a.");

  py::class_<CameraMotionOptions>(
      m, "CameraMotionOptions",
      "How the IMU is integrated and the uncertainties of the state at frame A.")
      .def(py::init<>(), "The defaults.")
      .def_readwrite("mode", &CameraMotionOptions::mode,
                     "IntegrationMode.SO3 (default) or IntegrationMode.PAPER.")
      .def_readwrite("velocity_sigma", &CameraMotionOptions::velocity_sigma, "m/s at frame A")
      .def_readwrite("attitude_sigma", &CameraMotionOptions::attitude_sigma, "rad at frame A")
      .def_readwrite("gyro_bias_sigma", &CameraMotionOptions::gyro_bias_sigma, "rad/s")
      .def_readwrite("accel_bias_sigma", &CameraMotionOptions::accel_bias_sigma, "m/s^2")
      .def("check", &CameraMotionOptions::Check,
           "Raises InvalidArgument (a ValueError) when a value is out of range.");

  py::class_<ImuStateAtFrame>(m, "ImuStateAtFrame", "The IMU state at frame A.")
      .def(py::init<>(), "The defaults.")
      .def(py::init([](const Rigid3d& world_from_imu, const Eigen::Vector3d& velocity_in_world,
                       const ImuBias& bias) {
             return ImuStateAtFrame{world_from_imu, velocity_in_world, bias};
           }),
           py::arg("world_from_imu"), py::arg("velocity_in_world"), py::arg("bias") = ImuBias())
      .def_readwrite("world_from_imu", &ImuStateAtFrame::world_from_imu,
                     "Pose of the IMU at frame A.")
      .def_readwrite("velocity_in_world", &ImuStateAtFrame::velocity_in_world,
                     "Velocity at frame A (m/s).")
      .def_readwrite("bias", &ImuStateAtFrame::bias, "ImuBias subtracted from the samples.");

  m.def("compute_camera_motion", &ComputeCameraMotion, py::arg("buffer"), py::arg("t_a_ns"),
        py::arg("t_b_ns"), py::arg("state_a"), py::arg("params"), py::arg("cam_from_imu"),
        py::arg("options") = CameraMotionOptions(),
        "The camera's motion between two frame times from the IMU, with its covariance.");
  m.def("camera_motion_from_poses", &CameraMotionFromPoses, py::arg("t_a_ns"),
        py::arg("world_from_cam_a"), py::arg("t_b_ns"), py::arg("world_from_cam_b"),
        "The exact motion between two camera poses (e.g. ground truth).");
}

}  // namespace imumatch::python
