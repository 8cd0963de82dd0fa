// KLT tracking on its own: the IMU-seeded tracker (`eval --methods klt`, the front end's
// `--hybrid` first step) and the unseeded VINS-Fusion-style baseline on OpenCV's pyramidal LK.

#include <limits>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "conversions.h"
#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/error.h"
#include "imumatch/eval/evaluation_options.h"  // VinsKltOptions
#include "imumatch/matching/klt_tracker.h"

namespace imumatch::python {

namespace {

// One row per keypoint of A: the tracked position in B (image pixels; NaN where the track
// failed), the seed, the correlation, and why each track ended as it did.
py::dict TrackDict(const TrackResult& r, size_t n) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  py::array_t<float> uv({static_cast<py::ssize_t>(n), py::ssize_t{2}});
  py::array_t<float> seed({static_cast<py::ssize_t>(n), py::ssize_t{2}});
  py::array_t<bool> tracked(static_cast<py::ssize_t>(n));
  py::array_t<float> correlation(static_cast<py::ssize_t>(n));
  std::fill(uv.mutable_data(), uv.mutable_data() + 2 * n, kNaN);
  std::fill(seed.mutable_data(), seed.mutable_data() + 2 * n, kNaN);
  std::fill(tracked.mutable_data(), tracked.mutable_data() + n, false);
  for (size_t i = 0; i < n; ++i) {
    correlation.mutable_data()[i] =
        i < r.correlation.size() && r.correlation[i] > -2.0f ? r.correlation[i] : kNaN;
  }
  for (const Match& m : r.tracks) {
    const size_t i = static_cast<size_t>(m.query_idx);
    uv.mutable_data()[2 * i] = m.refined_uv_b.x();
    uv.mutable_data()[2 * i + 1] = m.refined_uv_b.y();
    seed.mutable_data()[2 * i] = m.predicted_uv.x();
    seed.mutable_data()[2 * i + 1] = m.predicted_uv.y();
    tracked.mutable_data()[i] = true;
  }
  py::list outcomes;
  for (TrackOutcome o : r.outcomes) outcomes.append(ToString(o));
  py::dict stats;
  stats["queries"] = r.stats.queries;
  stats["tracked"] = r.stats.tracked;
  stats["no_prediction"] = r.stats.no_prediction;
  stats["border"] = r.stats.border;
  stats["texture"] = r.stats.texture;
  stats["no_convergence"] = r.stats.no_convergence;
  stats["forward_backward"] = r.stats.forward_backward;
  stats["low_correlation"] = r.stats.low_correlation;
  stats["outside_window"] = r.stats.outside_window;
  stats["ambiguous"] = r.stats.ambiguous;
  py::dict d;
  d["uv_b"] = uv;
  d["seed_uv_b"] = seed;
  d["tracked"] = tracked;
  d["correlation"] = correlation;
  d["outcomes"] = outcomes;
  d["stats"] = stats;
  return d;
}

}  // namespace

