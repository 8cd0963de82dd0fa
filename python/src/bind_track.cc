// The front end without ground truth (`imumatch track`): a dataset's frames and IMU fed in time
// order, every frame's matches and estimated pose, judged afterwards when the dataset has truth.

#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "conversions.h"
#include "imumatch/core/error.h"
#include "imumatch/eval/frame_source.h"
#include "imumatch/eval/track_run.h"
#include "imumatch/features/feature_factory.h"
#include "imumatch/frontend/front_end.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/pose_pair.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch::python {

namespace py = pybind11;

namespace {

py::dict FrameDict(const TrackFrameRecord& f, const std::vector<double>& thresholds) {
  py::dict d;
  d["frame"] = f.frame;
  d["t_ns"] = f.result.t_ns;
  d["error"] = f.error;
  d["status"] = std::string(ToString(f.result.status));
  d["event"] = f.result.event;
  d["keypoints"] = f.result.keypoints.size();
  d["matches"] = f.result.matches.size();
  d["matches_pass1"] = f.result.matches_pass1.size();
  d["second_pass"] = f.result.second_pass;
  d["pose_from_depth"] = f.result.pose_from_depth;
  d["world_from_cam"] =
      f.result.has_state ? py::cast(f.result.world_from_cam) : py::object(py::none());
  d["velocity_in_world"] = f.result.velocity_in_world;
  d["velocity_sigma"] = f.result.velocity_sigma;
  d["total_ms"] = f.result.total_ms;
  d["judged"] = f.judged;
  py::dict precision;
  for (size_t k = 0; k < thresholds.size() && k < f.final_counts.size(); ++k) {
    const JudgedCounts& c = f.final_counts[k];
    precision[py::float_(thresholds[k])] =
        c.matches > 0 ? py::object(py::float_(static_cast<double>(c.correct) / c.matches))
                      : py::object(py::none());
  }
  d["precision"] = precision;
  d["rpe_translation_m"] = f.rpe_translation_m >= 0.0 ? py::object(py::float_(f.rpe_translation_m))
                                                      : py::object(py::none());
  d["rpe_rotation_deg"] = f.rpe_rotation_deg >= 0.0 ? py::object(py::float_(f.rpe_rotation_deg))
                                                    : py::object(py::none());
  return d;
}

// A FrontEndResult as Python values: matches as an M x 2 int32 array (the previous frame's
// keypoint, this frame's), their refined positions in this frame (M x 2, NaN when not refined).
py::dict ResultDict(const FrontEndResult& r) {
  py::dict d;
  d["t_ns"] = r.t_ns;
  d["status"] = std::string(ToString(r.status));
  d["event"] = r.event;
  d["keypoints"] = KeypointsToArray(r.keypoints);
  py::array_t<int32_t> pairs({static_cast<py::ssize_t>(r.matches.size()), py::ssize_t{2}});
  py::array_t<float> refined({static_cast<py::ssize_t>(r.matches.size()), py::ssize_t{2}});
  auto p = pairs.mutable_unchecked<2>();
  auto q = refined.mutable_unchecked<2>();
  for (size_t i = 0; i < r.matches.size(); ++i) {
    const auto k = static_cast<py::ssize_t>(i);
    p(k, 0) = r.matches[i].query_idx;
    p(k, 1) = r.matches[i].train_idx;
    q(k, 0) = r.matches[i].refined_uv_b.x();
    q(k, 1) = r.matches[i].refined_uv_b.y();
  }
  d["matches"] = pairs;
  d["refined_uv"] = refined;
  d["matches_pass1"] = r.matches_pass1.size();
  d["second_pass"] = r.second_pass;
  d["pose_from_depth"] = r.pose_from_depth;
  d["cam_from_prev"] = r.cam_from_prev;
  d["world_from_cam"] = r.has_state ? py::cast(r.world_from_cam) : py::object(py::none());
  d["velocity_in_world"] = r.velocity_in_world;
  d["velocity_sigma"] = r.velocity_sigma;
  d["total_ms"] = r.total_ms;
  return d;
}

}  // namespace

