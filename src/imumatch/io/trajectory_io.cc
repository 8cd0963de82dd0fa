#include "imumatch/io/trajectory_io.h"

#include <fstream>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/io/output_files.h"
#include "imumatch/io/plausibility.h"
#include "imumatch/io/text_parsing.h"

namespace imumatch {
namespace {

// Fields [first, first+7) as "tx ty tz qx qy qz qw".
Rigid3d ParsePoseFields(const TextLine& line, size_t first, const std::string& path) {
  static const char* kNames[] = {"tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  double v[7];
  for (size_t i = 0; i < 7; ++i) {
    v[i] = ParseFiniteDouble(line.fields[first + i], path, line.line, kNames[i]);
  }
  const Eigen::Quaterniond q = CheckedUnitQuaternion(v[6], v[3], v[4], v[5], path, line.line);
  Rigid3d pose;
  pose.rotation = q;
  pose.translation = Eigen::Vector3d(v[0], v[1], v[2]);
  plausibility::CheckPosition(pose.translation, path, line.line);
  return pose;
}

}  // namespace

std::vector<StampedPose> ReadTumTrajectory(const std::string& path) {
  const std::vector<TextLine> lines = ReadTextFields(path, FieldSeparator::kWhitespace);
  std::vector<StampedPose> poses;
  poses.reserve(lines.size());
  int previous_line = 0;
  for (const TextLine& line : lines) {
    CheckFieldCount(line, 8, path, "t tx ty tz qx qy qz qw");
    StampedPose p;
    p.t_ns = ParseSecondsField(line.fields[0], path, line.line);
    if (!poses.empty()) {
      CheckIncreasingTimestamp(poses.back().t_ns, previous_line, p.t_ns, path, line.line);
    }
    p.world_from_body = ParsePoseFields(line, 1, path);
    poses.push_back(p);
    previous_line = line.line;
  }
  return poses;
}

void WriteTumTrajectory(const std::string& path, const std::vector<StampedPose>& poses,
                        const std::string& header_comment) {
  for (size_t i = 1; i < poses.size(); ++i) {
    IMUMATCH_CHECK(poses[i].t_ns > poses[i - 1].t_ns,
                   "pose timestamps must increase (index " << i << ")");
  }
  std::ostringstream out;
  if (!header_comment.empty()) out << "# " << header_comment << "\n";
  out << "# timestamp tx ty tz qx qy qz qw\n";
  for (const StampedPose& p : poses) {
    const Eigen::Vector3d& t = p.world_from_body.translation;
    const Eigen::Quaterniond& q = p.world_from_body.rotation;
    out << FormatNsAsSeconds(p.t_ns);
    for (double v : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) {
      out << ' ' << FormatDoubleExact(v);
    }
    out << '\n';
  }
  WriteFileAtomic(path, out.str());
}

Rigid3d ReadTumPose(const std::string& path) {
  const std::vector<TextLine> lines = ReadTextFields(path, FieldSeparator::kWhitespace);
  if (lines.empty()) throw InputError(path, "no pose found (expected 'tx ty tz qx qy qz qw')");
  if (lines.size() > 1) {
    throw InputError(path, lines[1].line, "expected a single pose line 'tx ty tz qx qy qz qw'");
  }
  CheckFieldCount(lines[0], 7, path, "tx ty tz qx qy qz qw");
  return ParsePoseFields(lines[0], 0, path);
}

}  // namespace imumatch
