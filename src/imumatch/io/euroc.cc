#include "imumatch/io/euroc.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "imumatch/core/error.h"
#include "imumatch/io/imu_io.h"
#include "imumatch/io/plausibility.h"
#include "imumatch/io/text_parsing.h"

namespace imumatch {
namespace {

namespace fs = std::filesystem;

int LineOf(const YAML::Node& node) { return node.Mark().line >= 0 ? node.Mark().line + 1 : 0; }

// Loads a Kalibr/OpenCV style YAML file; the "%YAML:1.0" first line becomes a comment so yaml-cpp
// accepts it and line numbers stay those of the file.
YAML::Node LoadOpenCvYaml(const std::string& path) {
  std::string text = ReadFileToString(path);
  if (text.rfind("%YAML", 0) == 0) text[0] = '#';
  try {
    YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) {
      throw InputError(path, root.IsNull() ? "the file holds no keys (empty, or comments only): "
                                             "expected a YAML mapping of keys to values"
                                           : "expected a YAML mapping of keys to values");
    }
    return root;
  } catch (const YAML::Exception& e) {
    throw InputError(path, e.mark.line >= 0 ? e.mark.line + 1 : 0, "YAML error: " + e.msg);
  }
}

// map[key], or InputError "missing key": with no line for a top-level key, with the line of the
// enclosing mapping for a nested one (parent names it).
YAML::Node Require(const YAML::Node& map, const std::string& key, const std::string& path,
                   const std::string& parent = "") {
  const YAML::Node node = map[key];
  if (!node.IsDefined() || node.IsNull()) {
    if (parent.empty()) throw InputError(path, "missing key '" + key + "'");
    throw InputError(path, LineOf(map), "missing key '" + key + "' in '" + parent + "'");
  }
  return node;
}

double ScalarToDouble(const YAML::Node& node, const std::string& what, const std::string& path) {
  if (!node.IsScalar()) throw InputError(path, LineOf(node), what + ": expected a number");
  return ParseFiniteDouble(node.Scalar(), path, LineOf(node), what);
}

double GetDouble(const YAML::Node& map, const std::string& key, const std::string& path,
                 const std::string& parent = "") {
  return ScalarToDouble(Require(map, key, path, parent), key, path);
}

std::string GetString(const YAML::Node& map, const std::string& key, const std::string& path) {
  const YAML::Node node = Require(map, key, path);
  if (!node.IsScalar()) throw InputError(path, LineOf(node), key + ": expected a text value");
  return node.Scalar();
}

std::vector<double> GetDoubles(const YAML::Node& map, const std::string& key,
                               const std::string& path, size_t min_size, size_t max_size,
                               const std::string& parent = "") {
  const YAML::Node node = Require(map, key, path, parent);
  if (!node.IsSequence())
    throw InputError(path, LineOf(node), key + ": expected a list [a, b, ...]");
  if (node.size() < min_size || node.size() > max_size) {
    std::ostringstream msg;
    msg << key << ": expected ";
    if (min_size == max_size) {
      msg << min_size;
    } else {
      msg << min_size << " to " << max_size;
    }
    msg << " numbers, got " << node.size();
    throw InputError(path, LineOf(node), msg.str());
  }
  std::vector<double> values;
  for (size_t i = 0; i < node.size(); ++i) {
    values.push_back(ScalarToDouble(node[i], key + "[" + std::to_string(i) + "]", path));
  }
  return values;
}

Rigid3d GetTransform(const YAML::Node& map, const std::string& key, const std::string& path) {
  const YAML::Node node = Require(map, key, path);
  if (!node.IsMap()) throw InputError(path, LineOf(node), key + ": expected rows, cols and data");
  if (GetDouble(node, "rows", path, key) != 4 || GetDouble(node, "cols", path, key) != 4) {
    throw InputError(path, LineOf(node), key + ": expected a 4x4 matrix");
  }
  const std::vector<double> data = GetDoubles(node, "data", path, 16, 16, key);
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = data[static_cast<size_t>(4 * r + c)];
  }
  try {
    return Rigid3d::FromMatrix(m, 1e-6);
  } catch (const InvalidArgument& e) {
    throw InputError(path, LineOf(node["data"]), key + " is not a rigid transform: " + e.what());
  }
}