void BindTrack(py::module_& m) {
  py::class_<FrontEnd>(m, "FrontEnd", R"(The front end one frame at a time, as `track` runs it over
a dataset: feed the IMU samples in time order (add_imu, at least up to each frame's time), then
the frame (process). It initialises gravity and the gyro bias from still_s seconds of still IMU
just before the first frame, else at the log's start (without a still window, and with
learn_gyro_bias, it learns the bias from zero from the rotations its fits measure), predicts each
frame's keypoints from the IMU and the previous frame, matches them (guided, or brute force as the
fallback), fits the motion and keeps the estimated pose.)")
      .def(py::init([](const PinholeCamera& camera, const ImuParams& imu_params,
                       const Rigid3d& cam_from_imu, const std::string& detector, int max_keypoints,
                       bool hybrid, bool second_pass, double still_s, bool learn_gyro_bias) {
             FrontEndOptions o;
             o.learn_gyro_bias = learn_gyro_bias;
             o.features.kind = ParseDetectorKind(detector);
             o.features.max_keypoints = max_keypoints;
             o.hybrid = hybrid;
             o.second_pass = second_pass;
             o.still_s = still_s;
             o.Check();
             return std::make_unique<FrontEnd>(camera, imu_params, cam_from_imu, o);
           }),
           py::arg("camera"), py::arg("imu_params"), py::arg("cam_from_imu"),
           py::arg("detector") = "orb", py::arg("max_keypoints") = 1000, py::arg("hybrid") = false,
           py::arg("second_pass") = true, py::arg("still_s") = 0.5,
           py::arg("learn_gyro_bias") = true,
           "camera: PinholeCamera; imu_params: ImuParams (noise model); cam_from_imu: Rigid3d.")
      .def(
          "add_imu",
          [](FrontEnd& fe, int64_t t_ns, const py::handle& gyro_rad_s,
             const py::handle& accel_m_s2) {
            fe.AddImu(ImuSampleFromPython(t_ns, gyro_rad_s, accel_m_s2));
          },
          py::arg("t_ns"), py::arg("gyro_rad_s"), py::arg("accel_m_s2"),
          "One IMU sample (int64 ns, rad/s, m/s^2), in time order; raises on a NaN, a sample "
          "out of order or a duplicate.")
      .def(
          "process",
          [](FrontEnd& fe, int64_t t_ns, const py::handle& image, const py::handle& depth) {
            FrontEndFrame f;
            f.t_ns = t_ns;
            const MatView image_view = ArrayToMat(image, "image");
            MatView depth_view;
            if (!depth.is_none()) depth_view = ArrayToMat(depth, "depth");
            f.image = image_view.mat;
            f.depth = depth_view.mat;
            FrontEndResult r;
            {
              py::gil_scoped_release release;
              r = fe.Process(f);
            }
            return ResultDict(r);
          },
          py::arg("t_ns"), py::arg("image"), py::arg("depth") = py::none(),
          R"(One frame: t_ns (int64, after the previous frame's), image (uint8 gray or BGR),
depth (uint16 raw, camera.depth_scale units per metre, 0 = none; or None). Returns {"status"
('first', 'guided' or 'brute_force'), "event", "keypoints" (N x 7 as extract_features), "matches"
(M x 2 int32: the previous frame's keypoint, this frame's), "refined_uv" (M x 2, the matches'
sub-pixel positions in this frame, NaN when not refined), "matches_pass1", "second_pass",
"cam_from_prev", "world_from_cam" (None while the IMU initialises), "velocity_in_world",
"velocity_sigma", "total_ms"}. Raises ValueError for an image of another size than the camera's,
an empty image, or a time not after the previous frame's.)")
      .def_property_readonly(
          "notes", [](const FrontEnd& fe) { return fe.notes(); },
          "What the front end noted (initialisation, bias), one line each.")
      .def_property_readonly(
          "gyro_bias", [](const FrontEnd& fe) { return Eigen::Vector3d(fe.gyro_bias()); },
          "The gyro bias in use (rad/s, IMU frame): the still start's, then the learnt one.");

  m.def(
      "track",
      [](const py::object& dataset, const std::string& detector, int max_keypoints, bool hybrid,
         bool second_pass, bool monocular, double still_s, bool learn_gyro_bias,
         bool estimate_time_offset, size_t first_frame, size_t max_frames,
         const std::vector<double>& thresholds_px, const std::string& imu_model, uint64_t seed) {
        // A missing image is a bad frame, as in `imumatch track`.
        const EvalSource source =
            SourceFromPython(dataset, imu_model, seed, /*check_files_exist=*/false);
        TrackRunOptions o;
        o.front_end.features.kind = ParseDetectorKind(detector);
        o.front_end.features.max_keypoints = max_keypoints;
        o.front_end.hybrid = hybrid;
        o.front_end.second_pass = second_pass;
        o.front_end.still_s = still_s;
        o.front_end.learn_gyro_bias = learn_gyro_bias;
        o.front_end.estimate_time_offset = estimate_time_offset;
        o.monocular = monocular;
        o.first_frame = first_frame;
        o.max_frames = max_frames;
        o.thresholds_px = thresholds_px;
        o.Check();
        TrackRunResult result;
        {
          py::gil_scoped_release release;
          result = RunTrack(source, o);
        }
        py::dict out;
        out["dataset"] = result.dataset_name;
        py::list frames;
        for (const TrackFrameRecord& f : result.frames)
          frames.append(FrameDict(f, o.thresholds_px));
        out["frames"] = frames;
        out["notes"] = result.notes;
        out["warnings"] = result.warnings;
        out["time_offset"] =
            result.time_offset ? py::object(TimeOffsetToDict(*result.time_offset)) : py::none();
        out["imu_time_offset_s"] = result.imu_time_offset_s;
        out["fallbacks"] = result.FallbackCount();
        out["has_truth"] = result.has_truth;
        if (result.has_truth && result.rpe.pairs() > 0) {
          py::dict rpe;
          rpe["pairs"] = result.rpe.pairs();
          rpe["rmse_translation_m"] = result.rpe.rmse_translation_m;
          rpe["mean_translation_m"] = result.rpe.mean_translation_m;
          rpe["rmse_rotation_deg"] = result.rpe.rmse_rotation_deg;
          rpe["mean_rotation_deg"] = result.rpe.mean_rotation_deg;
          out["rpe"] = rpe;
        } else {
          out["rpe"] = py::none();
        }
        out["wall_s"] = result.wall_s;
        return out;
      },
      py::arg("dataset"), py::arg("detector") = "orb", py::arg("max_keypoints") = 1000,
      py::arg("hybrid") = false, py::arg("second_pass") = true, py::arg("monocular") = false,
      py::arg("still_s") = 0.5, py::arg("learn_gyro_bias") = true,
      py::arg("estimate_time_offset") = false, py::arg("first_frame") = 0,
      py::arg("max_frames") = 0, py::arg("thresholds_px") = std::vector<double>{1.0, 3.0, 8.0},
      py::arg("imu_model") = "euroc", py::arg("seed") = 42,
      R"(Runs the front end as `imumatch track` does: the dataset (a path, a Dataset or a
SyntheticSequence) fed frame by frame with its IMU, no ground truth given to it; gravity and gyro
bias from still_s seconds of still IMU (before the first frame, else at the log's start); without
them the bias is learnt from the fits (learn_gyro_bias). estimate_time_offset: read the IMU in
the camera's clock, its offset estimated from the fits as the run goes (`--estimate-time-offset`). Returns {"frames": [per frame: status ('first', 'guided' or
'brute_force'), event, matches (final pass), matches_pass1, world_from_cam (Rigid3d, None
while the IMU initialises), velocity, precision per threshold and relative pose error to the
previous frame when the dataset has ground truth], "notes", "warnings", "time_offset" (the
camera's clock offset from the IMU's measured from the fitted rotations, t_imu = t_cam + offset:
measured, offset_s, sigma_s (both None when not measured), observations, inliers, reason; None
with a simulated IMU or when no fit measured a rotation), "imu_time_offset_s" (the offset the
IMU was read at by the end, 0 unless estimate_time_offset),
"fallbacks", "rpe" (RMSE and mean, None without ground truth), "wall_s"}. Raises InputError for a dataset without an IMU.)");
}

}  // namespace imumatch::python
