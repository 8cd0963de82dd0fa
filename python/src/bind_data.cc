// io (datasets in the TUM RGB-D, EuRoC/ASL and synthetic layouts, trajectories), the synthetic
// world, and the evaluation.

#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "conversions.h"
#include "imumatch/core/error.h"
#include "imumatch/eval/evaluation.h"
#include "imumatch/eval/frame_source.h"
#include "imumatch/eval/pair_selection.h"
#include "imumatch/eval/summary.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/euroc_writer.h"
#include "imumatch/io/pose_pair.h"
#include "imumatch/io/synthetic_io.h"
#include "imumatch/io/trajectory_io.h"
#include "imumatch/sim/motions.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch::python {

namespace {

py::dict SummaryRow(const MethodSummary& s, const ThresholdChoice& threshold) {
  py::dict d;
  d["case"] = s.case_name;
  d["detector"] = ToString(s.detector);
  d["method"] = ToString(s.method);
  d["pairs"] = s.pairs;
  d["keypoints"] = s.keypoints;
  d["matches"] = s.matches;
  d["correct"] = s.correct;
  d["false"] = s.wrong;
  d["precision"] = s.precision;
  d["recall"] = s.recall;
  d["possible"] = s.possible;
  d["threshold_px"] = threshold.threshold_px;
  d["extract_ms"] = s.extract_ms.mean;
  d["predict_ms"] = s.predict_ms.mean;
  d["match_ms"] = s.match_ms.mean;
  d["match_ms_p90"] = s.match_ms.p90;
  d["total_ms"] = s.total_ms.mean;
  d["epipolar_fraction"] = s.epipolar_fraction;
  if (s.window_recall >= 0.0) {
    d["window_recall"] = s.window_recall;
  } else {
    d["window_recall"] = py::none();
  }
  return d;
}

std::vector<DetectorKind> Detectors(const std::vector<std::string>& names) {
  std::vector<DetectorKind> out;
  for (const auto& n : names) out.push_back(ParseDetectorKind(n));
  if (out.empty()) throw InvalidArgument("detectors: at least one");
  return out;
}

std::vector<MatchMethod> Methods(const std::vector<std::string>& names) {
  std::vector<MatchMethod> out;
  for (const auto& n : names) out.push_back(ParseMatchMethod(n));
  if (out.empty()) throw InvalidArgument("methods: at least one");
  return out;
}

py::object Evaluate(EvalSource source, const std::vector<std::string>& detectors,
                    const std::vector<std::string>& methods, size_t max_pairs, int step,
                    double interval_s, const std::string& motion_source, int max_keypoints,
                    std::optional<double> threshold_px, bool refine, bool second_pass,
                    bool monocular, uint64_t seed, bool details) {
  EvaluationOptions o;
  o.detectors = Detectors(detectors);
  o.methods = Methods(methods);
  o.features.max_keypoints = max_keypoints;
  o.motion_source = ParseMotionSource(motion_source);
  o.refine_subpixel = refine;
  o.second_pass = second_pass;
  o.monocular = monocular;
  o.seed = seed;
  std::vector<std::string> notes;
  if (o.motion_source == MotionSource::kImu && source.dataset.imu.empty()) {
    notes.push_back("the dataset has no IMU data: using the ground-truth motion");
    o.motion_source = MotionSource::kGroundTruth;
  }
  o.Check();
  PairSelection sel;
  sel.step = step;
  sel.interval_s = interval_s;
  sel.max_pairs = max_pairs;
  sel.Check();
  const std::vector<FramePair> pairs = SelectFramePairs(source.dataset.frames, sel);
  if (pairs.empty()) {
    throw InputError(source.dataset.root, "no frame pair to evaluate (" +
                                              WhyNoFramePairs(source.dataset.frames, sel) + ")");
  }
  EvaluationResult result;
  ThresholdChoice threshold;
  std::vector<MethodSummary> summary;
  {
    py::gil_scoped_release release;
    result = EvaluateSource(source, pairs, o);
    threshold = ChooseThreshold(result, source.exact_ground_truth, threshold_px);
    summary = Summarize(result.records, threshold.threshold_px);
  }
  py::list rows;
  for (const MethodSummary& s : summary) rows.append(SummaryRow(s, threshold));
  if (!details) return std::move(rows);
  for (auto& n : result.notes) notes.push_back(n);
  py::list skipped;
  for (const SkippedPair& s : result.skipped) {
    py::dict d;
    d["pair"] = s.pair_index;
    d["frame_a"] = s.frame_a;
    d["frame_b"] = s.frame_b;
    d["detector"] = s.detector;
    d["reason"] = s.reason;
    skipped.append(d);
  }
  // What each prediction method made of brute force's correct matches, summed over the pairs.
  py::list fates;
  for (const MethodSummary& s : summary) {
    if (!UsesPrediction(s.method) || IsTracking(s.method)) continue;  // no per-query outcomes
    BruteForceFate f;
    for (const DetectorPairRecord& r : result.records) {
      if (r.case_name != s.case_name || r.detector != s.detector) continue;
      for (const MethodRun& run : r.runs) {
        if (run.method == s.method) f.Add(ComputeBruteForceFate(r, run, threshold.threshold_px));
      }
    }
    py::dict d;
    d["case"] = s.case_name;
    d["detector"] = ToString(s.detector);
    d["method"] = ToString(s.method);
    for (const auto& [name, count] : f.Named()) d[name] = count;
    fates.append(d);
  }
  py::dict out;
  out["rows"] = rows;
  out["bf_correct_fate"] = fates;
  out["threshold"] = threshold.description;
  out["threshold_px"] = threshold.threshold_px;
  out["notes"] = notes;
  out["warnings"] = result.warnings;
  py::list offsets;  // per case and detector, with a recorded IMU
  for (const EvaluationResult::TimeOffset& t : result.time_offsets) {
    py::dict d = TimeOffsetToDict(t.estimate);
    d["case"] = t.case_name;
    d["detector"] = ToString(t.detector);
    offsets.append(d);
  }
  out["time_offsets"] = offsets;
  out["skipped"] = skipped;
  out["pairs"] = pairs.size();
  out["wall_s"] = result.wall_s;
  return std::move(out);
}

}  // namespace

