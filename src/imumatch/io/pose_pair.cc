#include "imumatch/io/pose_pair.h"

#include <filesystem>

#include "imumatch/core/error.h"
#include "imumatch/io/trajectory_io.h"

namespace imumatch {
namespace {

std::string Join(const std::string& dir, const char* name) {
  return (std::filesystem::path(dir) / name).string();
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
    f.world_from_cam = ReadTumPose(Join(dir, names[i][2]));
    d.groundtruth_world_from_cam.push_back({f.t_ns, *f.world_from_cam});
    d.frames.push_back(f);
  }
  return d;
}

Dataset LoadDatasetOrPosePair(const std::string& path, const DatasetOptions& options) {
  if (!IsPosePairFolder(path)) return LoadDataset(path, options);
  if (options.timeshift_cam_imu_s) {
    throw InvalidArgument(path +
                          ": a timeshift_cam_imu applies to EuRoC/ASL recordings; this is a "
                          "two-frame pose pair, without an IMU");
  }
  return options.camera ? LoadPosePairFolder(path, *options.camera) : LoadPosePairFolder(path);
}

}  // namespace imumatch
