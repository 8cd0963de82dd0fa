// The imumatch command-line tool end to end, as a user runs it: `imumatch synth` writes a short
// synthetic sequence, `imumatch eval` reads it back (and the real TUM fr1_xyz pair) and its
// report.json is checked against the ground truth; bad inputs map to clear errors and exit codes.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "imumatch/io/trajectory_io.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

namespace fs = std::filesystem;

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

CommandResult RunCli(const std::string& args) {
  const std::string command = std::string(IMUMATCH_CLI) + " " + args + " 2>&1";
  CommandResult r;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  size_t n = 0;
  while ((n = fread(buffer, 1, sizeof(buffer), pipe)) > 0) r.output.append(buffer, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("imumatch_cli_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  return nlohmann::json::parse(in);
}

const nlohmann::json* SummaryRow(const nlohmann::json& report, const std::string& detector,
                                 const std::string& method) {
  for (const auto& row : report["summary"]) {
    if (row["detector"] == detector && row["method"] == method) return &row;
  }
  ADD_FAILURE() << "no summary row " << detector << " " << method;
  return nullptr;
}

TEST_F(CliTest, SynthThenEvalOnTheWrittenSequence) {
  const CommandResult synth =
      RunCli("synth --motion walk --width 320 --duration 0.2 --still 0.05 --out " + Path("seq"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  ASSERT_TRUE(fs::exists(Path("seq/rgb.txt"))) << synth.output;
  const CommandResult eval = RunCli("eval " + Path("seq") +
                                    " --detectors orb,sift --methods bf,guided --max-keypoints 400"
                                    " --max-pairs 4 --e2e-frames 0 --images 1 --out " +
                                    Path("out"));
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_NE(eval.output.find("Table I"), std::string::npos) << eval.output;
  EXPECT_NE(eval.output.find("Table II"), std::string::npos) << eval.output;
  const nlohmann::json report = ReadJson(Path("out/report.json"));
  // Exact synthetic ground truth: the fixed 1.5 px threshold, not an automatic one.
  EXPECT_DOUBLE_EQ(report["threshold"]["threshold_px"].get<double>(), 1.5) << report["threshold"];
  EXPECT_TRUE(report["skipped"].empty()) << report["skipped"];
  for (const std::string detector : {"orb", "sift"}) {
    SCOPED_TRACE(detector);
    const nlohmann::json* guided = SummaryRow(report, detector, "guided");
    const nlohmann::json* bf = SummaryRow(report, detector, "bf");
    ASSERT_TRUE(guided != nullptr && bf != nullptr);
    EXPECT_EQ((*guided)["pairs"].get<int>(), 4);
    EXPECT_GT((*guided)["matches"].get<double>(), 50.0);
    EXPECT_GE((*guided)["correct"].get<double>(), (*bf)["correct"].get<double>());
    EXPECT_GE((*guided)["precision"].get<double>(), detector == "sift" ? 0.98 : 0.85);
  }
  EXPECT_TRUE(fs::exists(Path("out/summary.csv")));
  EXPECT_TRUE(fs::exists(Path("out/report.md")));
}

TEST_F(CliTest, TrackRunsWithoutGroundTruthStateAndSaysWhatItSkipped) {
  const CommandResult synth = RunCli(
      "synth --motion walk --width 320 --fps 20 --duration 0.6 --still 0.5 --out " + Path("seq"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  // A frame whose image is gone: skipped with its file named, the run goes on.
  fs::remove(Path("seq/rgb/" + std::string("0.750000000.png")));
  CommandResult r = RunCli("track " + Path("seq") + " --max-keypoints 300 --out " + Path("t"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Judged by the ground truth"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fell back to brute force: 0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("0.750000000.png"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(Path("t/frames.csv")));
  // The trajectory is a TUM file: one pose per frame from the initialised state on.
  const auto poses = ReadTumTrajectory(Path("t/trajectory.txt"));
  EXPECT_GT(poses.size(), 10u);
  // A folder without an IMU (the TUM pose pair) is refused with its name.
  r = RunCli("track " + testing::DataPath("tum_fr1_xyz_pair") + " --out " + Path("t2"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
}

TEST_F(CliTest, EvalOnTheRealTumPairPrintsItsAutomaticThreshold) {
  const std::string tum = testing::DataPath("tum_fr1_xyz_pair");
  const CommandResult eval = RunCli(
      "eval " + tum + " --detectors orb --methods bf,guided --e2e-frames 0 --out " + Path("tum"));
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  const nlohmann::json report = ReadJson(Path("tum/report.json"));
  const double threshold = report["threshold"]["threshold_px"].get<double>();
  EXPECT_GE(threshold, 2.0);
  EXPECT_LE(threshold, 10.0);
  const nlohmann::json* guided = SummaryRow(report, "orb", "guided");
  const nlohmann::json* bf = SummaryRow(report, "orb", "bf");
  ASSERT_TRUE(guided != nullptr && bf != nullptr);
  EXPECT_GE((*guided)["correct"].get<double>(), (*bf)["correct"].get<double>());
  EXPECT_GT((*guided)["precision"].get<double>(), 0.95);
}

TEST_F(CliTest, BadInputsGiveClearErrorsAndExitCodes) {
  // A missing dataset folder: input error (3), naming the path.
  CommandResult r = RunCli("eval " + Path("does-not-exist") + " --out " + Path("o1"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("does-not-exist"), std::string::npos) << r.output;
  // A pose-pair folder with a malformed pose line: input error naming file and line.
  const std::string pair = testing::DataPath("tum_fr1_xyz_pair");
  fs::create_directories(Path("bad"));
  for (const char* f :
       {"img_prev.png", "img_curr.png", "dep_prev.png", "dep_curr.png", "pose_prev.txt"}) {
    fs::copy_file(pair + "/" + f, Path(std::string("bad/") + f));
  }
  std::ofstream(Path("bad/pose_curr.txt")) << "1.0 2.0 nan-ish 0 0 0 1\n";
  r = RunCli("eval " + Path("bad") + " --out " + Path("o2"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("pose_curr.txt:1"), std::string::npos) << r.output;
  // An unknown motion or detector: invalid argument (4).
  r = RunCli("synth --motion sideways --out " + Path("o3"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("sideways"), std::string::npos) << r.output;
  r = RunCli("eval " + pair + " --detectors orb,harris --out " + Path("o4"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("harris"), std::string::npos) << r.output;
  // A value outside its option's interval: a usage error (2) naming the option and the interval.
  r = RunCli("eval " + pair + " --gate 1.5 --out " + Path("o5"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--gate: 1.5 is not in (0, 1)"), std::string::npos) << r.output;
  // Usage errors (2).
  r = RunCli("eval");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

TEST_F(CliTest, HostileInputsAndOptionsAreRefusedBeforeTheWork) {
  const std::string pair = testing::DataPath("tum_fr1_xyz_pair");
  // Unbounded work: refused before rendering (invalid option, 4).
  CommandResult r = RunCli("synth --motion left30 --duration 1e6 --fps 1 --out " + Path("s1"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("20000"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(Path("s1/rgb.txt")));
  // Options outside their range: usage errors (2), before anything is read.
  r = RunCli("eval " + pair + " --max-keypoints 2147483647 --out " + Path("o1"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("max-keypoints"), std::string::npos) << r.output;
  r = RunCli("eval " + pair + " --max-pairs -1 --out " + Path("o2"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("max-pairs"), std::string::npos) << r.output;
  // Numbers that are not finite or lie outside their option's interval: usage errors naming the
  // option, before anything is read. A negative value never reaches an option's "automatic"
  // default (--orientation-tolerance -1, --z-min -1 and synth's --duration -1 ran silently with
  // the defaults).
  for (const std::string& bad :
       {std::string("eval ") + pair + " --threshold inf", "eval " + pair + " --threshold 0",
        "eval " + pair + " --ratio nan", "eval " + pair + " --interval nan",
        "eval " + pair + " --orientation-tolerance -1", "eval " + pair + " --z-min -1",
        "eval " + pair + " --fixed-window 0", "eval " + pair + " --still -0.5",
        std::string("synth --motion walk --duration -1"),
        std::string("synth --motion walk --fps 0"), std::string("synth --motion walk --texel 0")}) {
    const size_t at = bad.rfind(" --") + 1;
    const std::string option = bad.substr(at, bad.find(' ', at) - at);
    r = RunCli(bad + " --out " + Path("o3"));
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.output;
    EXPECT_NE(r.output.find(option + ": "), std::string::npos) << bad << "\n" << r.output;
    EXPECT_EQ(r.output.find("Table"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(Path("o3"))) << bad;
  }
  // Options that contradict each other or the dataset: invalid arguments (4) naming them.
  r = RunCli("eval " + pair + " --z-min 5 --z-max 2 --out " + Path("o4"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("--z-max (2 m) must be farther than --z-min (5 m)"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("required:"), std::string::npos) << r.output;
  r = RunCli("track " + testing::DataPath("euroc_v101_excerpt") + " --first 19 --out " +
             Path("o4"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("--first 19: euroc_v101_excerpt has 20 frames"), std::string::npos)
      << r.output;
  // An unwritable --out: said before the evaluation runs.
  r = RunCli("eval " + pair + " --out /proc/imumatch-out");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("/proc/imumatch-out"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Table"), std::string::npos) << r.output;
}

TEST_F(CliTest, EvalNeverWritesIntoSomebodyElsesFolder) {
  const std::string pair = testing::DataPath("tum_fr1_xyz_pair");
  // --out pointing at a folder of the user's files: refused (4), nothing touched.
  fs::create_directories(Path("mine"));
  std::ofstream(Path("mine/report.md")) << "my own notes\n";
  const std::string args = " --detectors orb --methods bf,guided --e2e-frames 0 --images 0";
  CommandResult r = RunCli("eval " + pair + args + " --out " + Path("mine"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("report.md"), std::string::npos) << r.output;
  std::ifstream notes(Path("mine/report.md"));
  std::string first;
  std::getline(notes, first);
  EXPECT_EQ(first, "my own notes");
  // Its own earlier outputs are replaced, and it says so.
  r = RunCli("eval " + pair + args + " --out " + Path("run"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = RunCli("eval " + pair + args + " --out " + Path("run"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("replacing the outputs of an earlier run"), std::string::npos)
      << r.output;
  // --overwrite writes into the user's folder (their other files stay).
  std::ofstream(Path("mine/keep.txt")) << "keep\n";
  r = RunCli("eval " + pair + args + " --overwrite --out " + Path("mine"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(Path("mine/keep.txt")));
  EXPECT_TRUE(fs::exists(Path("mine/summary.csv")));
}

TEST_F(CliTest, AGroundTruthTimestampJumpIsBadDataOnItsLine) {
  const std::string pair = testing::DataPath("tum_fr1_xyz_pair");
  fs::create_directories(Path("tum/rgb"));
  fs::create_directories(Path("tum/depth"));
  fs::copy_file(pair + "/img_prev.png", Path("tum/rgb/1.000000.png"));
  fs::copy_file(pair + "/img_curr.png", Path("tum/rgb/1.033333.png"));
  fs::copy_file(pair + "/dep_prev.png", Path("tum/depth/1.000000.png"));
  fs::copy_file(pair + "/dep_curr.png", Path("tum/depth/1.033333.png"));
  std::ofstream(Path("tum/rgb.txt")) << "1.000000 rgb/1.000000.png\n1.033333 rgb/1.033333.png\n";
  std::ofstream(Path("tum/depth.txt"))
      << "1.000000 depth/1.000000.png\n1.033333 depth/1.033333.png\n";
  std::ofstream gt(Path("tum/groundtruth.txt"));
  for (int i = 0; i < 10; ++i) gt << 0.95 + 0.01 * i << " 0 0 " << 0.001 * i << " 0 0 0 1\n";
  gt << "1000000.0 0 0 0 0 0 0 1\n";  // one line appended far ahead
  gt.close();
  const CommandResult r = RunCli("eval " + Path("tum") + " --out " + Path("o"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("groundtruth.txt:11"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("jumps"), std::string::npos) << r.output;
}

// Copies the EuRoC V1_01 excerpt to dest with the IMU rows whose timestamp (its 19 digits,
// compared as text) keep() rejects left out; returns the line, in the new data.csv, of the first
// kept row after the last left-out one (0: none).
int CopyV101WithImuRows(const std::string& dest,
                        const std::function<bool(const std::string&)>& keep) {
  const std::string src = testing::DataPath("euroc_v101_excerpt");
  fs::copy(src, dest, fs::copy_options::recursive);
  std::ifstream in(src + "/mav0/imu0/data.csv");
  std::ofstream out(dest + "/mav0/imu0/data.csv", std::ios::trunc);
  std::string line;
  int written = 0, first_after = 0;
  bool after_left_out = false;
  while (std::getline(in, line)) {
    if (line[0] != '#' && !keep(line.substr(0, 19))) {
      after_left_out = true;
      continue;
    }
    out << line << "\n";
    ++written;
    if (after_left_out && line[0] != '#') {
      first_after = written;
      after_left_out = false;
    }
  }
  return first_after;
}

TEST_F(CliTest, ImuSaysWhichIntervalsLieOutsideTheLog) {
  // The EuRoC excerpt with its IMU log cut 0.74 s after the first frame.
  CopyV101WithImuRows(Path("v101"),
                      [](const std::string& t) { return t <= "1403715274000000000"; });
  const CommandResult r = RunCli("imu --euroc " + Path("v101"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: 14 of 19 frame intervals printed"), std::string::npos) << r.output;
}

TEST_F(CliTest, ImuGapsShortenTheStillStartAndSkipTheIntervalsAcrossThem) {
  // The EuRoC excerpt (its IMU log starts still with the first frame) without the samples of
  // 0.30-0.40 s: 100 ms without IMU inside the 1 s still start and across frames 6-8.
  const int first_after_gap = CopyV101WithImuRows(Path("v101"), [](const std::string& t) {
    return t < "1403715273565000000" || t > "1403715273660000000";
  });
  ASSERT_GT(first_after_gap, 0);
  const CommandResult r = RunCli("imu --euroc " + Path("v101"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // The still start ends at the gap (0.3 s at 200 Hz: 61 samples) instead of failing.
  EXPECT_NE(r.output.find("still start 0.300 s (61 samples)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the still period ends at an IMU gap"), std::string::npos) << r.output;
  // The two intervals across the gap are skipped, naming the file and line after the gap.
  const std::string where = "imu0/data.csv:" + std::to_string(first_after_gap) + ": ";
  EXPECT_NE(r.output.find("skipped: " + Path("v101") + "/mav0/" + where), std::string::npos)
      << where << "\n"
      << r.output;
  EXPECT_NE(r.output.find("note: 17 of 19 frame intervals printed; of the others 2 cross a gap"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("warning: " + Path("v101") + "/mav0/" + where +
                          "the IMU log has 1 gap longer than 50.0 ms"),
            std::string::npos)
      << r.output;
  // track says the loader's warnings too (it printed none of them).
  const CommandResult t = RunCli("track " + Path("v101") + " --out " + Path("t"));
  EXPECT_EQ(t.exit_code, 0) << t.output;
  EXPECT_NE(t.output.find("imumatch: warning: " + Path("v101") + "/mav0/" + where +
                          "the IMU log has 1 gap longer than 50.0 ms"),
            std::string::npos)
      << t.output;
}

TEST_F(CliTest, ImuOnALogThatStartsInMotionIntegratesWithoutABias) {
  // A turn from the first sample on (no still time): no still start to take the bias from.
  ASSERT_EQ(RunCli("synth --motion left30 --still 0 --duration 0.5 --fps 20 --format euroc "
                   "--width 320 --imu ideal --out " +
                   Path("turn"))
                .exit_code,
            0);
  const CommandResult r = RunCli("imu --dataset " + Path("turn"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no still start ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the IMU does not look still"), std::string::npos) << r.output;
  // The ideal IMU has no bias: every interval's rotation is the ground truth's, to the 200 Hz
  // sampling of a turn that speeds up and slows down (up to 1e-3 deg of 0.3-4.6 deg).
  std::istringstream lines(r.output);
  std::string line;
  int rows = 0;
  while (std::getline(lines, line)) {
    std::istringstream row(line);
    int pair = -1;
    std::string t;
    double dt = 0, rot = 0, raw = 0, gt = -1;
    if (!(row >> pair >> t >> dt >> rot >> raw >> gt)) continue;
    EXPECT_NEAR(rot, gt, 2e-3) << line;
    EXPECT_EQ(rot, raw) << line;
    ++rows;
  }
  EXPECT_GE(rows, 8) << r.output;
}

TEST_F(CliTest, SynthOverwriteReplacesFilesAndNeverRewritesAHardLinkedCopy) {
  const std::string args = " --motion left30 --fps 4 --width 64 --out " + Path("seq");
  CommandResult r = RunCli("synth" + args);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The user keeps a hard-linked copy of a frame (cp -al), then renders again with --overwrite.
  const fs::path frame = *fs::directory_iterator(Path("seq/rgb"));
  fs::create_hard_link(frame, Path("kept.png"));
  const auto size_before = fs::file_size(Path("kept.png"));
  r = RunCli("synth" + args);
  EXPECT_EQ(r.exit_code, 4) << r.output;  // not empty: refused without --overwrite
  r = RunCli("synth" + args + " --overwrite --seed 7");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(fs::hard_link_count(Path("kept.png")), 1u);  // the frame was replaced, not rewritten
  EXPECT_EQ(fs::file_size(Path("kept.png")), size_before);
}

}  // namespace
}  // namespace imumatch