void BindData(py::module_& m) {
  // ------------------------------------------------------------------------------------ io
  py::class_<FrameRecord>(m, "FrameRecord", "One camera frame of a dataset.")
      .def_readonly("t_ns", &FrameRecord::t_ns, "Timestamp (ns).")
      .def_readonly("image_path", &FrameRecord::image_path, "Full path of the image.")
      .def_readonly("depth_path", &FrameRecord::depth_path, "'' when the frame has no depth.")
      .def_readonly("world_from_cam", &FrameRecord::world_from_cam, "Ground truth, or None.")
      .def_readonly("imu_velocity_in_world", &FrameRecord::imu_velocity_in_world,
                    "Velocity of the IMU (m/s, world frame) when known, else None.");

  py::class_<Dataset>(m, "Dataset", R"(A sequence: camera, frames, IMU and ground truth.

Timestamps are int64 nanoseconds. Load with imumatch.load_dataset.)")
      .def_readonly("name", &Dataset::name, "Folder name.")
      .def_readonly("root", &Dataset::root, "Folder holding the data (mav0 for EuRoC).")
      .def_property_readonly(
          "kind", [](const Dataset& d) { return std::string(ToString(d.kind)); },
          "'tum_rgbd', 'euroc' or 'synthetic'.")
      .def_readonly("camera", &Dataset::camera, "PinholeCamera of the images.")
      .def_readonly("frames", &Dataset::frames, "List of FrameRecord, time-ordered.")
      .def_readonly("imu", &Dataset::imu, "ImuBuffer (recorded or simulated).")
      .def_readonly("imu_simulated", &Dataset::imu_simulated,
                    "True when the IMU was simulated from the ground truth.")
      .def_readonly("imu_source_note", &Dataset::imu_source_note,
                    "Where the IMU data comes from (one line).")
      .def_readonly("imu_params", &Dataset::imu_params, "ImuParams: noise model of the IMU.")
      .def_readonly("cam_from_imu", &Dataset::cam_from_imu,
                    "Rigid3d: p_in_cam = cam_from_imu * p_in_imu.")
      .def_readonly("warnings", &Dataset::warnings,
                    "What the loader assumed or dropped, one line each (e.g. Kalibr calibration "
                    "files read in place of sensor.yaml, a ground truth of poses only).")
      .def_property_readonly(
          "groundtruth",
          [](const Dataset& d) {
            py::list l;
            for (const StampedPose& p : d.groundtruth_world_from_cam) {
              l.append(py::make_tuple(p.t_ns, p.world_from_body));
            }
            return l;
          },
          "[(t_ns, world_from_cam)] at the ground truth's full rate.")
      .def(
          "read_frame",
          [](const Dataset& d, size_t index, bool with_depth) {
            if (index >= d.frames.size()) {
              throw OutOfRange("frame " + std::to_string(index) + " of " +
                               std::to_string(d.frames.size()));
            }
            FrameImages f;
            {
              py::gil_scoped_release release;
              f = MakeDiskFrameReader(d)(index, with_depth);
            }
            return py::make_tuple(MatToArray(f.image),
                                  f.depth.empty() ? py::object(py::none()) : MatToArray(f.depth));
          },
          py::arg("index"), py::arg("with_depth") = true,
          "(gray image uint8, raw depth uint16 or None) of a frame; InputError when unreadable.")
      .def(
          "__len__", [](const Dataset& d) { return d.frames.size(); }, "Number of frames.");

  m.def(
      "load_dataset",
      [](const std::string& path, const std::string& imu_model, uint64_t imu_seed,
         size_t first_frame, size_t max_frames) {
        DatasetOptions o;
        o.imu_model = imu_model;
        o.imu_seed = imu_seed;
        o.first_frame = first_frame;
        o.max_frames = max_frames;
        o.Check();
        py::gil_scoped_release release;
        return LoadDatasetOrPosePair(path, o);
      },
      py::arg("path"), py::arg("imu_model") = "euroc", py::arg("imu_seed") = 42,
      py::arg("first_frame") = 0, py::arg("max_frames") = 0,
      R"(Loads a TUM RGB-D folder, a EuRoC/ASL folder (mav0), a synthetic folder written by
`imumatch synth`, or a two-frame pose pair (img_prev.png, pose_prev.txt, ...). Datasets without an
IMU (TUM) get one simulated from a spline through the ground truth (imu_model: 'euroc', 'mems',
'ideal'). Bad files raise InputError naming file and line.)");
  m.def(
      "read_tum_trajectory",
      [](const std::string& path) {
        py::list l;
        for (const StampedPose& p : ReadTumTrajectory(path)) {
          l.append(py::make_tuple(p.t_ns, p.world_from_body));
        }
        return l;
      },
      py::arg("path"),
      "[(t_ns, world_from_body)] of a TUM trajectory file (t tx ty tz qx qy qz qw).");
  m.def("read_tum_pose", &ReadTumPose, py::arg("path"),
        "The single pose of a one-line TUM pose file.");

  // ----------------------------------------------------------------------------------- sim
  py::class_<SyntheticFrame>(m, "SyntheticFrame", "A rendered frame with its exact state.")
      .def_readonly("t_ns", &SyntheticFrame::t_ns, "Timestamp (ns).")
      .def_property_readonly(
          "rgb", [](const SyntheticFrame& f) { return MatToArray(f.rgb); },
          "H x W x 3 uint8, BGR (OpenCV order).")
      .def_property_readonly(
          "depth", [](const SyntheticFrame& f) { return MatToArray(f.depth); },
          "H x W uint16, camera.depth_scale units per metre, 0 = none.")
      .def_readonly("world_from_cam", &SyntheticFrame::world_from_cam, "Exact camera pose.")
      .def_readonly("world_from_imu", &SyntheticFrame::world_from_imu, "Exact IMU pose.")
      .def_readonly("imu_velocity_in_world", &SyntheticFrame::imu_velocity_in_world,
                    "Exact IMU velocity (m/s).");

  py::class_<SyntheticSequence>(m, "SyntheticSequence", "Frames, IMU and exact ground truth.")
      .def_readonly("motion", &SyntheticSequence::motion, "Motion name.")
      .def_readonly("camera", &SyntheticSequence::camera,
                    "PinholeCamera the frames were rendered with (its lens too).")
      .def_readonly("frames", &SyntheticSequence::frames, "List of SyntheticFrame.")
      .def_property_readonly(
          "imu",
          [](const SyntheticSequence& s) {
            ImuBuffer b;
            for (const ImuSample& x : s.imu) b.Push(x, "synthetic imu");
            return b;
          },
          "The simulated IMU as an ImuBuffer (a copy).")
      .def_readonly("imu_params", &SyntheticSequence::imu_params,
                    "Noise model of the simulated IMU.")
      .def_readonly("imu_initial_bias", &SyntheticSequence::imu_initial_bias,
                    "Bias at t = 0 (the random walk starts from it).")
      .def_readonly("cam_from_imu", &SyntheticSequence::cam_from_imu,
                    "Rigid3d: p_in_cam = cam_from_imu * p_in_imu.");

  m.def(
      "write_synthetic_sequence",
      [](const SyntheticSequence& sequence, const std::string& path, const std::string& format,
         bool overwrite) {
        SyntheticWriteOptions w;
        w.overwrite = overwrite;
        py::gil_scoped_release release;
        if (format == "euroc") {
          WriteSyntheticSequenceAsEuroc(sequence, path, w);
        } else if (format == "tum") {
          WriteSyntheticSequence(sequence, path, w);
        } else {
          throw InvalidArgument("format must be 'tum' or 'euroc', not '" + format + "'");
        }
      },
      py::arg("sequence"), py::arg("path"), py::arg("format") = "tum", py::arg("overwrite") = false,
      R"(Writes a SyntheticSequence to a folder that load_dataset (and imumatch's commands) read:
format 'tum' (rgb/, depth/, *.txt, sequence.json, as `imumatch synth`) or 'euroc' (the EuRoC / ASL
layout, mav0/..., as `imumatch synth --format euroc`).)");
  m.def("motion_names", &MotionNames, "Names of the synthetic motions (e.g. 'front1m', 'left30').");
  m.def(
      "make_synthetic_sequence",
      [](const std::string& motion, const std::vector<double>& frame_times_s, double frame_rate_hz,
         const std::string& imu_model, uint64_t imu_seed, int render_threads,
         const std::optional<PinholeCamera>& camera) {
        SyntheticSequenceOptions o;
        if (camera) o.camera = *camera;
        o.motion = motion;
        o.frame_times_s = frame_times_s;
        o.frame_rate_hz = frame_rate_hz;
        o.imu_model = imu_model;
        o.imu_seed = imu_seed;
        o.render.num_threads = render_threads;
        o.Check();
        py::gil_scoped_release release;
        return MakeSyntheticSequence(o);
      },
      py::arg("motion") = "front1m", py::arg("frame_times_s") = std::vector<double>{},
      py::arg("frame_rate_hz") = 30.0, py::arg("imu_model") = "euroc", py::arg("imu_seed") = 42,
      py::arg("render_threads") = 2, py::arg("camera") = py::none(),
      R"(Renders a synthetic room seen along one of motion_names() (0.5 s still, 2 s motion, 0.5 s
still) at frame_times_s (seconds; default: every 1/frame_rate_hz), with a simulated IMU. Ground
truth is exact. camera: a PinholeCamera (default: Kinect-like 640 x 480 without a lens); with a
lens (either model) each pixel is rendered along the ray the lens gives it, and depth and poses
stay exact. Rendering costs ~0.1 s per 640 x 480 frame.)");

  // ---------------------------------------------------------------------------------- eval
  m.def(
      "evaluate",
      [](const py::object& dataset, const std::vector<std::string>& detectors,
         const std::vector<std::string>& methods, size_t max_pairs, int step, double interval_s,
         const std::string& motion_source, int max_keypoints, std::optional<double> threshold_px,
         bool refine, bool second_pass, bool monocular, uint64_t seed, bool details,
         const std::string& imu_model) {
        return Evaluate(SourceFromPython(dataset, imu_model, seed), detectors, methods, max_pairs,
                        step, interval_s, motion_source, max_keypoints, threshold_px, refine,
                        second_pass, monocular, seed, details);
      },
      py::arg("dataset"),
      py::arg("detectors") =
          std::vector<std::string>{"sift", "surf", "orb", "fast", "akaze", "brisk"},
      py::arg("methods") = std::vector<std::string>{"bf", "guided", "fixed10"},
      py::arg("max_pairs") = 0, py::arg("step") = 1, py::arg("interval_s") = 0.0,
      py::arg("motion_source") = "imu", py::arg("max_keypoints") = 1000,
      py::arg("threshold_px") = py::none(), py::arg("refine") = true, py::arg("second_pass") = true,
      py::arg("monocular") = false, py::arg("seed") = 42, py::arg("details") = false,
      py::arg("imu_model") = "euroc",
      R"(Compares IMU-guided and brute-force matching on a dataset (a path, a Dataset or a
SyntheticSequence), judged by its ground truth, as `imumatch eval` does. Returns the summary: one
dict per case, detector and method (matches, correct, false, precision, recall, window_recall,
times in ms, threshold_px). details=True returns {'rows', 'threshold', 'notes', 'warnings',
'skipped', 'bf_correct_fate', 'time_offsets', ...}; time_offsets: with a recorded IMU, per case
and detector, the camera's clock offset from the IMU's that the fitted rotations measure
(t_imu = t_cam + offset_s: measured, offset_s, sigma_s (both None when not measured),
observations, inliers, reason);
bf_correct_fate: per prediction method, summed over the pairs, what it
made of brute force's correct matches (kept, matched_wrong, not matched by reason) and the
correct matches it gained where brute force had none.
second_pass=False: the guided method matches once, in the IMU's windows (`--single-pass`).
monocular=True: predicted without depth, the depth images only judge (`--monocular`).)");
}

}  // namespace imumatch::python
