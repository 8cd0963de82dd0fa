#include "imumatch/io/tum_rgbd.h"

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/io/io_test_util.h"

namespace imumatch {
namespace {

using testing::ExpectInputError;
using testing::TempDir;

constexpr int64_t kMs = 1'000'000;

TEST(TumRgbd, ReadsFileListAndAccelerometer) {
  TempDir dir;
  const std::string rgb = dir.Write("rgb.txt",
                                    "# color images\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n"
                                    "# timestamp filename\n"
                                    "1305031102.175304 rgb/1305031102.175304.png\n"
                                    "1305031102.211214 rgb/1305031102.211214.png\n");
  const std::vector<StampedFile> files = ReadTumFileList(rgb);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].t_ns, 1305031102175304000LL);
  EXPECT_EQ(files[0].path, "rgb/1305031102.175304.png");
  EXPECT_EQ(files[0].line, 4);
  EXPECT_EQ(files[1].t_ns, 1305031102211214000LL);

  const std::string acc = dir.Write("accelerometer.txt",
                                    "# accelerometer data\n# timestamp ax ay az\n"
                                    "1305031098.3592 0.3600 -9.2200 -2.6000\n"
                                    "1305031098.3708 0.3400 -9.2400 -2.5700\n");
  const std::vector<StampedAccel> a = ReadTumAccelerometer(acc);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[1].t_ns, 1305031098370800000LL);
  EXPECT_DOUBLE_EQ(a[0].accel_m_s2.y(), -9.22);
  EXPECT_DOUBLE_EQ(a[1].accel_m_s2.z(), -2.57);
}

TEST(TumRgbd, FileListErrors) {
  TempDir dir;
  const std::string missing = dir.Path("rgb.txt");
  ExpectInputError([&] { ReadTumFileList(missing); }, missing, 0, "not found");
  const std::string fields = dir.Write("a.txt", "1.0 a.png\n2.0 b.png extra\n");
  ExpectInputError([&] { ReadTumFileList(fields); }, fields, 2, "expected 2 fields");
  const std::string bad_t = dir.Write("b.txt", "1.0 a.png\n2,5 b.png\n");
  ExpectInputError([&] { ReadTumFileList(bad_t); }, bad_t, 2, "timestamp");
  const std::string nan_t = dir.Write("c.txt", "nan a.png\n");
  ExpectInputError([&] { ReadTumFileList(nan_t); }, nan_t, 1, "timestamp");
  const std::string unsorted = dir.Write("d.txt", "2.0 a.png\n1.0 b.png\n");
  ExpectInputError([&] { ReadTumFileList(unsorted); }, unsorted, 2, "before the previous");
  const std::string dup = dir.Write("e.txt", "2.0 a.png\n2.0 b.png\n");
  ExpectInputError([&] { ReadTumFileList(dup); }, dup, 2, "duplicate");
}

TEST(TumRgbd, AccelerometerErrors) {
  TempDir dir;
  const std::string fields = dir.Write("a.txt", "1.0 0 0 9.8\n2.0 0 9.8\n");
  ExpectInputError([&] { ReadTumAccelerometer(fields); }, fields, 2, "expected 4 fields");
  const std::string nonnum = dir.Write("b.txt", "1.0 0 0 9.8\n2.0 0 x 9.8\n");
  ExpectInputError([&] { ReadTumAccelerometer(nonnum); }, nonnum, 2, "ay");
  const std::string nan = dir.Write("c.txt", "1.0 0 0 NaN\n");
  ExpectInputError([&] { ReadTumAccelerometer(nan); }, nan, 1, "az");
  const std::string dup = dir.Write("d.txt", "1.0 0 0 9.8\n1.0 0 0 9.8\n");
  ExpectInputError([&] { ReadTumAccelerometer(dup); }, dup, 2, "duplicate");
}

TEST(TumRgbd, AssociationIsGreedyByTimeDifference) {
  // Hand-made: rgb at 0, 30, 60, 100 ms; depth at 5, 25, 28, 90, 200 ms; max 20 ms.
  // Candidates (|dt| < 20): (30,28)=2, (0,5)=5, (30,25)=5, (100,90)=10; 60 has none (32, 30).
  // Greedy: (30,28), (0,5), (30,25) rejected because rgb 30 is taken, (100,90).
  const std::vector<int64_t> rgb = {0, 30 * kMs, 60 * kMs, 100 * kMs};
  const std::vector<int64_t> depth = {5 * kMs, 25 * kMs, 28 * kMs, 90 * kMs, 200 * kMs};
  const std::vector<Association> m = AssociateTimestamps(rgb, depth, 20 * kMs);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].first, 0u);
  EXPECT_EQ(m[0].second, 0u);
  EXPECT_EQ(m[0].difference_ns, 5 * kMs);
  EXPECT_EQ(m[1].first, 1u);
  EXPECT_EQ(m[1].second, 2u);
  EXPECT_EQ(m[1].difference_ns, 2 * kMs);
  EXPECT_EQ(m[2].first, 3u);
  EXPECT_EQ(m[2].second, 3u);
}

