// Outputs are written through a temporary file and a rename, and output folders are checked
// before any work: writable, and holding nothing imumatch did not write unless --overwrite.
#include "imumatch/io/output_files.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/image_io.h"
#include "imumatch/io/io_test_util.h"

namespace imumatch {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(OutputFilesTest, ReplacingAFileLeavesItsHardLinkedCopyIntact) {
  TempDir dir;
  const std::string original = dir.Write("user/frame.png", "the user's bytes");
  const std::string out = dir.Path("out/frame.png");
  fs::create_directories(dir.Path("out"));
  fs::create_hard_link(original, out);  // e.g. a dataset copied with cp -al
  cv::Mat image(8, 8, CV_8UC1, cv::Scalar(7));
  WriteImage(out, image);
  EXPECT_EQ(Slurp(original), "the user's bytes");  // replaced, not rewritten in place
  EXPECT_NE(Slurp(out), "the user's bytes");
  EXPECT_EQ(LoadImage(out).at<uint8_t>(3, 3), 7);
  WriteFileAtomic(out, "text");
  EXPECT_EQ(Slurp(out), "text");
  EXPECT_EQ(Slurp(original), "the user's bytes");
  // No temporary file is left behind.
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir.Path("out"))) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
}

TEST(OutputFilesTest, AFolderOfOtherFilesIsRefusedUnlessOverwrite) {
  TempDir dir;
  dir.Write("dataset/rgb.txt", "# a user's dataset\n");
  try {
    PrepareOutputFolder(dir.Path("dataset"), false);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("rgb.txt"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--overwrite"), std::string::npos) << e.what();
  }
  const OutputFolderCheck forced = PrepareOutputFolder(dir.Path("dataset"), true);
  EXPECT_NE(forced.note.find("1 other file"), std::string::npos) << forced.note;
}

TEST(OutputFilesTest, TheOutputsOfAnEarlierRunAreReplacedWithANote) {
  TempDir dir;
  const std::string out = dir.Path("eval-out");
  OutputFolderCheck first = PrepareOutputFolder(out, false);
  EXPECT_TRUE(first.created);
  EXPECT_TRUE(first.note.empty());
  WriteFileAtomic(out + "/report.md", "# report\n");
  WriteFileAtomic(out + "/summary.csv", "a,b\n");
  RecordOutputs(out, {out + "/report.md", out + "/summary.csv"});
  const OutputFolderCheck second = PrepareOutputFolder(out, false);
  EXPECT_EQ(second.earlier.size(), 2u);
  EXPECT_NE(second.note.find("earlier run"), std::string::npos) << second.note;
  // A file the tool did not write makes the folder foreign again.
  dir.Write("eval-out/notes.txt", "mine");
  EXPECT_THROW(PrepareOutputFolder(out, false), InvalidArgument);
}

TEST(OutputFilesTest, AnUnwritableOrInvalidFolderIsRefusedBeforeTheWork) {
  TempDir dir;
  const std::string file = dir.Write("a-file", "x");
  EXPECT_THROW(PrepareOutputFolder(file, false), InvalidArgument);                  // a file
  EXPECT_THROW(PrepareOutputFolder(file + "/sub", false), InvalidArgument);         // cannot create
  EXPECT_THROW(PrepareOutputFolder("/proc/imumatch-out", false), InvalidArgument);  // not writable
}

}  // namespace
}  // namespace imumatch