// "timestamp [ns], filename" rows with strictly increasing timestamps (cam0 and depth0 lists).
std::vector<StampedFile> ReadStampedFileList(const std::string& path, const std::string& what) {
  std::vector<StampedFile> files;
  for (const TextLine& line : ReadTextFields(path, FieldSeparator::kComma)) {
    CheckFieldCount(line, 2, path, "timestamp [ns], filename");
    StampedFile f;
    f.t_ns = ParseNsField(line.fields[0], path, line.line);
    if (!files.empty()) {
      CheckIncreasingTimestamp(files.back().t_ns, files.back().line, f.t_ns, path, line.line);
    }
    f.path = line.fields[1];
    f.line = line.line;
    files.push_back(std::move(f));
  }
  if (files.empty()) throw InputError(path, "no " + what + " listed");
  return files;
}

}  // namespace

ImuBuffer ReadEurocImu(const std::string& path, const ImuBufferOptions& options) {
  static const char* const kNames[6] = {"w_x", "w_y", "w_z", "a_x", "a_y", "a_z"};
  return ReadImuTable(path, FieldSeparator::kComma, ImuTimeUnit::kNanoseconds,
                      "timestamp [ns], w x y z [rad/s], a x y z [m/s^2]", kNames, options);
}

std::vector<StampedFile> ReadEurocImageList(const std::string& path) {
  return ReadStampedFileList(path, "images");
}

std::vector<StampedFile> ReadEurocDepthList(const std::string& path) {
  return ReadStampedFileList(path, "depth images");
}

namespace {

// The camera of a Kalibr / EuRoC camera node: camera_model (pinhole), intrinsics, resolution,
// distortion_model and its coefficients under coefficients_key.
PinholeCamera CameraFromYaml(const YAML::Node& node, const std::string& path,
                             const std::string& coefficients_key) {
  const std::string model = GetString(node, "camera_model", path);
  if (model != "pinhole") {
    throw InputError(path, LineOf(node["camera_model"]),
                     "camera_model '" + model + "' is not supported (only 'pinhole')");
  }
  PinholeCamera camera;
  const std::vector<double> k = GetDoubles(node, "intrinsics", path, 4, 4);
  camera.fx = k[0];
  camera.fy = k[1];
  camera.cx = k[2];
  camera.cy = k[3];
  const std::vector<double> size = GetDoubles(node, "resolution", path, 2, 2);
  if (size[0] != std::floor(size[0]) || size[1] != std::floor(size[1]) || size[0] < 1 ||
      size[1] < 1 || size[0] > plausibility::kMaxImageSide ||
      size[1] > plausibility::kMaxImageSide) {
    throw InputError(path, LineOf(node["resolution"]),
                     "resolution must be two whole numbers [width, height] in [1, " +
                         std::to_string(plausibility::kMaxImageSide) + "]");
  }
  camera.width = static_cast<int>(size[0]);
  camera.height = static_cast<int>(size[1]);
  const std::string distortion_model = GetString(node, "distortion_model", path);
  if (const std::optional<DistortionModel> lens = DistortionModelFromName(distortion_model)) {
    camera.model = *lens;
  } else {
    throw InputError(path, LineOf(node["distortion_model"]),
                     "distortion_model '" + distortion_model +
                         "' is not supported (radial-tangential k1 k2 p1 p2 [k3], or equidistant "
                         "k1 k2 k3 k4; names: " +
                         kDistortionModelNames + ")");
  }
  const bool equidistant = camera.model == DistortionModel::kEquidistant;
  const std::vector<double> d = GetDoubles(node, coefficients_key, path, 4, equidistant ? 4 : 5);
  for (size_t i = 0; i < d.size(); ++i) camera.distortion[i] = d[i];
  try {
    camera.Check();
  } catch (const InvalidArgument& e) {
    throw InputError(path, LineOf(node["intrinsics"]), e.what());
  }
  return camera;
}

// A 4x4 transform written as Kalibr does: a list of four rows of four numbers.
Rigid3d GetRowsTransform(const YAML::Node& map, const std::string& key, const std::string& path) {
  const YAML::Node node = Require(map, key, path);
  if (!node.IsSequence() || node.size() != 4) {
    throw InputError(path, LineOf(node), key + ": expected four rows of four numbers");
  }
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    const YAML::Node row = node[static_cast<size_t>(r)];
    if (!row.IsSequence() || row.size() != 4) {
      throw InputError(path, LineOf(row), key + ": expected four rows of four numbers");
    }
    for (int c = 0; c < 4; ++c) {
      m(r, c) =
          ScalarToDouble(row[static_cast<size_t>(c)],
                         key + "[" + std::to_string(r) + "][" + std::to_string(c) + "]", path);
    }
  }
  try {
    return Rigid3d::FromMatrix(m, 1e-6);
  } catch (const InvalidArgument& e) {
    throw InputError(path, LineOf(node), key + " is not a rigid transform: " + e.what());
  }
}

