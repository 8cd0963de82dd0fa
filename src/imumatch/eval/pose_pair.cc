#include "imumatch/eval/pose_pair.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "imumatch/core/error.h"

namespace imumatch {
namespace {

std::string Join(const std::string& dir, const char* name) {
  return (std::filesystem::path(dir) / name).string();
}

Rigid3d ReadSinglePose(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open pose file");
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::vector<double> v;
    std::string token;
    while (fields >> token) {
      try {
        size_t used = 0;
        v.push_back(std::stod(token, &used));
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw InputError(path, line_no, "not a number: '" + token + "'");
      }
      if (!std::isfinite(v.back())) throw InputError(path, line_no, "non-finite value");
    }
    if (v.size() != 7) {
      throw InputError(
          path, line_no,
          "expected 7 numbers (tx ty tz qx qy qz qw), got " + std::to_string(v.size()));
    }
    const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    if (std::abs(q.norm() - 1.0) > 1e-2) {
      throw InputError(path, line_no, "quaternion norm " + std::to_string(q.norm()) + " is not 1");
    }
    return Rigid3d(q, Eigen::Vector3d(v[0], v[1], v[2]));
  }
  throw InputError(path, "no pose line");
}

}  // namespace

bool IsPosePairFolder(const std::string& dir) {
  namespace fs = std::filesystem;
  return fs::exists(Join(dir, "img_prev.png")) && fs::exists(Join(dir, "img_curr.png")) &&
         fs::exists(Join(dir, "pose_prev.txt")) && fs::exists(Join(dir, "pose_curr.txt"));
}

Dataset LoadPosePairFolder(const std::string& dir, const PinholeCamera& camera,
                           int64_t frame_interval_ns) {
  camera.Check();
  IMUMATCH_CHECK(frame_interval_ns > 0, "frame_interval_ns = " << frame_interval_ns);
  Dataset d;
  d.name = std::filesystem::path(dir).filename().string();
  if (d.name.empty()) d.name = std::filesystem::path(dir).parent_path().filename().string();
  d.root = dir;
  d.kind = DatasetKind::kTumRgbd;
  d.camera = camera;
  d.imu_source_note = "no IMU: two-frame excerpt with ground-truth poses only";
  const char* names[2][3] = {{"img_prev.png", "dep_prev.png", "pose_prev.txt"},
                             {"img_curr.png", "dep_curr.png", "pose_curr.txt"}};
  for (int i = 0; i < 2; ++i) {
    FrameRecord f;
    f.t_ns = i * frame_interval_ns;
    f.image_path = Join(dir, names[i][0]);
    if (!std::filesystem::exists(f.image_path)) throw InputError(f.image_path, "missing image");
    const std::string depth = Join(dir, names[i][1]);
    if (std::filesystem::exists(depth)) f.depth_path = depth;
    f.world_from_cam = ReadSinglePose(Join(dir, names[i][2]));
    d.groundtruth_world_from_cam.push_back({f.t_ns, *f.world_from_cam});
    d.frames.push_back(f);
  }
  return d;
}

}  // namespace imumatch
