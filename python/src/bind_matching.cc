// features (the detector factory, SURF and BRIEF included), prediction, guided matching with
// sub-pixel refinement, and the brute-force baselines.

#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "conversions.h"
#include "imumatch/camera/pixel_undistorter.h"
#include "imumatch/core/error.h"
#include "imumatch/eval/evaluation.h"  // PadBinaryDescriptors
#include "imumatch/features/feature_factory.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/field_of_view.h"
#include "imumatch/matching/guided_matcher.h"
#include "imumatch/matching/guided_pipeline.h"
#include "imumatch/matching/predictor.h"
#include "imumatch/matching/subpixel_refinement.h"

namespace imumatch::python {

namespace {

// A matcher's output, plus the guided matcher's predictions (empty for the baselines).
struct PyMatchResult {
  MatchResult result;
  Predictions predictions;
  SceneNearDepth scene_near;
  bool guided = false;
  SubpixelStats refine_stats;
};

template <typename T, typename Fn>
py::array_t<T> Column(size_t n, Fn fn) {
  py::array_t<T> a(static_cast<py::ssize_t>(n));
  T* d = a.mutable_data();
  for (size_t i = 0; i < n; ++i) d[i] = fn(i);
  return a;
}

template <typename Fn>
py::array_t<float> Pairs(size_t n, Fn fn) {
  py::array_t<float> a({static_cast<py::ssize_t>(n), py::ssize_t{2}});
  float* d = a.mutable_data();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2f v = fn(i);
    d[2 * i] = v.x();
    d[2 * i + 1] = v.y();
  }
  return a;
}

py::dict StatsDict(const MatchStats& s) {
  py::dict d;
  d["queries"] = s.queries;
  d["predicted_with_depth"] = s.predicted_with_depth;
  d["predicted_without_depth"] = s.predicted_without_depth;
  d["no_prediction"] = s.no_prediction;
  d["behind_camera"] = s.behind_camera;
  d["outside_image"] = s.outside_image;
  d["no_candidate_in_window"] = s.no_candidate_in_window;
  d["orientation"] = s.orientation;
  d["scale"] = s.scale;
  d["distance_threshold"] = s.distance_threshold;
  d["ratio_test"] = s.ratio_test;
  d["mutual"] = s.mutual;
  d["matched"] = s.matched;
  d["points_scanned"] = s.points_scanned;
  d["distances_computed"] = s.distances_computed;
  return d;
}

std::vector<float> DepthsOrNone(const py::handle& depths, size_t n) {
  std::vector<float> out;
  if (depths.is_none()) return out;
  const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(depths);
  if (!a || a.ndim() != 1 || static_cast<size_t>(a.shape(0)) != n) {
    throw InvalidArgument("depths_m: expected one depth (m) per keypoint, " + std::to_string(n));
  }
  out.assign(a.data(), a.data() + n);
  return out;
}

cv::Mat Descriptors(const py::handle& h, const char* what, MatView& keep) {
  keep = ArrayToMat(h, what);
  if (keep.mat.empty()) return cv::Mat();
  if (keep.mat.channels() != 1 || (keep.mat.type() != CV_8U && keep.mat.type() != CV_32F)) {
    throw InvalidArgument(std::string(what) +
                          ": expected an N x D uint8 (binary) or float32 array");
  }
  return PadBinaryDescriptors(keep.mat);
}

BruteForceKernel ParseKernel(const std::string& name) {
  for (BruteForceKernel k :
       {BruteForceKernel::kAuto, BruteForceKernel::kScalar, BruteForceKernel::kPopcnt,
        BruteForceKernel::kAvx2, BruteForceKernel::kAvx512}) {
    if (name == ToString(k)) return k;
  }
  throw InvalidArgument("kernel: '" + name + "' is not auto, scalar, popcnt, avx2 or avx512");
}

}  // namespace