TEST(TumRgbd, AssociationUsesEachElementOnceAndStrictTolerance) {
  // Two rgb frames compete for one depth frame: the closer one wins, the other gets the next best.
  const std::vector<int64_t> rgb = {10 * kMs, 14 * kMs};
  const std::vector<int64_t> depth = {12 * kMs, 15 * kMs, 40 * kMs};
  const std::vector<Association> m = AssociateTimestamps(rgb, depth, 20 * kMs);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].second, 0u);  // rgb 10 -> depth 12 (|dt| 2)
  EXPECT_EQ(m[1].second, 1u);  // rgb 14 -> depth 15 (|dt| 1, taken first)
  // |dt| == max is not a match (associate.py uses '<').
  EXPECT_TRUE(AssociateTimestamps({0}, {20 * kMs}, 20 * kMs).empty());
  EXPECT_EQ(AssociateTimestamps({0}, {20 * kMs - 1}, 20 * kMs).size(), 1u);
  // The offset is added to the second list.
  const auto shifted = AssociateTimestamps({100 * kMs}, {0, 50 * kMs}, 5 * kMs, 50 * kMs);
  ASSERT_EQ(shifted.size(), 1u);
  EXPECT_EQ(shifted[0].second, 1u);
  EXPECT_THROW(AssociateTimestamps({2, 1}, {1}), InvalidArgument);
}

std::vector<StampedPose> TwoPoses() {
  std::vector<StampedPose> poses(2);
  poses[0].t_ns = 100 * kMs;
  poses[0].world_from_body = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0));
  poses[1].t_ns = 110 * kMs;
  poses[1].world_from_body =
      Rigid3d(ExpSO3(Eigen::Vector3d(0, 0, 0.2)), Eigen::Vector3d(1.0, 0, 0));
  return poses;
}

TEST(TumRgbd, InterpolatesGroundTruthWithSlerp) {
  const std::vector<StampedPose> poses = TwoPoses();
  const auto mid = InterpolatePoseAt(poses, 104 * kMs, 20 * kMs);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->translation.x(), 0.4, 1e-12);
  EXPECT_LT((LogSO3(mid->rotation) - Eigen::Vector3d(0, 0, 0.08)).norm(), 1e-12);
  // Exact timestamps return the stored pose; outside the range or too far: none.
  EXPECT_NEAR(InterpolatePoseAt(poses, 110 * kMs, 1)->translation.x(), 1.0, 0.0);
  EXPECT_FALSE(InterpolatePoseAt(poses, 99 * kMs, 20 * kMs).has_value());
  EXPECT_FALSE(InterpolatePoseAt(poses, 111 * kMs, 20 * kMs).has_value());
  EXPECT_FALSE(InterpolatePoseAt(poses, 104 * kMs, 5 * kMs).has_value());  // 6 ms to the next
}

TEST(TumRgbd, LookUpGroundTruthNearestVersusInterpolate) {
  const std::vector<StampedPose> poses = TwoPoses();
  const std::vector<int64_t> t = {96 * kMs, 103 * kMs, 200 * kMs};
  const auto nearest = LookUpGroundTruth(poses, t, GroundTruthLookup::kNearest, 20 * kMs);
  // 103 is closer to 100 (3 ms) than 96 (4 ms), so it takes pose 0 and 96 takes pose 1 (14 ms).
  ASSERT_TRUE(nearest[0].has_value());
  ASSERT_TRUE(nearest[1].has_value());
  EXPECT_NEAR(nearest[0]->translation.x(), 1.0, 0.0);
  EXPECT_NEAR(nearest[1]->translation.x(), 0.0, 0.0);
  EXPECT_FALSE(nearest[2].has_value());
  const auto interp = LookUpGroundTruth(poses, t, GroundTruthLookup::kInterpolate, 20 * kMs);
  EXPECT_FALSE(interp[0].has_value());
  ASSERT_TRUE(interp[1].has_value());
  EXPECT_NEAR(interp[1]->translation.x(), 0.3, 1e-12);
  EXPECT_FALSE(interp[2].has_value());
  EXPECT_EQ(ParseGroundTruthLookup("nearest"), GroundTruthLookup::kNearest);
  EXPECT_STREQ(ToString(ParseGroundTruthLookup("interpolate")), "interpolate");
  EXPECT_THROW(ParseGroundTruthLookup("closest"), InvalidArgument);
}

TEST(TumRgbd, ReadsFolderWithOptionalFiles) {
  TempDir dir;
  dir.Write("rgb.txt", "1.0 rgb/1.png\n2.0 rgb/2.png\n");
  TumRgbdFiles only_rgb = ReadTumRgbdFolder(dir.path());
  EXPECT_EQ(only_rgb.rgb.size(), 2u);
  EXPECT_TRUE(only_rgb.depth.empty());
  EXPECT_TRUE(only_rgb.groundtruth.empty());
  dir.Write("depth.txt", "1.01 depth/1.png\n");
  dir.Write("groundtruth.txt", "0.99 0 0 0 0 0 0 1\n1.5 1 0 0 0 0 0 1\n");
  const TumRgbdFiles all = ReadTumRgbdFolder(dir.path());
  EXPECT_EQ(all.depth.size(), 1u);
  EXPECT_EQ(all.groundtruth.size(), 2u);
  const std::string bad_gt = dir.Write("groundtruth.txt", "0.99 0 0 0 0 0 0 1\n1.5 1 0 0\n");
  ExpectInputError([&] { ReadTumRgbdFolder(dir.path()); }, bad_gt, 2, "expected 8 fields");
  TempDir empty;
  ExpectInputError([&] { ReadTumRgbdFolder(empty.path()); }, empty.Path("rgb.txt"), 0, "not found");
}

}  // namespace
}  // namespace imumatch
