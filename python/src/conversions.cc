#include "conversions.h"

#include <string>
#include <utility>
#include <vector>

#include "imumatch/core/error.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/pose_pair.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch::python {

namespace {

// The element types both sides know, as (OpenCV depth, NumPy dtype) pairs: the one table both
// directions read.
std::vector<std::pair<int, py::dtype>> ElementTypes() {
  return {{CV_8U, py::dtype::of<uint8_t>()},  {CV_16U, py::dtype::of<uint16_t>()},
          {CV_16S, py::dtype::of<int16_t>()}, {CV_32S, py::dtype::of<int32_t>()},
          {CV_32F, py::dtype::of<float>()},   {CV_64F, py::dtype::of<double>()}};
}

int DepthOf(const py::dtype& dtype, const char* what) {
  for (const auto& [depth, type] : ElementTypes()) {
    if (dtype.is(type)) return depth;
  }
  throw InvalidArgument(std::string(what) + ": unsupported dtype " +
                        py::str(static_cast<py::object>(dtype)).cast<std::string>() +
                        " (uint8, uint16, int16, int32, float32 or float64)");
}

py::dtype DtypeOf(int depth) {
  for (const auto& [d, type] : ElementTypes()) {
    if (d == depth) return type;
  }
  throw InvalidArgument("matrix of unsupported OpenCV depth " + std::to_string(depth));
}

}  // namespace

MatView ArrayToMat(const py::handle& object, const char* what) {
  MatView view;
  if (object.is_none()) return view;
  py::array in = py::array::ensure(object);
  if (!in) throw InvalidArgument(std::string(what) + ": expected a NumPy array");
  // Contiguous (copies only when the caller's array is strided or not C-ordered).
  view.array = py::array::ensure(in, py::array::c_style);
  const py::array& a = view.array;
  const int depth = DepthOf(a.dtype(), what);
  if (a.size() == 0) return view;
  const bool with_channels = a.ndim() == 3 && a.shape(2) >= 1 && a.shape(2) <= 4;
  if (a.ndim() != 2 && !with_channels) {
    throw InvalidArgument(std::string(what) +
                          ": expected a 2-D array (or H x W x C, C <= 4), got " +
                          std::to_string(a.ndim()) + " dimensions");
  }
  const int channels = with_channels ? static_cast<int>(a.shape(2)) : 1;
  view.mat = cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)),
                     CV_MAKETYPE(depth, channels), const_cast<void*>(a.data()));
  return view;
}

void CheckGrayPair(const MatView& image_a, const MatView& image_b) {
  for (const auto& [view, what] : {std::pair<const MatView&, const char*>{image_a, "image_a"},
                                   std::pair<const MatView&, const char*>{image_b, "image_b"}}) {
    if (view.mat.empty()) throw InvalidArgument(std::string(what) + ": the image is empty");
    if (view.mat.type() != CV_8UC1) {
      throw InvalidArgument(std::string(what) + ": expected a uint8 gray image (H x W)");
    }
  }
  const cv::Mat &a = image_a.mat, &b = image_b.mat;
  if (a.size() != b.size()) {
    throw InvalidArgument("image_a (" + std::to_string(a.cols) + "x" + std::to_string(a.rows) +
                          ") and image_b (" + std::to_string(b.cols) + "x" +
                          std::to_string(b.rows) +
                          ") differ in size: the two frames must have one size");
  }
}

void CheckCameraSize(const cv::Mat& image, const char* what, const PinholeCamera& camera) {
  if (image.cols == camera.width && image.rows == camera.height) return;
  throw InvalidArgument(std::string(what) + " is " + std::to_string(image.cols) + "x" +
                        std::to_string(image.rows) + ", the camera " +
                        std::to_string(camera.width) + "x" + std::to_string(camera.height));
}

py::array MatToArray(cv::Mat mat) {
  const py::dtype dtype = DtypeOf(mat.depth());
  if (mat.empty()) {
    return py::array(dtype, std::vector<py::ssize_t>{0, std::max(0, mat.cols)});
  }
  if (!mat.isContinuous()) mat = mat.clone();
  const py::ssize_t elem = static_cast<py::ssize_t>(mat.elemSize1());
  const int channels = mat.channels();
  std::vector<py::ssize_t> shape{mat.rows, mat.cols};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(mat.step[0]),
                                   static_cast<py::ssize_t>(mat.elemSize())};
  if (channels > 1) {
    shape.push_back(channels);
    strides.push_back(elem);
  }
  auto* owner = new cv::Mat(std::move(mat));
  py::capsule free_when_done(owner, [](void* p) { delete static_cast<cv::Mat*>(p); });
  return py::array(dtype, shape, strides, owner->data, free_when_done);
}