void BindMatching(py::module_& m) {
  m.def(
      "brute_force_kernels",
      [] {
        std::vector<std::string> out;
        for (BruteForceKernel k : AvailableBruteForceKernels()) out.push_back(ToString(k));
        return out;
      },
      "The brute-force paths this CPU runs, fastest last (what 'auto' uses).");
  m.def("cpu_features", &CpuFeaturesString, "The CPU features the fast paths use.");
  // ------------------------------------------------------------------------------ features
  py::class_<FeatureOptions>(m, "FeatureOptions", "Settings of the detector factory.")
      .def(py::init<>(), "The defaults.")
      .def_property(
          "detector", [](const FeatureOptions& o) { return ToString(o.kind); },
          [](FeatureOptions& o, const std::string& name) { o.kind = ParseDetectorKind(name); },
          "'sift', 'surf', 'orb', 'fast' (FAST+BRIEF), 'akaze' or 'brisk'.")
      .def_readwrite("max_keypoints", &FeatureOptions::max_keypoints,
                     "Keypoints kept per image (strongest first).")
      .def_readwrite("sift_contrast_threshold", &FeatureOptions::sift_contrast_threshold,
                     "SIFT contrast threshold.")
      .def_readwrite("sift_edge_threshold", &FeatureOptions::sift_edge_threshold,
                     "SIFT edge threshold.")
      .def_readwrite("orb_scale_factor", &FeatureOptions::orb_scale_factor,
                     "ORB pyramid scale factor.")
      .def_readwrite("orb_n_levels", &FeatureOptions::orb_n_levels, "ORB pyramid levels.")
      .def_readwrite("orb_fast_threshold", &FeatureOptions::orb_fast_threshold,
                     "ORB FAST threshold.")
      .def_readwrite("fast_threshold", &FeatureOptions::fast_threshold,
                     "FAST threshold (FAST+BRIEF).")
      .def_readwrite("akaze_threshold", &FeatureOptions::akaze_threshold,
                     "AKAZE detector response threshold.")
      .def_readwrite("brisk_threshold", &FeatureOptions::brisk_threshold, "BRISK AGAST threshold.")
      .def_readwrite("brisk_octaves", &FeatureOptions::brisk_octaves, "BRISK octaves.")
      .def_readwrite("threads", &FeatureOptions::threads,
                     "ORB: with 2 or more, the pyramid levels are split between two tasks on "
                     "OpenCV's thread pool (levels below the split identical to cv::ORB).")
      .def("check", &FeatureOptions::Check,
           "Raises InvalidArgument (a ValueError) when a value is out of range.");
  m.def(
      "extract_features",
      [](const py::handle& image, const std::string& detector, int max_keypoints,
         const FeatureOptions* options, const py::handle& mask) {
        MatView view = ArrayToMat(image, "image");
        MatView mask_view;
        if (!mask.is_none()) mask_view = ArrayToMat(mask, "mask");
        if (view.mat.empty()) throw InvalidArgument("extract_features: empty image");
        if (view.mat.depth() != CV_8U) {
          throw InvalidArgument("extract_features: expected a uint8 image (gray or BGR)");
        }
        FeatureOptions o = options ? *options : FeatureOptions();
        if (!options) {
          o.kind = ParseDetectorKind(detector);
          o.max_keypoints = max_keypoints;
        }
        Features f;
        {
          py::gil_scoped_release release;
          f = ExtractFeatures(view.mat, o, mask_view.mat);
        }
        return py::make_tuple(KeypointsToArray(f.keypoints), MatToArray(f.descriptors));
      },
      py::arg("image"), py::arg("detector") = "orb", py::arg("max_keypoints") = 1000,
      py::arg("options") = nullptr, py::arg("mask") = py::none(),
      R"(Detects and describes keypoints. Returns (keypoints, descriptors): an N x 7 float64 array
(x, y, size, angle, response, octave, class_id; convert with imumatch.to_cv2_keypoints) and an
N x D array (uint8 for binary descriptors, float32 for SIFT and SURF). ``options`` (a
FeatureOptions) overrides detector and max_keypoints. ``mask``: None, or a uint8 array of the
image's size; keypoints are detected only where it is non-zero (field_of_view_mask(camera) for a
fisheye wider than the matcher's field of view).)");
  m.def(
      "field_of_view_mask",
      [](const PinholeCamera& camera) {
        const cv::Mat mask = FieldOfViewMask(camera);
        return mask.empty() ? py::object(py::none()) : py::object(MatToArray(mask));
      },
      py::arg("camera"),
      "The detection mask of the camera's field of view: a uint8 array (255 within 80 deg of the "
      "optical axis, 0 beyond), or None for a camera whose whole image is in the field.");

  // ---------------------------------------------------------------------------- prediction
  py::enum_<WindowMode>(m, "WindowMode")
      .value("UNCERTAINTY", WindowMode::kUncertainty, "Window from the propagated uncertainty.")
      .value("FIXED", WindowMode::kFixed, "The paper's fixed square (fixed_half_size).");
  py::enum_<KeypointSigmaScaling>(m, "KeypointSigmaScaling")
      .value("NONE", KeypointSigmaScaling::kNone)
      .value("SIZE", KeypointSigmaScaling::kSize)
      .value("OCTAVE", KeypointSigmaScaling::kOctave);
  py::enum_<DepthSampling>(m, "DepthSampling")
      .value("NEAREST", DepthSampling::kNearest)
      .value("MIN3X3", DepthSampling::kMin3x3)
      .value("MEDIAN3X3", DepthSampling::kMedian3x3);
  py::class_<SceneNearDepthOptions>(m, "SceneNearDepthOptions",
                                    R"(The near end of the epipolar segments of keypoints without
depth, from the scene: a pilot of keypoints is matched along the full segments and the segments
then start at near_margin x the near_quantile of the depths its matches need.)")
      .def(py::init<>(), "The defaults.")
      .def_readwrite("enabled", &SceneNearDepthOptions::enabled,
                     "False: the segments start at segment_min_depth.")
      .def_readwrite("pilot_queries", &SceneNearDepthOptions::pilot_queries,
                     "Keypoints of A in the pilot (at most).")
      .def_readwrite("pilot_ratio", &SceneNearDepthOptions::pilot_ratio,
                     "Lowe's ratio of the pilot's matching (at most the matcher's).")
      .def_readwrite("min_samples", &SceneNearDepthOptions::min_samples,
                     "Fewer pilot matches: the configured near end is kept.")
      .def_readwrite("near_quantile", &SceneNearDepthOptions::near_quantile,
                     "Quantile of the pilot's depths from the near side (0: the nearest).")
      .def_readwrite("near_margin", &SceneNearDepthOptions::near_margin,
                     "The segments start at this fraction of that depth.");
  py::class_<PredictionOptions>(m, "PredictionOptions", "How keypoints are predicted into frame B.")
      .def(py::init<>(), "The defaults.")
      .def_readwrite("min_depth", &PredictionOptions::min_depth, "m; nearer depth is invalid")
      .def_readwrite("max_depth", &PredictionOptions::max_depth, "m")
      .def_readwrite("predict_without_depth", &PredictionOptions::predict_without_depth,
                     "Predict along the epipolar segment when a keypoint has no depth.")
      .def_readwrite("segment_min_depth", &PredictionOptions::segment_min_depth,
                     "m: near end of the epipolar segment")
      .def_readwrite("segment_max_depth", &PredictionOptions::segment_max_depth,
                     "m: far end (inf = the point at infinity)")
      .def_readwrite("depth_noise_coeff", &PredictionOptions::depth_noise_coeff,
                     "sigma_z = coeff * z^2 (Kinect)")
      .def_readwrite("keypoint_sigma_px", &PredictionOptions::keypoint_sigma_px,
                     "Keypoint localisation noise at the finest scale (px, 1 sigma).")
      .def_readwrite("sigma_scaling", &PredictionOptions::sigma_scaling,
                     "How the noise grows with keypoint scale (KeypointSigmaScaling).")
      .def_readwrite("window_mode", &PredictionOptions::window_mode,
                     "WindowMode.UNCERTAINTY (default) or WindowMode.FIXED.")
      .def_readwrite("gate_probability", &PredictionOptions::gate_probability,
                     "Chi-square gate probability of the window (0.99 -> 9.21 on 2 dof).")
      .def_readwrite("min_half_size", &PredictionOptions::min_half_size,
                     "Smallest window half size (px).")
      .def_readwrite("max_half_size", &PredictionOptions::max_half_size,
                     "Largest window half size (px).")
      .def_readwrite("fixed_half_size", &PredictionOptions::fixed_half_size,
                     "Half size of the fixed window (px; the paper: 10).")
      .def_readwrite("depth_sampling", &PredictionOptions::depth_sampling,
                     "How depth is read at a keypoint (DepthSampling).")
      .def_readwrite("scene_near", &PredictionOptions::scene_near,
                     "SceneNearDepthOptions: the segments' near end from the scene (match_guided; "
                     "predict_keypoints, which sees no frame B, uses segment_min_depth).")
      .def("check", &PredictionOptions::Check,
           "Raises InvalidArgument (a ValueError) when a value is out of range.");

  py::class_<Predictions>(m, "Predictions", R"(Per-keypoint predictions in frame B, in IDEAL pixels
(undistorted; camera.distort maps them to the image). Arrays, one row per keypoint of A.)")
      .def(
          "__len__", [](const Predictions& p) { return p.items.size(); }, "Number of predictions.")
      .def_property_readonly(
          "status",
          [](const Predictions& p) {
            py::list l;
            for (const auto& k : p.items) l.append(ToString(k.status));
            return l;
          },
          "'with_depth', 'without_depth', 'behind_camera', 'outside_image' or 'invalid'.")
      .def_property_readonly(
          "uv",
          [](const Predictions& p) {
            return Pairs(p.items.size(), [&](size_t i) { return p.items[i].uv; });
          },
          "N x 2 predicted position (the segment's far end without depth).")
      .def_property_readonly(
          "segment_start",
          [](const Predictions& p) {
            return Pairs(p.items.size(), [&](size_t i) { return p.items[i].segment_start; });
          },
          "N x 2 near end of the epipolar segment (= uv with depth).")
      .def_property_readonly(
          "segment_end",
          [](const Predictions& p) {
            return Pairs(p.items.size(), [&](size_t i) { return p.items[i].segment_end; });
          },
          "N x 2 far end of the epipolar segment (= uv with depth).")
      .def_property_readonly(
          "radius",
          [](const Predictions& p) {
            return Column<float>(p.items.size(), [&](size_t i) { return p.items[i].radius; });
          },
          "Capsule radius around the segment (without depth), px.")
      .def_property_readonly(
          "bbox",
          [](const Predictions& p) {
            py::array_t<float> a({static_cast<py::ssize_t>(p.items.size()), py::ssize_t{4}});
            float* d = a.mutable_data();
            for (size_t i = 0; i < p.items.size(); ++i) {
              d[4 * i] = p.items[i].min_x;
              d[4 * i + 1] = p.items[i].min_y;
              d[4 * i + 2] = p.items[i].max_x;
              d[4 * i + 3] = p.items[i].max_y;
            }
            return a;
          },
          "N x 4 search window (min_x, min_y, max_x, max_y).")
      .def_property_readonly(
          "covariance",
          [](const Predictions& p) {
            py::array_t<float> a(
                {static_cast<py::ssize_t>(p.items.size()), py::ssize_t{2}, py::ssize_t{2}});
            float* d = a.mutable_data();
            for (size_t i = 0; i < p.items.size(); ++i) {
              const Eigen::Matrix2f& c = p.items[i].covariance;
              d[4 * i] = c(0, 0);
              d[4 * i + 1] = c(0, 1);
              d[4 * i + 2] = c(1, 0);
              d[4 * i + 3] = c(1, 1);
            }
            return a;
          },
          "N x 2 x 2 position covariance (px^2).")
      .def_property_readonly(
          "angle_change_deg",
          [](const Predictions& p) {
            return Column<float>(p.items.size(),
                                 [&](size_t i) { return p.items[i].angle_change_deg; });
          },
          "Predicted change of a keypoint's image angle (degrees).")
      .def(
          "contains",
          [](const Predictions& p, size_t i, float x, float y) {
            if (i >= p.items.size()) throw OutOfRange("prediction index " + std::to_string(i));
            return p.items[i].Contains(x, y);
          },
          py::arg("index"), py::arg("x"), py::arg("y"),
          "Whether ideal pixel (x, y) lies in prediction index's search region.");

  m.def(
      "predict_keypoints",
      [](const PinholeCamera& camera, const CameraMotion& motion, const py::handle& keypoints,
         const py::handle& depth_image, const py::handle& depths_m,
         const PredictionOptions& options) {
        camera.Check();
        options.Check();
        const std::vector<cv::KeyPoint> kps = ToKeypoints(keypoints);
        std::vector<float> depths = DepthsOrNone(depths_m, kps.size());
        MatView depth = ArrayToMat(depth_image, "depth_image");
        if (!depth.mat.empty()) {
          if (!depths.empty()) throw InvalidArgument("give depth_image or depths_m, not both");
          if (depth.mat.type() != CV_16UC1) {
            throw InvalidArgument("depth_image: expected a uint16 H x W array (raw units)");
          }
          CheckCameraSize(depth.mat, "depth_image", camera);
          depths = SampleDepths(depth.mat, camera.depth_scale, kps, options.depth_sampling);
        }
        const PixelUndistorter undistorter(camera);
        Predictions p;
        p.items = PredictKeypoints(undistorter, motion, ToIdealKeypointInfos(kps, undistorter),
                                   depths, options);
        return p;
      },
      py::arg("camera"), py::arg("motion"), py::arg("keypoints"),
      py::arg("depth_image") = py::none(), py::arg("depths_m") = py::none(),
      py::arg("options") = PredictionOptions(),
      R"(Predicts where keypoints of frame A appear in frame B, with their search regions.
Keypoints in image pixels; depth from a raw uint16 depth image of A (camera.depth_scale units per
metre) or as metres per keypoint (<= 0 or NaN: none). Without depth: the epipolar segment.)");

  // ---------------------------------------------------------------------- matching results
  py::class_<SubpixelOptions>(m, "SubpixelOptions", "Sub-pixel refinement of guided matches.")
      .def(py::init<>(), "The defaults.")
      .def_readwrite("half_size", &SubpixelOptions::half_size,
                     "Patch half size (px): 4 -> 9 x 9 samples.")
      .def_readwrite("max_iterations", &SubpixelOptions::max_iterations,
                     "Gauss-Newton iterations at most.")
      .def_readwrite("convergence_px", &SubpixelOptions::convergence_px,
                     "Stop when a step is below this (px).")
      .def_readwrite("max_shift_px", &SubpixelOptions::max_shift_px,
                     "Largest move from the keypoint (px); farther = not aligned.")
      .def_readwrite("min_texture", &SubpixelOptions::min_texture,
                     "Smallest gradient texture of the patch.")
      .def_readwrite("retry_drifted_larger", &SubpixelOptions::retry_drifted_larger,
                     "Retry a drifting alignment with the patch twice the size.")
      .def_readwrite("retry_min_correlation", &SubpixelOptions::retry_min_correlation,
                     "Smallest ZNCC for the larger patch's retry to count.")
      .def_readwrite("drop_unaligned", &SubpixelOptions::drop_unaligned,
                     "Drop matches that cannot be aligned.")
      .def("check", &SubpixelOptions::Check,
           "Raises InvalidArgument (a ValueError) when a value is out of range.");

  py::class_<PyMatchResult>(m, "MatchResult", R"(Matches of frame A's keypoints (query) to frame B's
(train), as arrays. Guided results also carry the per-query outcome and the predictions.)")
      .def(
          "__len__", [](const PyMatchResult& r) { return r.result.matches.size(); },
          "Number of matches.")
      .def_property_readonly(
          "query_idx",
          [](const PyMatchResult& r) {
            return Column<int32_t>(r.result.matches.size(),
                                   [&](size_t i) { return r.result.matches[i].query_idx; });
          },
          "Index of each match's keypoint in frame A (int32).")
      .def_property_readonly(
          "train_idx",
          [](const PyMatchResult& r) {
            return Column<int32_t>(r.result.matches.size(),
                                   [&](size_t i) { return r.result.matches[i].train_idx; });
          },
          "Index of each match's keypoint in frame B (int32).")
      .def_property_readonly(
          "distance",
          [](const PyMatchResult& r) {
            return Column<float>(r.result.matches.size(),
                                 [&](size_t i) { return r.result.matches[i].distance; });
          },
          "Hamming bits or L2 distance.")
      .def_property_readonly(
          "second_distance",
          [](const PyMatchResult& r) {
            return Column<float>(r.result.matches.size(),
                                 [&](size_t i) { return r.result.matches[i].second_distance; });
          },
          "The runner-up's distance (inf when none).")
      .def_property_readonly(
          "predicted_uv",
          [](const PyMatchResult& r) {
            return Pairs(r.result.matches.size(),
                         [&](size_t i) { return r.result.matches[i].predicted_uv; });
          },
          "N x 2 prediction in ideal pixels (NaN for the baselines).")
      .def_property_readonly(
          "refined_uv_b",
          [](const PyMatchResult& r) {
            return Pairs(r.result.matches.size(),
                         [&](size_t i) { return r.result.matches[i].refined_uv_b; });
          },
          "N x 2 refined position in B, image pixels (NaN when not refined).")
      .def_property_readonly(
          "outcomes",
          [](const PyMatchResult& r) {
            py::list l;
            for (QueryOutcome o : r.result.outcomes) l.append(ToString(o));
            return l;
          },
          "Guided: why each query of A was matched or rejected ('matched', 'ratio_test', ...).")
      .def_property_readonly(
          "stats", [](const PyMatchResult& r) { return StatsDict(r.result.stats); },
          "Guided: counts of the outcomes and work done.")
      .def_property_readonly(
          "predictions",
          [](const PyMatchResult& r) -> py::object {
            if (!r.guided) return py::none();
            return py::cast(r.predictions);
          },
          "Guided: the Predictions of A's keypoints (None for the baselines).")
      .def_property_readonly(
          "segment_near_m",
          [](const PyMatchResult& r) -> py::object {
            if (!r.guided) return py::none();
            return py::float_(r.scene_near.segment_min_depth_m);
          },
          "Guided: where the epipolar segments of keypoints without depth started (m).")
      .def_property_readonly(
          "refine_stats",
          [](const PyMatchResult& r) {
            py::dict d;
            d["refined"] = r.refine_stats.refined;
            d["failed_border"] = r.refine_stats.failed_border;
            d["failed_texture"] = r.refine_stats.failed_texture;
            d["failed_convergence"] = r.refine_stats.failed_convergence;
            d["recovered_larger"] = r.refine_stats.recovered_larger;
            return d;
          },
          "Guided with images: how many matches were refined, and why the others failed.");

  py::class_<GuidedMatcherOptions>(m, "GuidedMatcherOptions", "Checks of the guided matcher.")
      .def(py::init<>(), "The defaults.")
      .def_readwrite("ratio", &GuidedMatcherOptions::ratio,
                     "Lowe's ratio inside the search region (1 disables).")
      .def_readwrite("max_hamming_fraction", &GuidedMatcherOptions::max_hamming_fraction,
                     "Largest Hamming distance as a fraction of the bits.")
      .def_readwrite("max_l2_relative", &GuidedMatcherOptions::max_l2_relative,
                     "Largest L2 distance relative to the descriptors' norm.")
      .def_readwrite("inconsistent_candidates_in_ratio",
                     &GuidedMatcherOptions::inconsistent_candidates_in_ratio,
                     "Candidates failing the orientation/scale checks still count as rivals.")
      .def_readwrite("duplicate_radius_px", &GuidedMatcherOptions::duplicate_radius_px,
                     "Candidates this close to the best are twins, not rivals (px).")
      .def_readwrite("mutual", &GuidedMatcherOptions::mutual, "Keep only mutual best matches.")
      .def_readwrite("check_orientation", &GuidedMatcherOptions::check_orientation,
                     "Reject candidates whose angle change disagrees with the predicted rotation.")
      .def_readwrite("orientation_tolerance_deg", &GuidedMatcherOptions::orientation_tolerance_deg,
                     "Tolerance of the orientation check (degrees).")
      .def_readwrite(
          "check_scale", &GuidedMatcherOptions::check_scale,
          "Reject candidates whose size ratio disagrees with the predicted scale change.")
      .def_readwrite("scale_tolerance_factor", &GuidedMatcherOptions::scale_tolerance_factor,
                     "Tolerance factor of the scale check.")
      .def_readwrite("grid_cell_size", &GuidedMatcherOptions::grid_cell_size,
                     "Cell size of the spatial grid over frame B (px).")
      .def("check", &GuidedMatcherOptions::Check,
           "Raises InvalidArgument (a ValueError) when a value is out of range.");

  m.def(
      "match_guided",
      [](const PinholeCamera& camera, const CameraMotion& motion, const py::handle& keypoints_a,
         const py::handle& descriptors_a, const py::handle& keypoints_b,
         const py::handle& descriptors_b, const py::handle& depth_a, const py::handle& image_a,
         const py::handle& image_b, const PredictionOptions& prediction_options,
         const GuidedMatcherOptions& matcher_options, const SubpixelOptions& subpixel_options) {
        const std::vector<cv::KeyPoint> kps_a = ToKeypoints(keypoints_a);
        const std::vector<cv::KeyPoint> kps_b = ToKeypoints(keypoints_b);
        MatView keep_a, keep_b;
        const cv::Mat da = Descriptors(descriptors_a, "descriptors_a", keep_a);
        const cv::Mat db = Descriptors(descriptors_b, "descriptors_b", keep_b);
        if (static_cast<size_t>(da.rows) != kps_a.size() ||
            static_cast<size_t>(db.rows) != kps_b.size()) {
          throw InvalidArgument(
              "match_guided: one descriptor row per keypoint (A: " + std::to_string(kps_a.size()) +
              " keypoints, " + std::to_string(da.rows) +
              " rows; B: " + std::to_string(kps_b.size()) + ", " + std::to_string(db.rows) + ")");
        }
        MatView depth = ArrayToMat(depth_a, "depth_a");
        if (!depth.mat.empty() && depth.mat.type() != CV_16UC1) {
          throw InvalidArgument("depth_a: expected a uint16 H x W array (raw units)");
        }
        if (!depth.mat.empty()) CheckCameraSize(depth.mat, "depth_a", camera);
        const MatView va = ArrayToMat(image_a, "image_a"), vb = ArrayToMat(image_b, "image_b");
        if (va.mat.empty() != vb.mat.empty()) {
          throw InvalidArgument("match_guided: give both images (for refinement) or neither");
        }
        if (!va.mat.empty()) {
          CheckGrayPair(va, vb);
          CheckCameraSize(va.mat, "image_a", camera);
        }
        const cv::Mat &ia = va.mat, &ib = vb.mat;
        PyMatchResult out;
        out.guided = true;
        {
          py::gil_scoped_release release;
          GuidedMatcherWorkspace workspace;
          out.result = workspace.Match(camera, motion, kps_a, da, depth.mat, kps_b, db,
                                       prediction_options, matcher_options);
          out.predictions.items = workspace.predictions();
          out.scene_near = workspace.scene_near();
          if (!ia.empty()) {
            out.refine_stats = RefineMatches(ia, ib, kps_a, kps_b, out.predictions.items, camera,
                                             subpixel_options, out.result.matches);
          }
        }
        return out;
      },
      py::arg("camera"), py::arg("motion"), py::arg("keypoints_a"), py::arg("descriptors_a"),
      py::arg("keypoints_b"), py::arg("descriptors_b"), py::arg("depth_a") = py::none(),
      py::arg("image_a") = py::none(), py::arg("image_b") = py::none(),
      py::arg("prediction_options") = PredictionOptions(),
      py::arg("matcher_options") = GuidedMatcherOptions(),
      py::arg("subpixel_options") = SubpixelOptions(),
      R"(IMU-guided matching of frame A's keypoints to frame B's: prediction, search windows through
a grid index, ratio test, orientation and scale checks. With both gray images (uint8), matches are
refined to sub-pixel accuracy (refined_uv_b) and unalignable ones dropped.)");

  m.def(
      "match_brute_force",
      [](const py::handle& descriptors_a, const py::handle& descriptors_b, double ratio,
         double max_distance, bool cross_check, const std::string& kernel) {
        MatView keep_a, keep_b;
        const cv::Mat da = Descriptors(descriptors_a, "descriptors_a", keep_a);
        const cv::Mat db = Descriptors(descriptors_b, "descriptors_b", keep_b);
        BruteForceOptions o;
        o.ratio = ratio;
        o.max_distance = max_distance;
        o.cross_check = cross_check;
        o.kernel = ParseKernel(kernel);
        PyMatchResult out;
        py::gil_scoped_release release;
        out.result.matches = MatchBruteForce(da, db, o);
        return out;
      },
      py::arg("descriptors_a"), py::arg("descriptors_b"), py::arg("ratio") = 0.8,
      py::arg("max_distance") = std::numeric_limits<double>::infinity(),
      py::arg("cross_check") = false, py::arg("kernel") = "auto",
      "imumatch's exhaustive matcher (every pair of descriptors), with Lowe's ratio test. kernel: "
      "'auto' (the fastest this CPU runs), 'scalar', 'popcnt', 'avx2' or 'avx512' (same results).");
  m.def(
      "match_opencv_knn_ratio",
      [](const py::handle& descriptors_a, const py::handle& descriptors_b, double ratio) {
        MatView keep_a, keep_b;
        const cv::Mat da = Descriptors(descriptors_a, "descriptors_a", keep_a);
        const cv::Mat db = Descriptors(descriptors_b, "descriptors_b", keep_b);
        PyMatchResult out;
        py::gil_scoped_release release;
        out.result.matches = MatchOpenCvKnnRatio(da, db, ratio);
        return out;
      },
      py::arg("descriptors_a"), py::arg("descriptors_b"), py::arg("ratio") = 0.8,
      "OpenCV's BFMatcher.knnMatch(k=2) with Lowe's ratio test: the brute-force baseline.");
}

}  // namespace imumatch::python
