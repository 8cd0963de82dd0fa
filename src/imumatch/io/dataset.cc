#include "imumatch/io/dataset.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/io/dataset_internal.h"
#include "imumatch/io/euroc.h"
#include "imumatch/io/imu_io.h"
#include "imumatch/io/plausibility.h"
#include "imumatch/io/text_parsing.h"
#include "imumatch/io/trajectory_io.h"
#include "imumatch/sim/imu_simulator.h"

namespace imumatch {
namespace fs = std::filesystem;

namespace dataset_internal {

std::string FolderName(const std::string& path) {
  fs::path p = fs::path(path).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

}  // namespace dataset_internal

namespace {

bool Contains(const std::string& haystack, const std::string& needle) {
  std::string h = haystack;
  std::transform(h.begin(), h.end(), h.begin(), [](unsigned char c) { return std::tolower(c); });
  return h.find(needle) != std::string::npos;
}

void CheckExists(const std::string& file, const std::string& list, int line) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    throw InputError(list, line, "listed file " + file + " not found");
  }
}

}  // namespace

namespace dataset_internal {

void SelectFrames(std::vector<FrameRecord>& frames, const DatasetOptions& options) {
  if (options.first_frame > 0) {
    frames.erase(frames.begin(), frames.begin() + static_cast<std::ptrdiff_t>(std::min(
                                                      options.first_frame, frames.size())));
  }
  if (options.max_frames > 0 && frames.size() > options.max_frames) {
    frames.resize(options.max_frames);
  }
}

std::string DescribeModel(const std::string& model) {
  std::string m = model;
  std::transform(m.begin(), m.end(), m.begin(), [](unsigned char c) { return std::tolower(c); });
  if (m == "euroc" || m == "adis16448") return "the EuRoC ADIS16448 noise model";
  if (m == "mems" || m == "consumer") return "a consumer MEMS noise model";
  if (m == "ideal" || m == "none") return "no noise (ideal IMU)";
  return "the '" + model + "' noise model";
}

std::vector<FrameRecord> TumFrames(const TumRgbdFiles& files, int64_t max_difference_ns,
                                   bool check_files, std::vector<std::string>* warnings) {
  const std::string rgb_list = (fs::path(files.root) / "rgb.txt").string();
  const std::string depth_list = (fs::path(files.root) / "depth.txt").string();
  std::vector<FrameRecord> frames;
  auto add = [&](const StampedFile& rgb, const StampedFile* depth) {
    FrameRecord f;
    f.t_ns = rgb.t_ns;
    f.image_path = (fs::path(files.root) / rgb.path).string();
    if (check_files) CheckExists(f.image_path, rgb_list, rgb.line);
    if (depth != nullptr) {
      f.depth_path = (fs::path(files.root) / depth->path).string();
      if (check_files) CheckExists(f.depth_path, depth_list, depth->line);
    }
    frames.push_back(std::move(f));
  };
  if (files.depth.empty()) {
    for (const StampedFile& rgb : files.rgb) add(rgb, nullptr);
    return frames;
  }
  std::vector<int64_t> rgb_t, depth_t;
  for (const StampedFile& f : files.rgb) rgb_t.push_back(f.t_ns);
  for (const StampedFile& f : files.depth) depth_t.push_back(f.t_ns);
  std::vector<char> associated(files.rgb.size(), 0);
  for (const Association& a : AssociateTimestamps(rgb_t, depth_t, max_difference_ns)) {
    add(files.rgb[a.first], &files.depth[a.second]);
    associated[a.first] = 1;
  }
  if (frames.size() < files.rgb.size() && warnings != nullptr) {
    const size_t first = static_cast<size_t>(std::find(associated.begin(), associated.end(), 0) -
                                             associated.begin());
    std::ostringstream msg;
    msg << (files.rgb.size() - frames.size()) << " of " << files.rgb.size()
        << " frames of rgb.txt have no depth image within " << max_difference_ns / 1000000.0
        << " ms in depth.txt and are dropped (first: " << rgb_list << ":" << files.rgb[first].line
        << ")";
    warnings->push_back(msg.str());
  }
  return frames;
}

void RefuseTimeshift(const std::string& path, const DatasetOptions& options, const char* why) {
  if (options.timeshift_cam_imu_s) {
    throw InvalidArgument(path + ": a timeshift_cam_imu applies to EuRoC/ASL recordings; this is " +
                          why);
  }
}

}  // namespace dataset_internal