// IMU noise densities and random walks (the same keys in EuRoC's sensor.yaml and Kalibr's
// imu.yaml).
ImuParams ImuNoiseFromYaml(const YAML::Node& node, const std::string& path,
                           const std::string& rate_key) {
  ImuParams params;
  params.gyro_noise_density = GetDouble(node, "gyroscope_noise_density", path);
  params.gyro_random_walk = GetDouble(node, "gyroscope_random_walk", path);
  params.accel_noise_density = GetDouble(node, "accelerometer_noise_density", path);
  params.accel_random_walk = GetDouble(node, "accelerometer_random_walk", path);
  params.rate_hz = GetDouble(node, rate_key, path);
  try {
    params.Check();
  } catch (const InvalidArgument& e) {
    throw InputError(path, e.what());
  }
  return params;
}

// Kalibr's timeshift_cam_imu (t_imu = t_cam + shift, seconds) when the node has it, else 0.
double TimeshiftCamImu(const YAML::Node& node, const std::string& path) {
  const YAML::Node shift = node["timeshift_cam_imu"];
  if (!shift.IsDefined() || shift.IsNull()) return 0.0;
  const double seconds = ScalarToDouble(shift, "timeshift_cam_imu", path);
  if (std::abs(seconds) > 1.0) {
    throw InputError(path, LineOf(shift),
                     "timeshift_cam_imu is " + shift.Scalar() +
                         " s: a camera-IMU time offset beyond 1 s is not a calibration");
  }
  return seconds;
}

}  // namespace

EurocCameraSensor ReadEurocCameraSensor(const std::string& path) {
  const YAML::Node root = LoadOpenCvYaml(path);
  EurocCameraSensor sensor;
  sensor.camera = CameraFromYaml(root, path, "distortion_coefficients");
  sensor.body_from_sensor = GetTransform(root, "T_BS", path);
  sensor.rate_hz = GetDouble(root, "rate_hz", path);
  if (sensor.rate_hz <= 0) throw InputError(path, LineOf(root["rate_hz"]), "rate_hz must be > 0");
  // Not one of EuRoC's keys: a user's, as Kalibr names it (what eval and track advise to set).
  sensor.timeshift_cam_imu_s = TimeshiftCamImu(root, path);
  return sensor;
}

