// LoadSyntheticDataset (dataset.h): a folder written by WriteSyntheticSequence (synthetic_io.h),
// read from its sequence.json, TUM-style frame lists and IMU text.
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/dataset_internal.h"
#include "imumatch/io/imu_io.h"
#include "imumatch/io/plausibility.h"
#include "imumatch/io/text_parsing.h"
#include "imumatch/io/trajectory_io.h"

namespace imumatch {

namespace fs = std::filesystem;
using dataset_internal::DescribeModel;
using dataset_internal::FolderName;
using dataset_internal::RefuseTimeshift;
using dataset_internal::SelectFrames;
using dataset_internal::TumFrames;

namespace {

using Json = nlohmann::json;

// ----- JSON helpers for sequence.json ------------------------------------------------------------

const Json& Need(const Json& obj, const std::string& key, const std::string& path) {
  if (!obj.is_object() || !obj.contains(key) || obj.at(key).is_null()) {
    throw InputError(path, "missing key '" + key + "'");
  }
  return obj.at(key);
}

double NeedDouble(const Json& obj, const std::string& key, const std::string& path) {
  const Json& v = Need(obj, key, path);
  if (!v.is_number()) throw InputError(path, "'" + key + "' must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw InputError(path, "'" + key + "' is not finite");
  return d;
}

std::vector<double> NeedDoubles(const Json& obj, const std::string& key, size_t n,
                                const std::string& path) {
  const Json& v = Need(obj, key, path);
  if (!v.is_array() || v.size() != n) {
    throw InputError(path, "'" + key + "' must be a list of " + std::to_string(n) + " numbers");
  }
  std::vector<double> out;
  for (const Json& e : v) {
    if (!e.is_number() || !std::isfinite(e.get<double>())) {
      throw InputError(path, "'" + key + "' must hold finite numbers");
    }
    out.push_back(e.get<double>());
  }
  return out;
}

Eigen::Vector3d NeedVec3(const Json& obj, const std::string& key, const std::string& path) {
  const std::vector<double> v = NeedDoubles(obj, key, 3, path);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Json ParseJsonFile(const std::string& path) {
  const std::string text = ReadFileToString(path);
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    const size_t byte = std::min<size_t>(e.byte, text.size());
    const int line = 1 + static_cast<int>(std::count(
                             text.begin(), text.begin() + static_cast<std::ptrdiff_t>(byte), '\n'));
    throw InputError(path, line, std::string("JSON syntax error: ") + e.what());
  } catch (const Json::exception& e) {  // e.g. out_of_range: a number like 1e400
    throw InputError(path, std::string("JSON: ") + e.what());
  }
}

int NeedInt(const Json& obj, const std::string& key, const std::string& path, int min_value,
            int max_value) {
  const double d = NeedDouble(obj, key, path);
  if (!(d >= min_value && d <= max_value) || d != std::floor(d)) {
    throw InputError(path, "'" + key + "' must be an integer in [" + std::to_string(min_value) +
                               ", " + std::to_string(max_value) + "]");
  }
  return static_cast<int>(d);
}

// "t vx vy vz" lines.
std::map<int64_t, Eigen::Vector3d> ReadVelocities(const std::string& path) {
  std::map<int64_t, Eigen::Vector3d> out;
  int64_t previous = 0;
  int previous_line = 0;
  for (const TextLine& line : ReadTextFields(path, FieldSeparator::kWhitespace)) {
    CheckFieldCount(line, 4, path, "t vx vy vz");
    const int64_t t = ParseSecondsField(line.fields[0], path, line.line);
    CheckIncreasingTimestamp(previous, previous_line, t, path, line.line);
    out[t] = Eigen::Vector3d(ParseFiniteDouble(line.fields[1], path, line.line, "vx"),
                             ParseFiniteDouble(line.fields[2], path, line.line, "vy"),
                             ParseFiniteDouble(line.fields[3], path, line.line, "vz"));
    plausibility::CheckVelocity(out[t], path, line.line);
    previous = t;
    previous_line = line.line;
  }
  return out;
}

}  // namespace

Dataset LoadSyntheticDataset(const std::string& root, const DatasetOptions& options) {
  options.Check();
  RefuseTimeshift(root, options, "a synthetic folder, whose IMU shares the camera's clock");
  const std::string json_path = (fs::path(root) / "sequence.json").string();
  const Json j = ParseJsonFile(json_path);
  if (!j.is_object() || !j.contains("generator") || j.at("generator") != "imumatch synth") {
    throw InputError(json_path,
                     "not an imumatch synthetic sequence (\"generator\" is not "
                     "\"imumatch synth\")");
  }
  Dataset d;
  d.kind = DatasetKind::kSynthetic;
  d.root = root;
  d.name = FolderName(root);

  const Json& cam = Need(j, "camera", json_path);
  PinholeCamera c;
  c.width = NeedInt(cam, "width", json_path, 1, plausibility::kMaxImageSide);
  c.height = NeedInt(cam, "height", json_path, 1, plausibility::kMaxImageSide);
  c.fx = NeedDouble(cam, "fx", json_path);
  c.fy = NeedDouble(cam, "fy", json_path);
  c.cx = NeedDouble(cam, "cx", json_path);
  c.cy = NeedDouble(cam, "cy", json_path);
  // "distortion_model" since 2026-12-06; sequences written before have radial-tangential lenses.
  if (const auto it = cam.find("distortion_model"); it != cam.end()) {
    const std::optional<DistortionModel> model =
        it->is_string() ? DistortionModelFromName(it->get<std::string>()) : std::nullopt;
    if (!model) {
      throw InputError(json_path, std::string("camera.distortion_model must be one of ") +
                                      kDistortionModelNames);
    }
    c.model = *model;
  }
  const std::vector<double> dist = NeedDoubles(cam, "distortion", 5, json_path);
  std::copy(dist.begin(), dist.end(), c.distortion.begin());
  c.depth_scale = NeedDouble(cam, "depth_scale", json_path);
  try {
    c.Check();
  } catch (const InvalidArgument& e) {
    throw InputError(json_path, std::string("camera: ") + e.what());
  }
  d.camera = options.camera ? *options.camera : c;
  // camera.txt is written beside sequence.json for TUM-style tools; the folder's camera is
  // sequence.json's. One edited by hand would otherwise be ignored without a word.
  const std::string camera_txt = (fs::path(root) / "camera.txt").string();
  std::error_code camera_txt_ec;
  if (!options.camera && fs::exists(camera_txt, camera_txt_ec)) {
    const std::string use =
        ": the camera used is sequence.json's (pass --camera " + camera_txt + " to use this one)";
    try {
      if (!ReadCameraFromText(camera_txt).SameImageGeometry(c)) {
        d.warnings.push_back(camera_txt + " differs from sequence.json's camera" + use);
      }
    } catch (const Error& e) {
      d.warnings.push_back(std::string(e.what()) + use);
    }
  }

  const Json& p = Need(j, "imu_params", json_path);
  d.imu_params.gyro_noise_density = NeedDouble(p, "gyro_noise_density", json_path);
  d.imu_params.gyro_random_walk = NeedDouble(p, "gyro_random_walk", json_path);
  d.imu_params.accel_noise_density = NeedDouble(p, "accel_noise_density", json_path);
  d.imu_params.accel_random_walk = NeedDouble(p, "accel_random_walk", json_path);
  d.imu_params.rate_hz = NeedDouble(p, "rate_hz", json_path);
  d.imu_params.gravity_in_world = NeedVec3(p, "gravity_in_world", json_path);
  try {
    d.imu_params.Check();
  } catch (const InvalidArgument& e) {
    throw InputError(json_path, std::string("imu_params: ") + e.what());
  }

  const Json& rows = Need(j, "cam_from_imu", json_path);
  if (!rows.is_array() || rows.size() != 4) {
    throw InputError(json_path, "'cam_from_imu' must be a 4x4 matrix (4 rows of 4 numbers)");
  }
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    const std::vector<double> row =
        NeedDoubles(Json{{"row", rows[static_cast<size_t>(r)]}}, "row", 4, json_path);
    for (int col = 0; col < 4; ++col) m(r, col) = row[static_cast<size_t>(col)];
  }
  try {
    d.cam_from_imu = Rigid3d::FromMatrix(m, 1e-6);
  } catch (const InvalidArgument& e) {
    throw InputError(json_path, std::string("cam_from_imu is not a rigid transform: ") + e.what());
  }
  if (j.contains("cam_from_imu_quaternion_wxyz")) {
    // The quaternion as written, so the extrinsic round-trips bit for bit.
    const std::vector<double> q = NeedDoubles(j, "cam_from_imu_quaternion_wxyz", 4, json_path);
    const Eigen::Quaterniond stored(q[0], q[1], q[2], q[3]);
    if (std::abs(stored.norm() - 1.0) > 1e-9 ||
        RotationDistance(stored, d.cam_from_imu.rotation) > 1e-6) {
      throw InputError(json_path, "cam_from_imu_quaternion_wxyz disagrees with cam_from_imu");
    }
    d.cam_from_imu.rotation = stored;
  }

