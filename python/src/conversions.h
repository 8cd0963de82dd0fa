#pragma once

// NumPy <-> OpenCV / imumatch conversions shared by the binding files.

#include <cstdint>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <opencv2/core.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/types.h"
#include "imumatch/eval/frame_source.h"
#include "imumatch/imu/time_offset.h"
#include "imumatch/matching/match_types.h"
#include "imumatch/matching/predictor.h"

namespace imumatch::python {

namespace py = pybind11;

// A cv::Mat header over a NumPy array (no copy when the array is C-contiguous and of a supported
// dtype: uint8, uint16, int16, int32, float32, float64; 2-D, or 3-D with up to 4 channels). The
// returned holder keeps a (possibly converted) array alive as long as the Mat is used.
struct MatView {
  py::array array;  // owner of the memory the Mat points into
  cv::Mat mat;
};
MatView ArrayToMat(const py::handle& object, const char* what);

// Checks that image_a and image_b (as ArrayToMat gave them) are two 8-bit gray frames of one
// size: InvalidArgument naming the one that is empty, not uint8 gray (H x W), or of another size.
void CheckGrayPair(const MatView& image_a, const MatView& image_b);

// Checks that an image given with a camera (a frame, a depth image) has the camera's size: a
// keypoint's depth is read at its pixel and its patch around it, so another size would give
// silently wrong depths and patches. InvalidArgument naming what and both sizes.
void CheckCameraSize(const cv::Mat& image, const char* what, const PinholeCamera& camera);

// A NumPy array that owns a copy-free reference to the Mat's buffer (the Mat is moved into a
// capsule). An empty Mat gives an empty array of shape (0,) or (0, cols).
py::array MatToArray(cv::Mat mat);

// One IMU sample from Python values: gyro (rad/s) and accel (m/s^2) as any 3 numbers (a list, a
// NumPy array); InvalidArgument naming which when one is not 3 values.
ImuSample ImuSampleFromPython(int64_t t_ns, const py::handle& gyro, const py::handle& accel);

// Keypoints: either a list of cv2.KeyPoint-like objects (pt, size, angle, response, octave,
// class_id) or an N x 2 / N x 7 array with columns x, y, size, angle, response, octave, class_id.
std::vector<cv::KeyPoint> ToKeypoints(const py::handle& object);
py::array_t<double> KeypointsToArray(const std::vector<cv::KeyPoint>& keypoints);

// Per-keypoint predictions in ideal pixels: Python's `Predictions` (bound in bind_matching.cc,
// returned by predict_keypoints, match_guided and track_klt).
struct Predictions {
  std::vector<KeypointPrediction> items;
};

// The `dataset` argument of evaluate() and track(): a SyntheticSequence (exact truth, in memory),
// a Dataset, or a path (LoadDatasetOrPosePair with the simulated IMU's model and seed; with
// check_files_exist false a missing image is a bad frame found when it is read).
// {"measured", "offset_s", "sigma_s", "observations", "inliers", "reason"}: t_imu = t_cam +
// offset_s, as eval and track report it.
py::dict TimeOffsetToDict(const TimeOffsetEstimate& estimate);

EvalSource SourceFromPython(const py::object& dataset, const std::string& imu_model, uint64_t seed,
                            bool check_files_exist = true);

}  // namespace imumatch::python