EurocCameraSensor ReadKalibrCamchain(const std::string& path, const std::string& camera) {
  const YAML::Node root = LoadOpenCvYaml(path);
  const YAML::Node node = Require(root, camera, path);
  if (!node.IsMap()) throw InputError(path, LineOf(node), camera + ": expected a mapping");
  EurocCameraSensor sensor;
  sensor.camera = CameraFromYaml(node, path, "distortion_coeffs");
  // T_cam_imu takes IMU coordinates to the camera's; the body is the IMU.
  sensor.body_from_sensor = GetRowsTransform(node, "T_cam_imu", path).Inverse();
  sensor.timeshift_cam_imu_s = TimeshiftCamImu(node, path);
  return sensor;
}

PinholeCamera ReadYamlCamera(const std::string& path) {
  const YAML::Node cam0 = LoadOpenCvYaml(path)["cam0"];
  if (cam0.IsDefined() && cam0.IsMap()) return ReadKalibrCamchain(path).camera;
  return ReadEurocCameraSensor(path).camera;
}

EurocImuSensor ReadKalibrImu(const std::string& path) {
  const YAML::Node root = LoadOpenCvYaml(path);
  const YAML::Node imu0 = root["imu0"];
  EurocImuSensor sensor;
  sensor.params =
      ImuNoiseFromYaml(imu0.IsDefined() && imu0.IsMap() ? imu0 : root, path, "update_rate");
  return sensor;
}

EurocImuSensor ReadEurocImuSensor(const std::string& path) {
  const YAML::Node root = LoadOpenCvYaml(path);
  EurocImuSensor sensor;
  sensor.params = ImuNoiseFromYaml(root, path, "rate_hz");
  sensor.body_from_sensor = GetTransform(root, "T_BS", path);
  return sensor;
}

EurocDepthSensor ReadEurocDepthSensor(const std::string& path) {
  const YAML::Node root = LoadOpenCvYaml(path);
  EurocDepthSensor sensor;
  sensor.depth_scale = GetDouble(root, "depth_scale", path);
  if (sensor.depth_scale <= 0) {
    throw InputError(
        path, LineOf(root["depth_scale"]),
        "depth_scale must be > 0 (raw depth units per metre), got " + root["depth_scale"].Scalar());
  }
  // Absent means cam0: the layout only defines depth on cam0's grid.
  if (const YAML::Node node = root["registered_to"]; node.IsDefined() && !node.IsNull()) {
    sensor.registered_to = GetString(root, "registered_to", path);
    if (sensor.registered_to != "cam0") {
      throw InputError(path, LineOf(node),
                       "registered_to '" + sensor.registered_to +
                           "' is not supported (depth0 must be registered to cam0)");
    }
  }
  return sensor;
}

namespace {

// Rows "timestamp [ns], p x y z, q w x y z" and `extra` more numbers, timestamps strictly
// increasing (a unit quaternion, w first; a plausible position): row(t_ns, pose, extra numbers,
// line) for each. Both of the layout's pose files (the estimator's states, a pose sensor's).
template <typename Row>
void ForEachPoseRow(const std::string& path, size_t extra, const char* columns, Row&& row) {
  int64_t previous_t = 0;
  int previous_line = 0;
  std::vector<double> v(7 + extra);
  for (const TextLine& line : ReadTextFields(path, FieldSeparator::kComma)) {
    CheckFieldCount(line, 8 + extra, path, columns);
    const int64_t t_ns = ParseNsField(line.fields[0], path, line.line);
    if (previous_line > 0) {
      CheckIncreasingTimestamp(previous_t, previous_line, t_ns, path, line.line);
    }
    for (size_t i = 0; i < v.size(); ++i) {
      v[i] =
          ParseFiniteDouble(line.fields[i + 1], path, line.line, "field " + std::to_string(i + 2));
    }
    Rigid3d pose;
    pose.translation = Eigen::Vector3d(v[0], v[1], v[2]);
    pose.rotation = CheckedUnitQuaternion(v[3], v[4], v[5], v[6], path, line.line);
    plausibility::CheckPosition(pose.translation, path, line.line);
    row(t_ns, pose, v.data() + 7, line.line);
    previous_t = t_ns;
    previous_line = line.line;
  }
}

}  // namespace

