#include "imumatch/io/synthetic_io.h"

#include <filesystem>
#include <fstream>
#include <optional>

#include <nlohmann/json.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/io/image_io.h"
#include "imumatch/io/imu_io.h"
#include "imumatch/io/output_files.h"
#include "imumatch/io/text_parsing.h"
#include "imumatch/io/trajectory_io.h"

namespace imumatch {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

Json Vec(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

void WriteText(const fs::path& path, const std::string& text) {
  WriteFileAtomic(path.string(), text);
}

void WriteSequence(const SyntheticSequence& seq, const SyntheticSequenceOptions* generated_with,
                   const std::string& dir_name, const SyntheticWriteOptions& write_options) {
  CheckSyntheticWrite(seq, dir_name, write_options);
  const fs::path dir(dir_name);
  std::error_code ec;
  fs::create_directories(dir / "rgb", ec);
  if (ec) throw Error("cannot create folder " + (dir / "rgb").string() + ": " + ec.message());
  fs::create_directories(dir / "depth", ec);
  if (ec) throw Error("cannot create folder " + (dir / "depth").string() + ": " + ec.message());

  std::string rgb_list = "# color images\n# timestamp filename\n";
  std::string depth_list = "# depth images (16-bit, " + FormatDoubleExact(seq.camera.depth_scale) +
                           " per metre, 0 = none)\n# timestamp filename\n";
  std::string velocity = "# IMU velocity in the world at the frame times\n# timestamp vx vy vz\n";
  std::vector<StampedPose> groundtruth;
  for (const SyntheticFrame& f : seq.frames) {
    const std::string t = FormatNsAsSeconds(f.t_ns);
    const std::string rgb_name = "rgb/" + t + ".png";
    IMUMATCH_CHECK(f.rgb.type() == CV_8UC3 || f.rgb.type() == CV_8UC1,
                   "frame " << t << ": rgb must be 8-bit");
    WriteImage((dir / rgb_name).string(), f.rgb);
    rgb_list += t + " " + rgb_name + "\n";
    if (!f.depth.empty()) {
      IMUMATCH_CHECK(f.depth.type() == CV_16UC1, "frame " << t << ": depth must be CV_16UC1");
      const std::string depth_name = "depth/" + t + ".png";
      WriteImage((dir / depth_name).string(), f.depth);
      depth_list += t + " " + depth_name + "\n";
    }
    groundtruth.push_back({f.t_ns, f.world_from_cam});
    velocity += t;
    for (int i = 0; i < 3; ++i) velocity += " " + FormatDoubleExact(f.imu_velocity_in_world[i]);
    velocity += "\n";
  }
  WriteText(dir / "rgb.txt", rgb_list);
  WriteText(dir / "depth.txt", depth_list);
  WriteText(dir / "velocity.txt", velocity);
  WriteTumTrajectory((dir / "groundtruth.txt").string(), groundtruth,
                     "ground truth world_from_cam (camera-to-world), exact");
  WriteImuText((dir / "imu.txt").string(), seq.imu, "simulated IMU (imumatch synth)");

  const PinholeCamera& c = seq.camera;
  // ReadCameraFromText's line: an equidistant lens is named and has k1..k4.
  const bool equidistant = c.model == DistortionModel::kEquidistant;
  std::string camera_txt = equidistant ? "# equidistant fx fy cx cy width height k1 k2 k3 k4\n"
                                       : "# fx fy cx cy width height k1 k2 p1 p2 k3\n";
  if (equidistant) camera_txt += "equidistant ";
  for (double v : {c.fx, c.fy, c.cx, c.cy}) camera_txt += FormatDoubleExact(v) + " ";
  camera_txt += std::to_string(c.width) + " " + std::to_string(c.height);
  for (size_t i = 0; i < (equidistant ? 4u : c.distortion.size()); ++i) {
    camera_txt += " " + FormatDoubleExact(c.distortion[i]);
  }
  WriteText(dir / "camera.txt", camera_txt + "\n");

  Json j;
  j["generator"] = "imumatch synth";
  j["format_version"] = 1;
  j["motion"] = seq.motion;
  j["seed"] = generated_with ? Json(generated_with->imu_seed) : Json(nullptr);
  j["imu_model"] = generated_with ? Json(generated_with->imu_model) : Json(nullptr);
  j["imu_simulated"] = true;
  const ImuParams& p = seq.imu_params;
  j["imu_params"] = {{"gyro_noise_density", p.gyro_noise_density},
                     {"gyro_random_walk", p.gyro_random_walk},
                     {"accel_noise_density", p.accel_noise_density},
                     {"accel_random_walk", p.accel_random_walk},
                     {"rate_hz", p.rate_hz},
                     {"gravity_in_world", Vec(p.gravity_in_world)}};
  j["imu_initial_bias"] = {{"gyro", Vec(seq.imu_initial_bias.gyro)},
                           {"accel", Vec(seq.imu_initial_bias.accel)}};
  const Eigen::Matrix4d m = seq.cam_from_imu.ToMatrix();
  Json rows = Json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  j["cam_from_imu"] = rows;
  j["cam_from_imu_quaternion_wxyz"] = {seq.cam_from_imu.rotation.w(), seq.cam_from_imu.rotation.x(),
                                       seq.cam_from_imu.rotation.y(),
                                       seq.cam_from_imu.rotation.z()};
  j["camera"] = {{"width", c.width},
                 {"height", c.height},
                 {"fx", c.fx},
                 {"fy", c.fy},
                 {"cx", c.cx},
                 {"cy", c.cy},
                 {"distortion_model", ToString(c.model)},
                 {"distortion", c.distortion},
                 {"depth_scale", c.depth_scale}};
  if (generated_with != nullptr) {
    j["frame_rate_hz"] =
        generated_with->frame_times_s.empty() ? Json(generated_with->frame_rate_hz) : Json(nullptr);
    j["depth_noise"] = generated_with->render.depth_noise.add_noise;
    j["depth_holes"] = generated_with->render.depth_noise.add_holes;
    j["t0_ns"] = generated_with->t0_ns;
  }
  j["num_frames"] = seq.frames.size();
  j["num_imu_samples"] = seq.imu.size();
  WriteText(dir / "sequence.json", j.dump(2) + "\n");
}

}  // namespace

void CheckSyntheticWrite(const SyntheticSequence& seq, const std::string& dir_name,
                         const SyntheticWriteOptions& write_options) {
  IMUMATCH_CHECK(!seq.frames.empty(), "the synthetic sequence has no frames");
  for (size_t i = 1; i < seq.frames.size(); ++i) {
    IMUMATCH_CHECK(seq.frames[i].t_ns > seq.frames[i - 1].t_ns,
                   "frame timestamps must increase (frame " << i << ")");
  }
  const fs::path dir(dir_name);
  std::error_code ec;
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec)) throw Error(dir_name + " exists and is not a folder");
    if (!write_options.overwrite && !fs::is_empty(dir, ec)) {
      throw Error("output folder " + dir_name + " is not empty (allow overwriting to replace it)");
    }
  }
}

void WriteSyntheticSequence(const SyntheticSequence& sequence, const std::string& dir,
                            const SyntheticWriteOptions& write_options) {
  WriteSequence(sequence, nullptr, dir, write_options);
}

void WriteSyntheticSequence(const SyntheticSequence& sequence,
                            const SyntheticSequenceOptions& generated_with, const std::string& dir,
                            const SyntheticWriteOptions& write_options) {
  WriteSequence(sequence, &generated_with, dir, write_options);
}

}  // namespace imumatch