using dataset_internal::DescribeModel;
using dataset_internal::FolderName;
using dataset_internal::RefuseTimeshift;
using dataset_internal::SelectFrames;
using dataset_internal::TumFrames;

namespace {

std::vector<int64_t> FrameTimes(const std::vector<FrameRecord>& frames) {
  std::vector<int64_t> t;
  for (const FrameRecord& f : frames) t.push_back(f.t_ns);
  return t;
}

}  // namespace

const char* ToString(DatasetKind kind) {
  switch (kind) {
    case DatasetKind::kTumRgbd:
      return "tum_rgbd";
    case DatasetKind::kEuroc:
      return "euroc";
    case DatasetKind::kSynthetic:
      return "synthetic";
  }
  return "unknown";
}

void DatasetOptions::Check() const {
  if (camera) camera->Check();
  IMUMATCH_CHECK(max_time_difference_ns >= 0, "max_time_difference_ns=" << max_time_difference_ns);
  IMUMATCH_CHECK(groundtruth_max_difference_ns >= 0,
                 "groundtruth_max_difference_ns=" << groundtruth_max_difference_ns);
  ImuParams::FromName(imu_model);  // throws InvalidArgument for an unknown model
  IMUMATCH_CHECK(tum_cam_from_imu.translation.allFinite() &&
                     std::abs(tum_cam_from_imu.rotation.norm() - 1.0) < 1e-9,
                 "tum_cam_from_imu must be a finite rigid transform");
  IMUMATCH_CHECK(
      max_simulated_imu_span_ns > 0 && max_simulated_imu_span_ns <= kMaxSimulatedImuSpanNs,
      "max_simulated_imu_span_ns=" << max_simulated_imu_span_ns << " (at most "
                                   << kMaxSimulatedImuSpanNs << ")");
  spline.Check();
  imu_buffer.Check();
  IMUMATCH_CHECK(!timeshift_cam_imu_s ||
                     (std::isfinite(*timeshift_cam_imu_s) && std::abs(*timeshift_cam_imu_s) <= 1.0),
                 "timeshift_cam_imu_s must be finite and at most 1 s, got "
                     << timeshift_cam_imu_s.value_or(0.0));
}

PinholeCamera ReadCameraFile(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".yaml" || extension == ".yml") return ReadYamlCamera(path);
  return ReadCameraFromText(path);
}

PinholeCamera TumCameraForFolderName(const std::string& folder_name) {
  if (Contains(folder_name, "freiburg1")) return PinholeCamera::TumFreiburg1();
  PinholeCamera c = PinholeCamera::KinectDefault();
  if (Contains(folder_name, "freiburg2")) {
    c.fx = 520.9;
    c.fy = 521.0;
    c.cx = 325.1;
    c.cy = 249.7;
    c.distortion = {0.2312, -0.7849, -0.0033, -0.0001, 0.9172};
  } else if (Contains(folder_name, "freiburg3")) {
    c.fx = 535.4;
    c.fy = 539.2;
    c.cx = 320.1;
    c.cy = 247.6;
  }
  return c;
}

