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

}  // namespace

void BindTrack(py::module_& m) {
  m.def(
      "track",
      [](const py::object& dataset, const std::string& detector, int max_keypoints, bool hybrid,
         bool second_pass, bool monocular, double still_s, size_t first_frame, size_t max_frames,
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
      py::arg("still_s") = 0.5, py::arg("first_frame") = 0, py::arg("max_frames") = 0,
      py::arg("thresholds_px") = std::vector<double>{1.0, 3.0, 8.0}, py::arg("imu_model") = "euroc",
      py::arg("seed") = 42,
      R"(Runs the front end as `imumatch track` does: the dataset (a path, a Dataset or a
SyntheticSequence) fed frame by frame with its IMU, no ground truth given to it; gravity and gyro
bias from the first still_s seconds. Returns {"frames": [per frame: status ('first', 'guided' or
'brute_force'), event, matches (final pass), matches_pass1, world_from_cam (Rigid3d, None
while the IMU initialises), velocity, precision per threshold and relative pose error to the
previous frame when the dataset has ground truth], "notes", "fallbacks", "rpe" (RMSE and mean,
None without ground truth), "wall_s"}. Raises InputError for a dataset without an IMU.)");
}

}  // namespace imumatch::python