std::vector<cv::KeyPoint> ToKeypoints(const py::handle& object) {
  std::vector<cv::KeyPoint> out;
  if (object.is_none()) return out;
  if (py::isinstance<py::array>(object)) {
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
    if (!a) throw InvalidArgument("keypoints: expected a numeric N x 2 or N x 7 array");
    if (a.size() == 0) return out;
    if (a.ndim() != 2 || (a.shape(1) != 2 && a.shape(1) != 7)) {
      throw InvalidArgument(
          "keypoints: expected an N x 2 (x, y) or N x 7 (x, y, size, angle, response, octave, "
          "class_id) array");
    }
    const auto r = a.unchecked<2>();
    out.reserve(static_cast<size_t>(a.shape(0)));
    for (py::ssize_t i = 0; i < a.shape(0); ++i) {
      cv::KeyPoint kp;
      kp.pt = cv::Point2f(static_cast<float>(r(i, 0)), static_cast<float>(r(i, 1)));
      if (a.shape(1) == 7) {
        kp.size = static_cast<float>(r(i, 2));
        kp.angle = static_cast<float>(r(i, 3));
        kp.response = static_cast<float>(r(i, 4));
        kp.octave = static_cast<int>(r(i, 5));
        kp.class_id = static_cast<int>(r(i, 6));
      } else {
        kp.size = 0.0f;  // no scale
      }
      out.push_back(kp);
    }
    return out;
  }
  if (!py::isinstance<py::sequence>(object)) {
    throw InvalidArgument("keypoints: expected a list of cv2.KeyPoint or an N x 7 array");
  }
  const auto seq = py::reinterpret_borrow<py::sequence>(object);
  out.reserve(seq.size());
  for (const py::handle item : seq) {
    if (!py::hasattr(item, "pt")) {
      throw InvalidArgument("keypoints: list item without .pt (expected cv2.KeyPoint)");
    }
    const auto pt = item.attr("pt").cast<std::pair<float, float>>();
    cv::KeyPoint kp;
    kp.pt = cv::Point2f(pt.first, pt.second);
    kp.size = item.attr("size").cast<float>();
    kp.angle = item.attr("angle").cast<float>();
    kp.response = item.attr("response").cast<float>();
    kp.octave = item.attr("octave").cast<int>();
    kp.class_id = item.attr("class_id").cast<int>();
    out.push_back(kp);
  }
  return out;
}

py::array_t<double> KeypointsToArray(const std::vector<cv::KeyPoint>& keypoints) {
  py::array_t<double> a({static_cast<py::ssize_t>(keypoints.size()), py::ssize_t{7}});
  auto w = a.mutable_unchecked<2>();
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& kp = keypoints[i];
    const auto k = static_cast<py::ssize_t>(i);
    w(k, 0) = kp.pt.x;
    w(k, 1) = kp.pt.y;
    w(k, 2) = kp.size;
    w(k, 3) = kp.angle;
    w(k, 4) = kp.response;
    w(k, 5) = kp.octave;
    w(k, 6) = kp.class_id;
  }
  return a;
}

EvalSource SourceFromPython(const py::object& dataset, const std::string& imu_model, uint64_t seed,
                            bool check_files_exist) {
  if (py::isinstance<SyntheticSequence>(dataset)) {
    return MakeSyntheticSource(dataset.cast<const SyntheticSequence&>(), "");
  }
  if (py::isinstance<Dataset>(dataset)) return MakeDiskSource(dataset.cast<Dataset>());
  DatasetOptions options;
  options.imu_model = imu_model;
  options.imu_seed = seed;
  options.check_files_exist = check_files_exist;
  return MakeDiskSource(LoadDatasetOrPosePair(dataset.cast<std::string>(), options));
}

ImuSample ImuSampleFromPython(int64_t t_ns, const py::handle& gyro, const py::handle& accel) {
  const auto vec3 = [](const py::handle& h, const char* what) {
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(h);
    if (!a || a.size() != 3) throw InvalidArgument(std::string(what) + ": expected 3 values");
    return Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
  };
  ImuSample s;
  s.t_ns = t_ns;
  s.gyro_rad_s = vec3(gyro, "gyro");
  s.accel_m_s2 = vec3(accel, "accel");
  return s;
}

py::dict TimeOffsetToDict(const TimeOffsetEstimate& estimate) {
  py::dict out;
  out["measured"] = estimate.measured;
  // Not measured: no number to read (the grid's value would look exact).
  out["offset_s"] = estimate.measured ? py::object(py::float_(estimate.offset_s)) : py::none();
  out["sigma_s"] = estimate.measured ? py::object(py::float_(estimate.sigma_s)) : py::none();
  out["jackknife_sigma_s"] = estimate.measured && estimate.jackknife_sigma_s > 0.0
                                 ? py::object(py::float_(estimate.jackknife_sigma_s))
                                 : py::none();
  out["observations"] = estimate.observations;
  out["inliers"] = estimate.inliers;
  out["reason"] = estimate.reason;
  return out;
}

}  // namespace imumatch::python