void BindKlt(py::module_& m) {
  py::class_<KltOptions>(m, "KltOptions", "Lucas-Kanade tracking settings (KltOptions).")
      .def(py::init<>(), "The seeded tracker's defaults (15 x 15 patch, levels 0-3).")
      .def_static("vins", &VinsKltOptions,
                  "The unseeded baseline's settings, as VINS-Fusion tracks (21 x 21 patch).")
      .def_readwrite("half_size", &KltOptions::half_size, "Patch of (2 half_size + 1)^2 samples.")
      .def_readwrite("max_level", &KltOptions::max_level, "Coarsest pyramid level.")
      .def_readwrite("max_iterations", &KltOptions::max_iterations, "Per level.")
      .def_readwrite("convergence_px", &KltOptions::convergence_px, "Step that ends a level (px).")
      .def_readwrite("min_texture", &KltOptions::min_texture,
                     "A's patch needs this much gradient in both directions.")
      .def_readwrite("max_forward_backward_px", &KltOptions::max_forward_backward_px,
                     "Tracked back into A, B's patch must land this close to A's keypoint.")
      .def_readwrite("min_correlation", &KltOptions::min_correlation,
                     "Least zero-normalised cross-correlation of the two patches (-1: no check).")
      .def_readwrite("warp_patch", &KltOptions::warp_patch,
                     "Seeded: warp A's patch by the predicted rotation and scale.")
      .def_readwrite("gate_by_window", &KltOptions::gate_by_window,
                     "Seeded: reject a track that leaves its prediction's search region.")
      .def_readwrite("max_segment_seeds", &KltOptions::max_segment_seeds,
                     "Seeded, without depth: seeds compared along the epipolar segment.")
      .def_readwrite("max_segment_starts", &KltOptions::max_segment_starts,
                     "Seeded, without depth: best seeds tracked coarse to fine.")
      .def_readwrite("ambiguity_margin", &KltOptions::ambiguity_margin,
                     "Seeded, several starts: a rival this close in correlation is ambiguous.")
      .def("check", &KltOptions::Check,
           "Raises InvalidArgument (a ValueError) when a value is out of range.");

  m.def(
      "track_klt",
      [](const PinholeCamera& camera, const py::handle& image_a, const py::handle& image_b,
         const py::handle& keypoints_a, const Predictions& predictions, const KltOptions& options) {
        camera.Check();
        options.Check();
        const MatView va = ArrayToMat(image_a, "image_a"), vb = ArrayToMat(image_b, "image_b");
        CheckGrayPair(va, vb);
        const cv::Mat &a = va.mat, &b = vb.mat;
        CheckCameraSize(a, "image_a", camera);
        const std::vector<cv::KeyPoint> kps = ToKeypoints(keypoints_a);
        if (predictions.items.size() != kps.size()) {
          throw InvalidArgument("track_klt: " + std::to_string(predictions.items.size()) +
                                " predictions for " + std::to_string(kps.size()) +
                                " keypoints (one each, from predict_keypoints)");
        }
        TrackResult r;
        {
          py::gil_scoped_release release;
          const PixelUndistorter undistorter(camera);
          const TrackingPyramid pa = TrackingPyramid::Build(a, options.max_level);
          const TrackingPyramid pb = TrackingPyramid::Build(b, options.max_level);
          r = TrackSeeded(pa, pb, kps, predictions.items, undistorter, options);
        }
        return TrackDict(r, kps.size());
      },
      py::arg("camera"), py::arg("image_a"), py::arg("image_b"), py::arg("keypoints_a"),
      py::arg("predictions"), py::arg("options") = KltOptions(),
      R"(The IMU-seeded KLT tracker: each keypoint of A (image pixels) starts where its prediction
(predict_keypoints, or match_guided(...).predictions) puts it in B: with depth at the predicted
position, without at the best-correlating point of its epipolar segment; coarse to fine from the
level its uncertainty needs, A's patch warped by the predicted rotation and scale; forward-backward
and correlation checks, then the search-region gate. Gray uint8 images of the camera's size.
Returns a dict: uv_b (N x 2 image pixels, NaN where not tracked), seed_uv_b, tracked (bool),
correlation, outcomes (one per keypoint: 'tracked', 'border', 'forward_backward', ...), stats.)");

  m.def(
      "track_opencv_lk",
      [](const py::handle& image_a, const py::handle& image_b, const py::handle& keypoints_a,
         const KltOptions& options) {
        options.Check();
        const MatView va = ArrayToMat(image_a, "image_a"), vb = ArrayToMat(image_b, "image_b");
        CheckGrayPair(va, vb);
        const cv::Mat &a = va.mat, &b = vb.mat;
        const std::vector<cv::KeyPoint> kps = ToKeypoints(keypoints_a);
        TrackResult r;
        {
          py::gil_scoped_release release;
          r = TrackOpenCvLk(a, b, kps, options);
        }
        return TrackDict(r, kps.size());
      },
      py::arg("image_a"), py::arg("image_b"), py::arg("keypoints_a"),
      py::arg("options") = VinsKltOptions(),
      R"(The unseeded baseline: OpenCV's pyramidal Lucas-Kanade from each keypoint's own position, as
VINS-Fusion tracks (KltOptions.vins()), with the forward-backward and correlation checks. Returns
the dict of track_klt (seed_uv_b NaN).)");
}

}  // namespace imumatch::python