  // Frames, exact ground truth, velocities and the stored IMU.
  const TumRgbdFiles files = ReadTumRgbdFolder(root);
  d.warnings.insert(d.warnings.end(), files.warnings.begin(), files.warnings.end());
  d.frames = TumFrames(files, 1, options.check_files_exist,
                       &d.warnings);  // identical timestamps only
  d.groundtruth_world_from_cam = files.groundtruth;
  const std::string velocity_path = (fs::path(root) / "velocity.txt").string();
  std::error_code ec;
  const auto velocities = fs::exists(velocity_path, ec) ? ReadVelocities(velocity_path)
                                                        : std::map<int64_t, Eigen::Vector3d>();
  for (FrameRecord& f : d.frames) {
    f.world_from_cam = InterpolatePoseAt(files.groundtruth, f.t_ns, 0);
    if (const auto it = velocities.find(f.t_ns); it != velocities.end()) {
      f.imu_velocity_in_world = it->second;
    }
  }
  SelectFrames(d.frames, options);
  d.imu = ReadImuText((fs::path(root) / "imu.txt").string(), options.imu_buffer);
  d.imu_simulated = true;
  std::ostringstream note;
  note << "IMU simulated by imumatch synth";
  auto text_field = [&j](const char* key) {
    return j.contains(key) && j.at(key).is_string() ? j.at(key).get<std::string>() : std::string();
  };
  if (const std::string model = text_field("imu_model"); !model.empty()) {
    note << " with " << DescribeModel(model);
  }
  if (j.contains("seed") && j.at("seed").is_number_integer()) {
    note << ", seed " << j.at("seed").get<uint64_t>();
  }
  if (const std::string motion = text_field("motion"); !motion.empty()) {
    note << " (motion " << motion << ")";
  }
  d.imu_source_note = note.str();
  return d;
}

}  // namespace imumatch