std::vector<EurocGroundTruthState> ReadEurocGroundTruth(const std::string& path) {
  std::vector<EurocGroundTruthState> states;
  ForEachPoseRow(path, 9, "timestamp, p x y z, q w x y z, v x y z, bw x y z, ba x y z",
                 [&](int64_t t_ns, const Rigid3d& pose, const double* v, int line) {
                   EurocGroundTruthState s;
                   s.t_ns = t_ns;
                   s.world_from_body = pose;
                   s.velocity_in_world = Eigen::Vector3d(v[0], v[1], v[2]);
                   plausibility::CheckVelocity(s.velocity_in_world, path, line);
                   s.gyro_bias = Eigen::Vector3d(v[3], v[4], v[5]);
                   s.accel_bias = Eigen::Vector3d(v[6], v[7], v[8]);
                   states.push_back(s);
                 });
  return states;
}

std::vector<StampedPose> ReadEurocPoses(const std::string& path) {
  std::vector<StampedPose> poses;
  ForEachPoseRow(path, 0, "timestamp, p x y z, q w x y z",
                 [&](int64_t t_ns, const Rigid3d& pose, const double*, int) {
                   poses.push_back({t_ns, pose});
                 });
  return poses;
}

std::vector<EurocGroundTruthState> GroundTruthFromPoses(
    const std::vector<StampedPose>& world_from_sensor, const Rigid3d& body_from_sensor,
    int64_t half_window_ns) {
  IMUMATCH_CHECK(half_window_ns > 0, "half_window_ns=" << half_window_ns);
  const Rigid3d sensor_from_body = body_from_sensor.Inverse();
  std::vector<EurocGroundTruthState> states(world_from_sensor.size());
  for (size_t i = 0; i < states.size(); ++i) {
    states[i].t_ns = world_from_sensor[i].t_ns;
    states[i].world_from_body = world_from_sensor[i].world_from_body * sensor_from_body;
  }
  // The slope of a straight line through the positions within the window (times relative to the
  // sample's own, in seconds, so that large timestamps lose no precision).
  size_t lo = 0, hi = 0;
  for (size_t i = 0; i < states.size(); ++i) {
    const int64_t t = states[i].t_ns;
    while (states[lo].t_ns < t - half_window_ns) ++lo;
    while (hi + 1 < states.size() && states[hi + 1].t_ns <= t + half_window_ns) ++hi;
    if (lo == i || hi == i) {
      states[i].velocity_in_world.setConstant(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    double mean_t = 0.0;
    Eigen::Vector3d mean_p = Eigen::Vector3d::Zero();
    for (size_t j = lo; j <= hi; ++j) {
      mean_t += 1e-9 * static_cast<double>(states[j].t_ns - t);
      mean_p += states[j].world_from_body.translation;
    }
    const double n = static_cast<double>(hi - lo + 1);
    mean_t /= n;
    mean_p /= n;
    double stt = 0.0;
    Eigen::Vector3d stp = Eigen::Vector3d::Zero();
    for (size_t j = lo; j <= hi; ++j) {
      const double dt = 1e-9 * static_cast<double>(states[j].t_ns - t) - mean_t;
      stt += dt * dt;
      stp += dt * (states[j].world_from_body.translation - mean_p);
    }
    states[i].velocity_in_world = stp / stt;
  }
  return states;
}

std::string FindEurocMav0(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::path(path).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();  // trailing slash
  if (fs::is_directory(p / "mav0", ec)) return (p / "mav0").string();
  if (fs::exists(p / "imu0" / "data.csv", ec) || fs::exists(p / "cam0" / "data.csv", ec)) {
    return p.string();
  }
  return "";
}

EurocSequence ReadEurocSequence(const std::string& path, const ImuBufferOptions& options) {
  const std::string mav0 = FindEurocMav0(path);
  if (mav0.empty()) {
    throw InputError(path, "not a EuRoC folder (expected mav0/ or imu0/ and cam0/ inside)");
  }
  EurocSequence seq;
  seq.mav0 = mav0;
  // Calibration: EuRoC's sensor.yaml files, else Kalibr's files beside mav0 or in its dso/ folder
  // (TUM-VI's exports keep them there).
  std::error_code ec;
  const fs::path above = fs::path(mav0).parent_path();
  const auto first_existing = [&](std::initializer_list<fs::path> paths) -> std::string {
    for (const fs::path& p : paths) {
      if (fs::is_regular_file(p, ec)) return p.string();
    }
    return "";
  };
  const std::string cam_yaml = mav0 + "/cam0/sensor.yaml";
  const std::string camchain =
      first_existing({above / "dso" / "camchain.yaml", above / "camchain.yaml"});
  if (fs::exists(cam_yaml, ec) || camchain.empty()) {
    seq.cam0 = ReadEurocCameraSensor(cam_yaml);
    seq.cam0_calibration_file = cam_yaml;
  } else {
    seq.cam0 = ReadKalibrCamchain(camchain);
    seq.cam0_calibration_file = camchain;
    seq.kalibr_calibration = true;
  }
  const std::string imu_yaml = mav0 + "/imu0/sensor.yaml";
  const std::string kalibr_imu = first_existing(
      {above / "dso" / "imu_config.yaml", above / "imu_config.yaml", above / "imu.yaml"});
  if (fs::exists(imu_yaml, ec) || kalibr_imu.empty()) {
    seq.imu0 = ReadEurocImuSensor(imu_yaml);
    seq.imu0_calibration_file = imu_yaml;
  } else {
    seq.imu0 = ReadKalibrImu(kalibr_imu);
    seq.imu0_calibration_file = kalibr_imu;
    seq.kalibr_calibration = true;
  }
  seq.images = ReadEurocImageList(mav0 + "/cam0/data.csv");
  seq.imu = ReadEurocImu(mav0 + "/imu0/data.csv", options);
  const std::string gt = mav0 + "/state_groundtruth_estimate0/data.csv";
  if (fs::exists(gt, ec)) {
    seq.groundtruth = ReadEurocGroundTruth(gt);
    seq.groundtruth_source = "state_groundtruth_estimate0";
  } else {
    // A motion-capture body's poses (TUM-VI: mocap0, the IMU's; EuRoC's Vicon rooms: vicon0).
    for (const char* sensor : {"mocap0", "vicon0"}) {
      const std::string folder = mav0 + "/" + sensor;
      if (!fs::exists(folder + "/data.csv", ec)) continue;
      Rigid3d body_from_sensor;
      const std::string yaml = folder + "/sensor.yaml";
      if (fs::exists(yaml, ec)) {
        body_from_sensor = GetTransform(LoadOpenCvYaml(yaml), "T_BS", yaml);
      }
      seq.groundtruth =
          GroundTruthFromPoses(ReadEurocPoses(folder + "/data.csv"), body_from_sensor);
      seq.groundtruth_source = sensor;
      break;
    }
  }
  if (fs::is_directory(mav0 + "/depth0", ec)) {
    seq.depth0 = ReadEurocDepthSensor(mav0 + "/depth0/sensor.yaml");
    const std::string depth_list = mav0 + "/depth0/data.csv";
    seq.depth_images = ReadEurocDepthList(depth_list);
    // Both lists are strictly increasing (checked above), so a binary search finds exact matches.
    for (const StampedFile& d : seq.depth_images) {
      const auto it =
          std::lower_bound(seq.images.begin(), seq.images.end(), d.t_ns,
                           [](const StampedFile& image, int64_t t) { return image.t_ns < t; });
      if (it == seq.images.end() || it->t_ns != d.t_ns) {
        throw InputError(depth_list, d.line,
                         "depth image at t=" + std::to_string(d.t_ns) +
                             " ns has no cam0 frame (depth0 timestamps must equal cam0's)");
      }
    }
  }
  return seq;
}

}  // namespace imumatch