Dataset LoadTumRgbdDataset(const std::string& root, const DatasetOptions& options) {
  options.Check();
  RefuseTimeshift(root, options,
                  "a TUM RGB-D folder, whose IMU is simulated in the ground truth's clock");
  const TumRgbdFiles files = ReadTumRgbdFolder(root);
  Dataset d;
  d.kind = DatasetKind::kTumRgbd;
  d.root = root;
  d.name = FolderName(root);
  std::error_code ec;
  const std::string camera_txt = (fs::path(root) / "camera.txt").string();
  if (options.camera) {
    d.camera = *options.camera;
  } else if (fs::exists(camera_txt, ec)) {
    d.camera = ReadCameraFromText(camera_txt);
  } else {
    d.camera = TumCameraForFolderName(d.name);
  }
  d.warnings = files.warnings;
  d.frames =
      TumFrames(files, options.max_time_difference_ns, options.check_files_exist, &d.warnings);
  if (fs::exists(fs::path(root) / "imu.txt", ec) &&
      fs::exists(fs::path(root) / "velocity.txt", ec)) {
    d.warnings.push_back(
        "the folder has imu.txt and velocity.txt like an `imumatch synth` sequence, but no "
        "sequence.json: read as TUM RGB-D, with an IMU simulated from groundtruth.txt (its "
        "imu.txt is not used)");
  }
  d.groundtruth_world_from_cam = files.groundtruth;
  const auto gt =
      LookUpGroundTruth(files.groundtruth, FrameTimes(d.frames), options.groundtruth_lookup,
                        options.groundtruth_max_difference_ns);
  for (size_t i = 0; i < d.frames.size(); ++i) d.frames[i].world_from_cam = gt[i];
  SelectFrames(d.frames, options);

  d.cam_from_imu = options.tum_cam_from_imu;
  d.imu_params = ImuParams::FromName(options.imu_model);
  d.imu = ImuBuffer(options.imu_buffer);
  const std::string gt_path = (fs::path(root) / "groundtruth.txt").string();
  if (!options.simulate_imu) {
    d.imu_source_note = "no IMU (TUM RGB-D records no gyroscope; simulation disabled)";
  } else if (files.groundtruth.size() < 4) {
    d.imu_source_note =
        "no IMU (TUM RGB-D records no gyroscope and there is no ground truth "
        "to simulate one from)";
  } else {
    // The spline describes the camera (body = camera); the IMU sits at cam_from_imu in it.
    // Bounded work: the IMU is simulated over the whole ground-truth span.
    const int64_t span_ns = files.groundtruth.back().t_ns - files.groundtruth.front().t_ns;
    if (span_ns > options.max_simulated_imu_span_ns) {
      throw InputError(gt_path, "ground truth spans " + FormatNsAsSeconds(span_ns) +
                                    " s: longer than the " +
                                    FormatNsAsSeconds(options.max_simulated_imu_span_ns) +
                                    " s an IMU is simulated for (a timestamp jump?)");
    }
    const SplineTrajectory spline(files.groundtruth, options.spline);
    ImuSimulatorOptions sim;
    sim.rate_hz = d.imu_params.rate_hz;
    sim.seed = options.imu_seed;
    sim.body_from_imu = options.tum_cam_from_imu;
    sim.t0_ns = spline.t0_ns();
    for (const ImuSample& s : SimulateImu(spline, d.imu_params, sim)) {
      d.imu.Push(s, "IMU simulated from " + gt_path, 0);
    }
    d.imu_simulated = true;
    std::ostringstream note;
    note << "IMU simulated from ground truth with " << DescribeModel(options.imu_model) << ", seed "
         << options.imu_seed << " (" << d.imu_params.rate_hz << " Hz, spline knots every "
         << options.spline.knot_spacing_s << " s)";
    d.imu_source_note = note.str();
    // IMU velocity: v_imu = v_cam + R_world_from_cam (omega_cam x t_cam_imu).
    const Rigid3d cam_from_imu = options.tum_cam_from_imu;
    for (FrameRecord& f : d.frames) {
      const double t = spline.TimeOf(f.t_ns);
      if (t < 0.0 || t > spline.EndTime()) continue;
      const Rigid3d world_from_cam = spline.WorldFromBody(t);
      f.imu_velocity_in_world =
          spline.VelocityInWorld(t) +
          world_from_cam.rotation * spline.AngularVelocityInBody(t).cross(cam_from_imu.translation);
    }
  }
  return d;
}

