#include "imumatch/io/trajectory_io.h"

#include <cmath>

#include <gtest/gtest.h>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/io/io_test_util.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

using testing::ExpectInputError;
using testing::TempDir;

TEST(TrajectoryIo, ReadsTumLinesWithComments) {
  TempDir dir;
  const std::string path =
      dir.Write("gt.txt",
                "# ground truth trajectory\n"
                "# timestamp tx ty tz qx qy qz qw\n"
                "1305031098.6659 1.3563 0.6305 1.6380 0.6132 0.5962 -0.3311 -0.3986\n"
                "\n"
                "1305031098.6758 1.3543 0.6306 1.6360 0 0 0 1\n");
  const std::vector<StampedPose> poses = ReadTumTrajectory(path);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].t_ns, 1305031098665900000LL);
  EXPECT_EQ(poses[1].t_ns, 1305031098675800000LL);
  EXPECT_DOUBLE_EQ(poses[0].world_from_body.translation.x(), 1.3563);
  EXPECT_DOUBLE_EQ(poses[0].world_from_body.translation.z(), 1.6380);
  // The 4-decimal quaternion (norm 0.99995...) is normalised; order x y z w.
  const Eigen::Quaterniond q = poses[0].world_from_body.rotation;
  EXPECT_NEAR(q.norm(), 1.0, 1e-15);
  const double n = std::sqrt(0.6132 * 0.6132 + 0.5962 * 0.5962 + 0.3311 * 0.3311 + 0.3986 * 0.3986);
  EXPECT_NEAR(q.x(), 0.6132 / n, 1e-15);
  EXPECT_NEAR(q.w(), -0.3986 / n, 1e-15);
  EXPECT_TRUE(poses[1].world_from_body.rotation.isApprox(Eigen::Quaterniond::Identity()));
}

TEST(TrajectoryIo, WriteReadRoundTripIsExact) {
  TempDir dir;
  std::vector<StampedPose> poses;
  for (int i = 0; i < 5; ++i) {
    StampedPose p;
    p.t_ns = 1305031098665912345LL + i * 33333333LL;
    p.world_from_body = Rigid3d(FromEulerZYX(0.1 * i, -0.2 + 0.05 * i, 1.0 / 3.0 * i),
                                Eigen::Vector3d(1.0 / 7.0 * i, -2.5e-9, 123.456789012345));
    poses.push_back(p);
  }
  const std::string path = dir.Path("traj.txt");
  WriteTumTrajectory(path, poses, "test trajectory");
  const std::vector<StampedPose> back = ReadTumTrajectory(path);
  ASSERT_EQ(back.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(back[i].t_ns, poses[i].t_ns);
    EXPECT_LT((back[i].world_from_body.translation - poses[i].world_from_body.translation).norm(),
              1e-12);
    EXPECT_LT(RotationDistance(back[i].world_from_body.rotation, poses[i].world_from_body.rotation),
              1e-12);
  }
}

TEST(TrajectoryIo, WriteRejectsUnsortedPoses) {
  TempDir dir;
  std::vector<StampedPose> poses(2);
  poses[0].t_ns = 10;
  poses[1].t_ns = 10;
  EXPECT_THROW(WriteTumTrajectory(dir.Path("x.txt"), poses), InvalidArgument);
}

TEST(TrajectoryIo, MissingFile) {
  TempDir dir;
  const std::string path = dir.Path("nope.txt");
  ExpectInputError([&] { ReadTumTrajectory(path); }, path, 0, "not found");
}

TEST(TrajectoryIo, WrongFieldCount) {
  TempDir dir;
  const std::string path = dir.Write("gt.txt", "# c\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(path); }, path, 3, "expected 8 fields");
}

TEST(TrajectoryIo, NonNumeric) {
  TempDir dir;
  const std::string path = dir.Write("gt.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 abc 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(path); }, path, 2, "ty: 'abc' is not a number");
  const std::string bad_t = dir.Write("gt2.txt", "1.0x 0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(bad_t); }, bad_t, 1, "timestamp");
}

TEST(TrajectoryIo, NaN) {
  TempDir dir;
  const std::string path = dir.Write("gt.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 nan 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(path); }, path, 2, "not finite");
}

TEST(TrajectoryIo, UnsortedAndDuplicateTimestamps) {
  TempDir dir;
  const std::string unsorted =
      dir.Write("a.txt", "1.0 0 0 0 0 0 0 1\n# gap\n3.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(unsorted); }, unsorted, 4, "before the previous");
  const std::string dup = dir.Write("b.txt", "1.0 0 0 0 0 0 0 1\n1.000000000 0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(dup); }, dup, 2, "duplicate timestamp");
}

TEST(TrajectoryIo, NonUnitQuaternion) {
  TempDir dir;
  // Within 1e-3: normalised silently.
  const std::string ok = dir.Write("ok.txt", "1.0 0 0 0 0 0 0 1.0009\n");
  EXPECT_NEAR(ReadTumTrajectory(ok)[0].world_from_body.rotation.w(), 1.0, 1e-15);
  const std::string bad = dir.Write("bad.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0.5 0 0 1\n");
  ExpectInputError([&] { ReadTumTrajectory(bad); }, bad, 2, "norm");
}

TEST(TrajectoryIo, ReadsPoseOfRealTumPair) {
  const Rigid3d prev = ReadTumPose(testing::DataPath("tum_fr1_xyz_pair/pose_prev.txt"));
  EXPECT_DOUBLE_EQ(prev.translation.x(), 1.3303);
  EXPECT_DOUBLE_EQ(prev.translation.z(), 1.6464);
  EXPECT_NEAR(prev.rotation.w(), -0.3189, 1e-4);
  EXPECT_NEAR(prev.rotation.x(), 0.6579, 1e-4);
  const Rigid3d curr = ReadTumPose(testing::DataPath("tum_fr1_xyz_pair/pose_curr.txt"));
  // fr1_xyz moves slowly: the two frames are a couple of cm and a degree or so apart.
  EXPECT_LT((curr.translation - prev.translation).norm(), 0.05);
  EXPECT_LT(RotationDistance(prev.rotation, curr.rotation), 0.05);
}

}  // namespace
}  // namespace imumatch
