#include "imumatch/io/dataset.h"

#include <string>

#include <gtest/gtest.h>

#include "imumatch/io/io_test_util.h"
#include "imumatch/testing/test_data.h"

// What a loader says about an input it can read but that is not what its owner may think: frames
// dropped by association, IMU gaps, a rate other than the calibration's, unused or empty files.
namespace imumatch {
namespace {

// A TUM RGB-D folder with dummy image files (not decoded while loading).
void WriteTumFolder(const testing::TempDir& dir, int rgb_frames, int depth_frames) {
  std::string rgb, depth, gt;
  for (int i = 0; i < rgb_frames; ++i) {
    const std::string t = std::to_string(1.0 + 0.1 * i);
    rgb += t + " rgb/" + std::to_string(i) + ".png\n";
    dir.Write("tum/rgb/" + std::to_string(i) + ".png", "x");
    if (i < depth_frames) {
      depth += t + " depth/" + std::to_string(i) + ".png\n";
      dir.Write("tum/depth/" + std::to_string(i) + ".png", "x");
    }
  }
  for (int i = 0; i < 20; ++i) {
    gt += std::to_string(0.95 + 0.05 * i) + " " + std::to_string(0.01 * i) + " 0 0 0 0 0 1\n";
  }
  dir.Write("tum/rgb.txt", rgb);
  dir.Write("tum/depth.txt", depth);
  dir.Write("tum/groundtruth.txt", gt);
}

TEST(DatasetWarnings, FramesDroppedByAssociationAreSaid) {
  testing::TempDir dir;
  WriteTumFolder(dir, 16, 6);
  const Dataset d = LoadDataset(dir.Path("tum"));
  EXPECT_EQ(d.frames.size(), 6u);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("10 of 16 frames"), std::string::npos) << d.warnings[0];
  EXPECT_NE(d.warnings[0].find("rgb.txt:7"), std::string::npos) << d.warnings[0];
}

TEST(DatasetWarnings, AnUnusedAccelerometerFileWithABadRowDoesNotBlock) {
  testing::TempDir dir;
  WriteTumFolder(dir, 4, 4);
  dir.Write("tum/accelerometer.txt", "1.0 0 0 9.8\n1.1 0 zero 9.8\n");
  const Dataset d = LoadDataset(dir.Path("tum"));
  EXPECT_EQ(d.frames.size(), 4u);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("accelerometer.txt:2"), std::string::npos) << d.warnings[0];
}

TEST(DatasetWarnings, GapsInTheImuLogAreSaidWithTheirLine) {
  TempDir dir;
  const EurocDepthFolder f = MakeEurocDepthFolder(dir);
  // Samples every 5 ms from 0.95 s but those of 1.005-1.07 s: 75 ms without one before line 12.
  std::string imu;
  for (int i = 0; i <= 40; ++i) {
    if (i > 10 && i < 25) continue;
    imu += std::to_string(950000000 + 5000000 * i) + ",0,0,0.1,0,0,9.81\n";
  }
  dir.Write("MH_depth/mav0/imu0/data.csv", imu);
  const Dataset d = LoadDataset(f.root);
  ASSERT_EQ(d.imu.Gaps().size(), 1u);
  bool said = false;
  for (const std::string& w : d.warnings) {
    if (w.find("imu0/data.csv:12: the IMU log has 1 gap longer than 50.0 ms") !=
            std::string::npos &&
        w.find("the longest 75.0 ms") != std::string::npos) {
      said = true;
    }
  }
  EXPECT_TRUE(said) << ::testing::PrintToString(d.warnings);
}

TEST(DatasetWarnings, AnImuRecordedAtAnotherRateThanItsCalibrationSaysIsSaid) {
  TempDir dir;
  const EurocDepthFolder f = MakeEurocDepthFolder(dir);
  // The fixture's samples come every 5 ms, as the real sensor.yaml's rate_hz (200) says: no word.
  const Dataset at_rate = LoadDataset(f.root);
  EXPECT_DOUBLE_EQ(at_rate.imu_params.rate_hz, 200.0);
  for (const std::string& w : at_rate.warnings)
    EXPECT_EQ(w.find("rate_hz"), std::string::npos) << w;
  // Every 10 ms, with a few milliseconds of jitter: 100 Hz recorded against 200 Hz stated.
  std::string imu;
  for (int i = 0; i <= 20; ++i) {
    const int jitter_ns = (i % 3 == 1) ? 300000 : 0;
    imu += std::to_string(950000000 + 10000000 * i + jitter_ns) + ",0,0,0.1,0,0,9.81\n";
  }
  dir.Write("MH_depth/mav0/imu0/data.csv", imu);
  const Dataset d = LoadDataset(f.root);
  EXPECT_NEAR(d.imu_params.rate_hz, 100.0, 1e-9);
  // The calibration's densities stay: only the rate that discretises them changes.
  EXPECT_DOUBLE_EQ(d.imu_params.gyro_noise_density, at_rate.imu_params.gyro_noise_density);
  bool said = false;
  for (const std::string& w : d.warnings) {
    if (w.find("imu0/data.csv: the IMU samples come at 100.0 Hz (median interval 10.0 ms) but "
               "its calibration says rate_hz 200") != std::string::npos) {
      said = true;
    }
  }
  EXPECT_TRUE(said) << ::testing::PrintToString(d.warnings);
}

TEST(DatasetWarnings, AGroundTruthFileWithoutPosesIsSaid) {
  TempDir dir;
  const EurocDepthFolder f = MakeEurocDepthFolder(dir);
  dir.Write("MH_depth/mav0/state_groundtruth_estimate0/data.csv",
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w []\n");
  const Dataset d = LoadDataset(f.root);
  EXPECT_TRUE(d.groundtruth_world_from_cam.empty());
  bool said = false;
  for (const std::string& w : d.warnings) {
    said |= w.find("state_groundtruth_estimate0/data.csv holds no poses") != std::string::npos;
  }
  EXPECT_TRUE(said) << ::testing::PrintToString(d.warnings);
}

TEST(DatasetWarnings, ASynthFolderWithoutSequenceJsonIsSaid) {
  testing::TempDir dir;
  WriteTumFolder(dir, 4, 4);
  dir.Write("tum/imu.txt", "1.0 0 0 0 0 0 9.81\n");
  dir.Write("tum/velocity.txt", "1.0 0 0 0\n");
  const Dataset d = LoadDataset(dir.Path("tum"));
  EXPECT_EQ(d.kind, DatasetKind::kTumRgbd);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("sequence.json"), std::string::npos) << d.warnings[0];
}

}  // namespace
}  // namespace imumatch
