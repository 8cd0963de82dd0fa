#include "imumatch/io/euroc_writer.h"

#include <filesystem>
#include <string>

#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/image_io.h"
#include "imumatch/io/output_files.h"
#include "imumatch/io/text_parsing.h"

namespace imumatch {
namespace {

namespace fs = std::filesystem;

std::string Numbers(const double* values, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += (i > 0 ? ", " : "") + FormatDoubleExact(values[i]);
  return out;
}

std::string TransformYaml(const Rigid3d& body_from_sensor) {
  const Eigen::Matrix4d m = body_from_sensor.ToMatrix();
  std::string out = "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      out += (r > 0 || c > 0 ? ", " : "") + FormatDoubleExact(m(r, c));
    }
  }
  return out + "]\n";
}

void CreateFolder(const fs::path& path) {
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec) throw Error("cannot create folder " + path.string() + ": " + ec.message());
}

}  // namespace

void WriteSyntheticSequenceAsEuroc(const SyntheticSequence& seq, const std::string& dir_name,
                                   const SyntheticWriteOptions& write_options) {
  CheckSyntheticWrite(seq, dir_name, write_options);
  seq.camera.Check();
  const fs::path dir(dir_name);
  const fs::path mav0 = dir / "mav0";
  bool any_depth = false;
  for (const SyntheticFrame& f : seq.frames) any_depth |= !f.depth.empty();
  for (const char* sub : {"cam0/data", "imu0", "state_groundtruth_estimate0"}) {
    CreateFolder(mav0 / sub);
  }
  if (any_depth) CreateFolder(mav0 / "depth0" / "data");

  // Images, depth and ground truth at the frame times.
  std::string cam_list = "#timestamp [ns],filename\n";
  std::string depth_list = cam_list;
  std::string groundtruth =
      "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
      "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
      "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
      "b_a_RS_S_z [m s^-2]\n";
  cv::Mat gray;
  for (const SyntheticFrame& f : seq.frames) {
    const std::string t = std::to_string(f.t_ns);
    IMUMATCH_CHECK(f.rgb.type() == CV_8UC3 || f.rgb.type() == CV_8UC1,
                   "frame " << t << ": the image must be 8-bit");
    if (f.rgb.channels() == 3) {
      cv::cvtColor(f.rgb, gray, cv::COLOR_BGR2GRAY);
    } else {
      gray = f.rgb;
    }
    WriteImage((mav0 / "cam0" / "data" / (t + ".png")).string(), gray);
    cam_list += t + "," + t + ".png\n";
    if (!f.depth.empty()) {
      IMUMATCH_CHECK(f.depth.type() == CV_16UC1, "frame " << t << ": depth must be CV_16UC1");
      WriteImage((mav0 / "depth0" / "data" / (t + ".png")).string(), f.depth);
      depth_list += t + "," + t + ".png\n";
    }
    const Eigen::Quaterniond& q = f.world_from_imu.rotation;
    const double state[16] = {f.world_from_imu.translation.x(),
                              f.world_from_imu.translation.y(),
                              f.world_from_imu.translation.z(),
                              q.w(),
                              q.x(),
                              q.y(),
                              q.z(),
                              f.imu_velocity_in_world.x(),
                              f.imu_velocity_in_world.y(),
                              f.imu_velocity_in_world.z(),
                              seq.imu_initial_bias.gyro.x(),
                              seq.imu_initial_bias.gyro.y(),
                              seq.imu_initial_bias.gyro.z(),
                              seq.imu_initial_bias.accel.x(),
                              seq.imu_initial_bias.accel.y(),
                              seq.imu_initial_bias.accel.z()};
    groundtruth += t + "," + Numbers(state, 16) + "\n";
  }
  WriteFileAtomic((mav0 / "cam0" / "data.csv").string(), cam_list);
  if (any_depth) WriteFileAtomic((mav0 / "depth0" / "data.csv").string(), depth_list);
  WriteFileAtomic((mav0 / "state_groundtruth_estimate0" / "data.csv").string(), groundtruth);

  std::string imu =
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
      "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  for (const ImuSample& s : seq.imu) {
    const double values[6] = {s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z(),
                              s.accel_m_s2.x(), s.accel_m_s2.y(), s.accel_m_s2.z()};
    imu += std::to_string(s.t_ns) + "," + Numbers(values, 6) + "\n";
  }
  WriteFileAtomic((mav0 / "imu0" / "data.csv").string(), imu);

  // Sensors: the body is the IMU (EuRoC's convention).
  const PinholeCamera& c = seq.camera;
  const bool equidistant = c.model == DistortionModel::kEquidistant;
  double rate_hz = 1.0;  // one frame has no rate; readers require a positive one
  if (seq.frames.size() >= 2) {
    rate_hz = 1e9 * static_cast<double>(seq.frames.size() - 1) /
              static_cast<double>(seq.frames.back().t_ns - seq.frames.front().t_ns);
  }
  const double intrinsics[4] = {c.fx, c.fy, c.cx, c.cy};
  const std::string cam_yaml =
      "# imumatch synth: a synthetic camera (exact intrinsics; the images are rendered through "
      "its lens)\nsensor_type: camera\ncomment: imumatch synthetic cam0\n\n" +
      TransformYaml(seq.cam_from_imu.Inverse()) + "\nrate_hz: " + FormatDoubleExact(rate_hz) +
      "\nresolution: [" + std::to_string(c.width) + ", " + std::to_string(c.height) +
      "]\ncamera_model: pinhole\nintrinsics: [" + Numbers(intrinsics, 4) +
      "] # fu, fv, cu, cv\ndistortion_model: " + ToString(c.model) +
      "\ndistortion_coefficients: [" +
      Numbers(c.distortion.data(), equidistant || c.distortion[4] == 0.0 ? 4 : 5) + "]\n";
  WriteFileAtomic((mav0 / "cam0" / "sensor.yaml").string(), cam_yaml);
  const ImuParams& p = seq.imu_params;
  const std::string imu_yaml =
      "# imumatch synth: the simulated IMU's noise model\nsensor_type: imu\ncomment: imumatch "
      "simulated IMU\n\n" +
      TransformYaml(Rigid3d()) + "rate_hz: " + FormatDoubleExact(p.rate_hz) +
      "\n\ngyroscope_noise_density: " + FormatDoubleExact(p.gyro_noise_density) +
      "\ngyroscope_random_walk: " + FormatDoubleExact(p.gyro_random_walk) +
      "\naccelerometer_noise_density: " + FormatDoubleExact(p.accel_noise_density) +
      "\naccelerometer_random_walk: " + FormatDoubleExact(p.accel_random_walk) + "\n";
  WriteFileAtomic((mav0 / "imu0" / "sensor.yaml").string(), imu_yaml);
  if (any_depth) {
    WriteFileAtomic(
        (mav0 / "depth0" / "sensor.yaml").string(),
        "# Exact depth rendered on cam0's pixel grid at cam0's timestamps: uint16 PNG,\n"
        "# value / depth_scale = depth along the optical axis in metres, 0 = none.\n"
        "sensor_type: depth\nregistered_to: cam0\ndepth_scale: " +
            FormatDoubleExact(c.depth_scale) + "\n");
  }
  WriteFileAtomic((mav0 / "body.yaml").string(), "comment: imumatch synthetic body (the IMU)\n");
}

}  // namespace imumatch