Dataset LoadEurocDataset(const std::string& path, const DatasetOptions& options) {
  options.Check();
  EurocSequence seq = ReadEurocSequence(path, options.imu_buffer);
  Dataset d;
  d.kind = DatasetKind::kEuroc;
  d.root = seq.mav0;
  // Name of the folder above mav0 (e.g. V1_01_easy).
  d.name = FolderName(fs::path(seq.mav0).lexically_normal().parent_path().string());
  d.camera = options.camera ? *options.camera : seq.cam0.camera;
  // The depth scale describes the depth files, not the lens, so depth0's value wins even over an
  // intrinsics override.
  if (seq.depth0) d.camera.depth_scale = seq.depth0->depth_scale;
  d.cam_from_imu = seq.CamFromImu();
  d.imu_params = seq.imu0.params;
  d.imu = std::move(seq.imu);
  d.imu_simulated = false;
  d.sixteen_bit_images = SixteenBitImages::kScaleTo8Bit;
  d.imu_source_note = "IMU recorded (EuRoC imu0, " + FormatDoubleExact(seq.imu0.params.rate_hz) +
                      " Hz, noise model from " + seq.imu0_calibration_file + ")";
  if (seq.kalibr_calibration) {
    d.warnings.push_back("no EuRoC sensor.yaml: camera and extrinsics from " +
                         seq.cam0_calibration_file + ", IMU noise from " +
                         seq.imu0_calibration_file);
  }
  // Kalibr's timeshift: t_imu = t_cam + shift. The frames move into the IMU's clock (the ground
  // truth's, for EuRoC and TUM-VI); depth0 rows pair with cam0 rows by their recorded times.
  // A timeshift given in the options replaces the calibration's.
  const double shift_s = options.timeshift_cam_imu_s.value_or(seq.cam0.timeshift_cam_imu_s);
  const int64_t shift_ns = std::llround(shift_s * 1e9);
  d.timeshift_cam_imu_s = shift_s;
  const auto seconds = [](double v) {  // as typed: 0.0098, not 0.0097999999999999997
    std::ostringstream out;
    out << std::setprecision(9) << v;
    return out.str();
  };
  if (options.timeshift_cam_imu_s) {
    d.warnings.push_back("frame timestamps moved by the given timeshift_cam_imu (" +
                         seconds(shift_s) + " s, replacing the calibration's " +
                         seconds(seq.cam0.timeshift_cam_imu_s) +
                         " s) into the IMU's clock (t_imu = t_cam + shift)");
  } else if (shift_ns != 0) {
    d.warnings.push_back("frame timestamps moved by the timeshift_cam_imu of " +
                         seq.cam0_calibration_file + " (" + seconds(shift_s) +
                         " s) into the IMU's clock (t_imu = t_cam + shift)");
  }
  if (seq.groundtruth.empty() && !seq.groundtruth_source.empty()) {
    d.warnings.push_back(seq.mav0 + "/" + seq.groundtruth_source +
                         "/data.csv holds no poses: the recording has no ground truth");
  }
  if (!seq.groundtruth.empty() && seq.groundtruth_source != "state_groundtruth_estimate0") {
    d.warnings.push_back("ground truth from " + seq.groundtruth_source +
                         "/data.csv (poses only): the velocity at each frame is the slope of the "
                         "positions within +-50 ms, the biases are not known");
  }
  const Rigid3d& body_from_cam = seq.cam0.body_from_sensor;
  for (const EurocGroundTruthState& s : seq.groundtruth) {
    d.groundtruth_world_from_cam.push_back({s.t_ns, s.world_from_body * body_from_cam});
  }
  const std::string list = seq.mav0 + "/cam0/data.csv";
  const std::string depth_list = seq.mav0 + "/depth0/data.csv";
  // ReadEurocSequence guarantees every depth row has a cam0 row with the same timestamp and both
  // lists are increasing, so one forward walk pairs them; cam0 frames in between get no depth.
  auto depth = seq.depth_images.begin();
  for (const StampedFile& f : seq.images) {
    FrameRecord r;
    r.t_ns = f.t_ns + shift_ns;
    r.image_path = seq.ImagePath(f);
    if (options.check_files_exist) CheckExists(r.image_path, list, f.line);
    if (depth != seq.depth_images.end() && depth->t_ns == f.t_ns) {
      r.depth_path = seq.DepthPath(*depth);
      if (options.check_files_exist) CheckExists(r.depth_path, depth_list, depth->line);
      ++depth;
    }
    d.frames.push_back(std::move(r));
  }
  const auto gt =
      LookUpGroundTruth(d.groundtruth_world_from_cam, FrameTimes(d.frames),
                        options.groundtruth_lookup, options.groundtruth_max_difference_ns);
  for (size_t i = 0; i < d.frames.size(); ++i) {
    FrameRecord& f = d.frames[i];
    f.world_from_cam = gt[i];
    // Velocity of the body (= the IMU in EuRoC) interpolated linearly between the neighbours.
    const auto upper =
        std::lower_bound(seq.groundtruth.begin(), seq.groundtruth.end(), f.t_ns,
                         [](const EurocGroundTruthState& s, int64_t t) { return s.t_ns < t; });
    if (upper == seq.groundtruth.end()) continue;
    if (upper->t_ns == f.t_ns) {
      // (A velocity derived from poses may be missing: NaN, at the ends of the poses.)
      if (upper->velocity_in_world.allFinite()) f.imu_velocity_in_world = upper->velocity_in_world;
    } else if (upper != seq.groundtruth.begin()) {
      const auto& a = *std::prev(upper);
      const auto& b = *upper;
      if (f.t_ns - a.t_ns <= options.groundtruth_max_difference_ns &&
          b.t_ns - f.t_ns <= options.groundtruth_max_difference_ns) {
        const double alpha =
            static_cast<double>(f.t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
        const Eigen::Vector3d v = (1.0 - alpha) * a.velocity_in_world + alpha * b.velocity_in_world;
        if (v.allFinite()) f.imu_velocity_in_world = v;
      }
    }
  }
  SelectFrames(d.frames, options);
  return d;
}

namespace {

// A loader warning for the gaps in the IMU log: pairs of frames across one get no IMU motion.
void WarnAboutImuGaps(Dataset& d) {
  const std::vector<ImuBuffer::Gap> gaps = d.imu.Gaps();
  if (gaps.empty()) return;
  const auto it = std::max_element(gaps.begin(), gaps.end(), [](const auto& a, const auto& b) {
    return a.end_ns - a.begin_ns < b.end_ns - b.begin_ns;
  });
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(1) << d.imu.source();
  if (gaps.front().line > 0) msg << ":" << gaps.front().line;
  msg << ": the IMU log has " << gaps.size() << (gaps.size() == 1 ? " gap" : " gaps")
      << " longer than " << static_cast<double>(d.imu.options().max_gap_ns) * 1e-6
      << " ms (the first from " << FormatNsAsSeconds(gaps.front().begin_ns) << " s, the longest "
      << static_cast<double>(it->end_ns - it->begin_ns) * 1e-6
      << " ms): frames paired across a gap get no IMU motion";
  d.warnings.push_back(msg.str());
}

// A recorded IMU whose samples come at another rate than its calibration's rate_hz says (a
// sensor.yaml copied from another IMU or another rate setting, a log decimated since). The
// calibration's noise densities are continuous-time and stay; the per-sample noise they imply
// (density x sqrt(rate), the still start's floor) is the recorded rate's, which replaces the
// stated one. Within 10 % (a clock's drift, the jitter of a driver's timestamps) nothing is said.
void CheckImuRate(Dataset& d) {
  if (d.imu_simulated || d.imu.size() < 3) return;
  const std::vector<ImuSample>& s = d.imu.samples();
  std::vector<int64_t> intervals;
  intervals.reserve(s.size() - 1);
  for (size_t i = 1; i < s.size(); ++i) intervals.push_back(s[i].t_ns - s[i - 1].t_ns);
  const auto mid = intervals.begin() + static_cast<std::ptrdiff_t>(intervals.size() / 2);
  std::nth_element(intervals.begin(), mid, intervals.end());
  if (*mid <= 0) return;  // the buffer refuses such logs; nothing to compare
  const double recorded_hz = 1e9 / static_cast<double>(*mid);
  const double stated_hz = d.imu_params.rate_hz;
  if (std::fabs(recorded_hz / stated_hz - 1.0) <= 0.1) return;
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(1) << d.imu.source() << ": the IMU samples come at "
      << recorded_hz << " Hz (median interval " << static_cast<double>(*mid) * 1e-6
      << " ms) but its calibration says rate_hz " << FormatDoubleExact(stated_hz)
      << ": the noise per sample is taken at the recorded rate";
  d.warnings.push_back(msg.str());
  d.imu_params.rate_hz = recorded_hz;
}

Dataset LoadDatasetOfKind(const std::string& path, const DatasetOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "dataset folder not found");
  if (!fs::is_directory(path, ec)) throw InputError(path, "dataset path is not a folder");
  const fs::path p(path);
  if (fs::exists(p / "sequence.json", ec)) return LoadSyntheticDataset(path, options);
  if (fs::exists(p / "rgb.txt", ec)) return LoadTumRgbdDataset(path, options);
  if (!FindEurocMav0(path).empty()) return LoadEurocDataset(path, options);
  throw InputError(path,
                   "not a recognised dataset folder: expected sequence.json (imumatch synth), "
                   "rgb.txt (TUM RGB-D) or mav0/ (EuRoC)");
}

}  // namespace

Dataset LoadDataset(const std::string& path, const DatasetOptions& options) {
  options.Check();
  Dataset d = LoadDatasetOfKind(path, options);
  WarnAboutImuGaps(d);
  CheckImuRate(d);
  return d;
}

}  // namespace imumatch
