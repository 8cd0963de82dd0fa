#include "imumatch/io/synthetic_io.h"

#include <array>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/dataset.h"
#include "imumatch/io/euroc_writer.h"
#include "imumatch/io/image_io.h"
#include "imumatch/io/io_test_util.h"
#include "imumatch/io/text_parsing.h"

namespace imumatch {
namespace {

using testing::ExpectInputError;
using testing::TempDir;

// A small, fast sequence: 80x60 camera, 10 fps, coarse textures, noisy depth and IMU.
struct Small {
  SyntheticSequenceOptions options;
  SyntheticSequence sequence;
};
const Small& SmallSequence() {
  static const Small small = [] {
    Small s;
    s.options.motion = "left30";
    s.options.motion_options.duration_s = 0.5;
    s.options.motion_options.still_before_s = 0.2;
    s.options.motion_options.still_after_s = 0.1;
    s.options.frame_rate_hz = 10.0;
    s.options.camera = PinholeCamera::KinectDefault();
    s.options.camera.width = 80;
    s.options.camera.height = 60;
    s.options.camera.fx = s.options.camera.fy = 65.625;
    s.options.camera.cx = 39.5;
    s.options.camera.cy = 29.5;
    s.options.imu_model = "mems";
    s.options.imu_seed = 42;
    s.options.imu_initial_bias.gyro = Eigen::Vector3d(0.01, -0.02, 0.003);
    s.options.t0_ns = 1'000'000'123;
    s.options.render.depth_noise.add_noise = true;
    SceneOptions scene_options;
    scene_options.texel_size_m = 0.04;
    s.sequence = MakeSyntheticSequence(s.options, Scene(scene_options));
    return s;
  }();
  return small;
}

// The IMU read back, sample by sample, bit for bit (both layouts write the samples exactly).
void ExpectTheSameImu(const Dataset& d, const SyntheticSequence& seq) {
  ASSERT_EQ(d.imu.size(), seq.imu.size());
  for (size_t i = 0; i < seq.imu.size(); ++i) {
    EXPECT_EQ(d.imu.samples()[i].t_ns, seq.imu[i].t_ns);
    EXPECT_EQ(d.imu.samples()[i].gyro_rad_s, seq.imu[i].gyro_rad_s);
    EXPECT_EQ(d.imu.samples()[i].accel_m_s2, seq.imu[i].accel_m_s2);
  }
}

TEST(SyntheticIo, WriteThenLoadRoundTripsExactly) {
  const Small& small = SmallSequence();
  const SyntheticSequence& seq = small.sequence;
  ASSERT_GE(seq.frames.size(), 8u);
  TempDir dir;
  const std::string root = dir.Path("left30");
  WriteSyntheticSequence(seq, small.options, root);

  const Dataset d = LoadDataset(root);
  EXPECT_EQ(d.kind, DatasetKind::kSynthetic);
  EXPECT_EQ(d.name, "left30");
  EXPECT_TRUE(d.imu_simulated);
  EXPECT_NE(d.imu_source_note.find("seed 42"), std::string::npos) << d.imu_source_note;
  EXPECT_NE(d.imu_source_note.find("left30"), std::string::npos) << d.imu_source_note;
  // Camera, extrinsic and IMU model.
  EXPECT_EQ(d.camera.width, 80);
  EXPECT_EQ(d.camera.fx, seq.camera.fx);
  EXPECT_EQ(d.camera.cy, seq.camera.cy);
  EXPECT_EQ(d.camera.depth_scale, seq.camera.depth_scale);
  EXPECT_LT((d.cam_from_imu.translation - seq.cam_from_imu.translation).norm(), 1e-15);
  EXPECT_LT(RotationDistance(d.cam_from_imu.rotation, seq.cam_from_imu.rotation), 1e-15);
  EXPECT_EQ(d.imu_params.gyro_noise_density, seq.imu_params.gyro_noise_density);
  EXPECT_EQ(d.imu_params.accel_random_walk, seq.imu_params.accel_random_walk);
  EXPECT_EQ(d.imu_params.rate_hz, seq.imu_params.rate_hz);
  EXPECT_EQ(d.imu_params.gravity_in_world, seq.imu_params.gravity_in_world);
  // Frames: timestamps, exact poses, velocities, identical images.
  ASSERT_EQ(d.frames.size(), seq.frames.size());
  ASSERT_EQ(d.groundtruth_world_from_cam.size(), seq.frames.size());
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const SyntheticFrame& f = seq.frames[i];
    const FrameRecord& r = d.frames[i];
    EXPECT_EQ(r.t_ns, f.t_ns);
    ASSERT_TRUE(r.world_from_cam.has_value());
    EXPECT_LT((r.world_from_cam->translation - f.world_from_cam.translation).norm(), 1e-9);
    EXPECT_LT(RotationDistance(r.world_from_cam->rotation, f.world_from_cam.rotation), 1e-9);
    ASSERT_TRUE(r.imu_velocity_in_world.has_value());
    EXPECT_EQ(*r.imu_velocity_in_world, f.imu_velocity_in_world);
    const cv::Mat rgb = LoadImage(r.image_path, ImageColor::kColor);
    const cv::Mat depth = LoadDepth(r.depth_path, rgb.size());
    EXPECT_EQ(cv::norm(rgb, f.rgb, cv::NORM_INF), 0.0) << r.image_path;
    EXPECT_EQ(cv::norm(depth, f.depth, cv::NORM_INF), 0.0) << r.depth_path;
  }
  ExpectTheSameImu(d, seq);
  // sequence.json says what made it.
  const nlohmann::json j = nlohmann::json::parse(ReadFileToString(root + "/sequence.json"));
  EXPECT_EQ(j.at("generator"), "imumatch synth");
  EXPECT_EQ(j.at("motion"), "left30");
  EXPECT_EQ(j.at("seed"), 42);
  EXPECT_EQ(j.at("imu_model"), "mems");
  EXPECT_EQ(j.at("imu_simulated"), true);
  EXPECT_EQ(j.at("depth_noise"), true);
  EXPECT_EQ(j.at("cam_from_imu").size(), 4u);
  // camera.txt is readable by the camera module, and as written it agrees with sequence.json.
  EXPECT_EQ(ReadCameraFromText(root + "/camera.txt").fx, seq.camera.fx);
  EXPECT_TRUE(d.warnings.empty()) << ::testing::PrintToString(d.warnings);
  // Edited by hand, it is not used (the folder's camera is sequence.json's), and that is said.
  dir.Write("left30/camera.txt", "50 60 39.5 29.5 80 60 0 0 0 0 0\n");
  const Dataset edited = LoadDataset(root);
  EXPECT_EQ(edited.camera.fx, seq.camera.fx);
  ASSERT_EQ(edited.warnings.size(), 1u);
  EXPECT_NE(edited.warnings[0].find("camera.txt differs from sequence.json's camera"),
            std::string::npos)
      << edited.warnings[0];
  dir.Write("left30/camera.txt", "50 0 39.5\n");
  const Dataset broken = LoadDataset(root);
  ASSERT_EQ(broken.warnings.size(), 1u);
  EXPECT_NE(broken.warnings[0].find("camera.txt:"), std::string::npos) << broken.warnings[0];
  EXPECT_NE(broken.warnings[0].find("the camera used is sequence.json's"), std::string::npos)
      << broken.warnings[0];
}

// A lens survives the round trip: camera.txt names an equidistant lens and gives its k1..k4,
// a radial-tangential one its five coefficients; sequence.json states the model.
TEST(SyntheticIo, TheLensRoundTrips) {
  for (const DistortionModel model :
       {DistortionModel::kRadialTangential, DistortionModel::kEquidistant}) {
    SyntheticSequence seq = SmallSequence().sequence;
    seq.camera.model = model;
    seq.camera.distortion = model == DistortionModel::kEquidistant
                                ? std::array<double, 5>{-0.02, 0.01, -0.004, 0.0005, 0.0}
                                : std::array<double, 5>{-0.28, 0.07, 2e-4, -3e-5, 0.01};
    TempDir dir;
    const std::string root = dir.Path("lens");
    WriteSyntheticSequence(seq, SmallSequence().options, root);
    const Dataset d = LoadDataset(root);
    EXPECT_EQ(d.camera.model, model);
    EXPECT_EQ(d.camera.distortion, seq.camera.distortion) << ToString(model);
    EXPECT_EQ(d.camera.fx, seq.camera.fx);
    const nlohmann::json j = nlohmann::json::parse(ReadFileToString(root + "/sequence.json"));
    EXPECT_EQ(j.at("camera").at("distortion_model"), ToString(model));
  }
}

// The EuRoC layout: imumatch's own EuRoC reader gets back the same camera (lens included),
// extrinsic, IMU samples bit for bit, frames with their exact poses, velocities and depth, and
// the gray image that reading the TUM-style folder gives.
TEST(SyntheticIo, EurocLayoutRoundTripsThroughTheEurocReader) {
  SyntheticSequence seq = SmallSequence().sequence;
  seq.camera.model = DistortionModel::kEquidistant;
  seq.camera.distortion = {-0.02, 0.01, -0.004, 0.0005, 0.0};
  seq.cam_from_imu =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())),
              Eigen::Vector3d(0.01, -0.06, 0.02));
  TempDir dir;
  const std::string root = dir.Path("euroc");
  WriteSyntheticSequenceAsEuroc(seq, root);
  const Dataset d = LoadDataset(root);
  EXPECT_EQ(d.kind, DatasetKind::kEuroc);
  EXPECT_EQ(d.camera.model, DistortionModel::kEquidistant);
  EXPECT_EQ(d.camera.distortion, seq.camera.distortion);
  EXPECT_EQ(d.camera.fx, seq.camera.fx);
  EXPECT_EQ(d.camera.cy, seq.camera.cy);
  EXPECT_EQ(d.camera.width, seq.camera.width);
  EXPECT_EQ(d.camera.depth_scale, seq.camera.depth_scale);
  EXPECT_LT((d.cam_from_imu.translation - seq.cam_from_imu.translation).norm(), 1e-12);
  EXPECT_LT(RotationDistance(d.cam_from_imu.rotation, seq.cam_from_imu.rotation), 1e-12);
  EXPECT_EQ(d.imu_params.gyro_noise_density, seq.imu_params.gyro_noise_density);
  EXPECT_EQ(d.imu_params.accel_random_walk, seq.imu_params.accel_random_walk);
  ExpectTheSameImu(d, seq);
  ASSERT_EQ(d.frames.size(), seq.frames.size());
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const SyntheticFrame& f = seq.frames[i];
    const FrameRecord& r = d.frames[i];
    EXPECT_EQ(r.t_ns, f.t_ns);
    ASSERT_TRUE(r.world_from_cam.has_value());
    // The IMU's pose is what EuRoC records; the camera's follows from the changed extrinsic.
    const Rigid3d world_from_cam = f.world_from_imu * seq.cam_from_imu.Inverse();
    EXPECT_LT((r.world_from_cam->translation - world_from_cam.translation).norm(), 1e-9);
    EXPECT_LT(RotationDistance(r.world_from_cam->rotation, world_from_cam.rotation), 1e-9);
    ASSERT_TRUE(r.imu_velocity_in_world.has_value());
    EXPECT_LT((*r.imu_velocity_in_world - f.imu_velocity_in_world).norm(), 1e-12);
    const cv::Mat gray = LoadImage(r.image_path, ImageColor::kGray);
    cv::Mat expected;
    cv::cvtColor(f.rgb, expected, cv::COLOR_BGR2GRAY);
    EXPECT_EQ(cv::norm(gray, expected, cv::NORM_INF), 0.0) << r.image_path;
    const cv::Mat depth = LoadDepth(r.depth_path, gray.size());
    EXPECT_EQ(cv::norm(depth, f.depth, cv::NORM_INF), 0.0) << r.depth_path;
  }
  // Not over a sequence that is there, unless asked.
  EXPECT_THROW(WriteSyntheticSequenceAsEuroc(seq, root), Error);
  WriteSyntheticSequenceAsEuroc(seq, root, {/*overwrite=*/true});
  // One frame (no frame rate to state) still makes a readable folder.
  seq.frames.resize(1);
  WriteSyntheticSequenceAsEuroc(seq, root, {/*overwrite=*/true});
  EXPECT_EQ(LoadDataset(root).frames.size(), 1u);
}

TEST(SyntheticIo, RefusesNonEmptyFolderUnlessOverwrite) {
  const Small& small = SmallSequence();
  TempDir dir;
  dir.Write("out/keep.txt", "x");
  EXPECT_THROW(WriteSyntheticSequence(small.sequence, dir.Path("out")), Error);
  SyntheticWriteOptions overwrite;
  overwrite.overwrite = true;
  WriteSyntheticSequence(small.sequence, dir.Path("out"), overwrite);
  const Dataset d = LoadDataset(dir.Path("out"));
  EXPECT_EQ(d.frames.size(), small.sequence.frames.size());
  // Without the generating options the note still names the generator.
  EXPECT_NE(d.imu_source_note.find("imumatch synth"), std::string::npos);
}

TEST(SyntheticIo, MalformedSequenceJson) {
  const Small& small = SmallSequence();
  TempDir dir;
  const std::string root = dir.Path("seq");
  WriteSyntheticSequence(small.sequence, root);
  const std::string json = root + "/sequence.json";
  dir.Write("seq/sequence.json", "{\n  \"generator\": \"imumatch synth\",\n  \"motion\": ,\n}\n");
  ExpectInputError([&] { LoadDataset(root); }, json, 3, "JSON syntax error");
  dir.Write("seq/sequence.json", "{\"generator\": \"something else\"}\n");
  ExpectInputError([&] { LoadDataset(root); }, json, 0, "not an imumatch synthetic sequence");
  dir.Write("seq/sequence.json", "{\"generator\": \"imumatch synth\"}\n");
  ExpectInputError([&] { LoadDataset(root); }, json, 0, "missing key 'camera'");
  // A lens model by an unknown name.
  WriteSyntheticSequence(small.sequence, small.options, root, {/*overwrite=*/true});
  nlohmann::json j = nlohmann::json::parse(ReadFileToString(json));
  j["camera"]["distortion_model"] = "kb8";
  dir.Write("seq/sequence.json", j.dump(2));
  ExpectInputError([&] { LoadDataset(root); }, json, 0, "camera.distortion_model must be one of");
}

TEST(SyntheticIo, CorruptImuFileNamesLine) {
  const Small& small = SmallSequence();
  TempDir dir;
  const std::string root = dir.Path("seq");
  WriteSyntheticSequence(small.sequence, small.options, root);
  // Line 3 is the first sample (two comment lines); duplicate it as line 4.
  std::string imu = ReadFileToString(root + "/imu.txt");
  size_t first = 0;
  for (int i = 0; i < 2; ++i) first = imu.find('\n', first) + 1;
  const size_t end = imu.find('\n', first) + 1;
  imu.insert(end, imu.substr(first, end - first));
  dir.Write("seq/imu.txt", imu);
  ExpectInputError([&] { LoadDataset(root); }, root + "/imu.txt", 4, "duplicate");
}

}  // namespace
}  // namespace imumatch
