#include "imumatch/io/tum_rgbd.h"

#include <algorithm>
#include <filesystem>
#include <tuple>

#include "imumatch/core/error.h"
#include "imumatch/io/plausibility.h"
#include "imumatch/io/text_parsing.h"
#include "imumatch/io/trajectory_io.h"

namespace imumatch {

std::vector<StampedFile> ReadTumFileList(const std::string& path) {
  const std::vector<TextLine> lines = ReadTextFields(path, FieldSeparator::kWhitespace);
  std::vector<StampedFile> files;
  files.reserve(lines.size());
  for (const TextLine& line : lines) {
    CheckFieldCount(line, 2, path, "t filename");
    StampedFile f;
    f.t_ns = ParseSecondsField(line.fields[0], path, line.line);
    if (!files.empty()) {
      CheckIncreasingTimestamp(files.back().t_ns, files.back().line, f.t_ns, path, line.line);
    }
    f.path = line.fields[1];
    f.line = line.line;
    files.push_back(std::move(f));
  }
  return files;
}

std::vector<StampedAccel> ReadTumAccelerometer(const std::string& path) {
  const std::vector<TextLine> lines = ReadTextFields(path, FieldSeparator::kWhitespace);
  std::vector<StampedAccel> samples;
  samples.reserve(lines.size());
  int previous_line = 0;
  for (const TextLine& line : lines) {
    CheckFieldCount(line, 4, path, "t ax ay az");
    StampedAccel s;
    s.t_ns = ParseSecondsField(line.fields[0], path, line.line);
    if (!samples.empty()) {
      CheckIncreasingTimestamp(samples.back().t_ns, previous_line, s.t_ns, path, line.line);
    }
    s.accel_m_s2 = Eigen::Vector3d(ParseFiniteDouble(line.fields[1], path, line.line, "ax"),
                                   ParseFiniteDouble(line.fields[2], path, line.line, "ay"),
                                   ParseFiniteDouble(line.fields[3], path, line.line, "az"));
    plausibility::CheckAccel(s.accel_m_s2, path, line.line);
    samples.push_back(s);
    previous_line = line.line;
  }
  return samples;
}

std::vector<StampedPose> ReadTumGroundTruth(const std::string& path) {
  return ReadTumTrajectory(path);
}

std::vector<Association> AssociateTimestamps(const std::vector<int64_t>& first,
                                             const std::vector<int64_t>& second,
                                             int64_t max_difference_ns, int64_t offset_ns) {
  IMUMATCH_CHECK(max_difference_ns >= 0, "max_difference_ns must be >= 0");
  IMUMATCH_CHECK(std::is_sorted(first.begin(), first.end()), "first timestamps must be sorted");
  IMUMATCH_CHECK(std::is_sorted(second.begin(), second.end()), "second timestamps must be sorted");
  std::vector<Association> candidates;
  for (size_t i = 0; i < first.size(); ++i) {
    // second[j] + offset in (first[i] - max, first[i] + max).
    const int64_t lo = first[i] - offset_ns - max_difference_ns;
    size_t j =
        static_cast<size_t>(std::upper_bound(second.begin(), second.end(), lo) - second.begin());
    for (; j < second.size(); ++j) {
      const int64_t d = first[i] - (second[j] + offset_ns);
      if (d <= -max_difference_ns) break;
      const int64_t diff = d < 0 ? -d : d;
      if (diff < max_difference_ns) candidates.push_back({i, j, diff});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Association& a, const Association& b) {
    return std::tie(a.difference_ns, a.first, a.second) <
           std::tie(b.difference_ns, b.first, b.second);
  });
  std::vector<bool> used_first(first.size(), false), used_second(second.size(), false);
  std::vector<Association> matches;
  for (const Association& c : candidates) {
    if (used_first[c.first] || used_second[c.second]) continue;
    used_first[c.first] = true;
    used_second[c.second] = true;
    matches.push_back(c);
  }
  std::sort(matches.begin(), matches.end(),
            [](const Association& a, const Association& b) { return a.first < b.first; });
  return matches;
}

std::optional<Rigid3d> InterpolatePoseAt(const std::vector<StampedPose>& poses, int64_t t_ns,
                                         int64_t max_difference_ns) {
  const auto upper = std::upper_bound(poses.begin(), poses.end(), t_ns,
                                      [](int64_t t, const StampedPose& p) { return t < p.t_ns; });
  if (upper != poses.begin() && std::prev(upper)->t_ns == t_ns) {
    return std::prev(upper)->world_from_body;
  }
  if (upper == poses.begin() || upper == poses.end()) return std::nullopt;
  const StampedPose& a = *std::prev(upper);
  const StampedPose& b = *upper;
  if (t_ns - a.t_ns > max_difference_ns || b.t_ns - t_ns > max_difference_ns) return std::nullopt;
  const double alpha = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  return Interpolate(a.world_from_body, b.world_from_body, alpha);
}

const char* ToString(GroundTruthLookup lookup) {
  return lookup == GroundTruthLookup::kNearest ? "nearest" : "interpolate";
}

GroundTruthLookup ParseGroundTruthLookup(const std::string& name) {
  if (name == "nearest") return GroundTruthLookup::kNearest;
  if (name == "interpolate") return GroundTruthLookup::kInterpolate;
  throw InvalidArgument("unknown ground-truth lookup '" + name +
                        "' (expected 'nearest' or 'interpolate')");
}

std::vector<std::optional<Rigid3d>> LookUpGroundTruth(const std::vector<StampedPose>& poses,
                                                      const std::vector<int64_t>& t_ns,
                                                      GroundTruthLookup lookup,
                                                      int64_t max_difference_ns) {
  std::vector<std::optional<Rigid3d>> out(t_ns.size());
  if (lookup == GroundTruthLookup::kInterpolate) {
    for (size_t i = 0; i < t_ns.size(); ++i) {
      out[i] = InterpolatePoseAt(poses, t_ns[i], max_difference_ns);
    }
    return out;
  }
  std::vector<int64_t> pose_t(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) pose_t[i] = poses[i].t_ns;
  for (const Association& a : AssociateTimestamps(t_ns, pose_t, max_difference_ns)) {
    out[a.first] = poses[a.second].world_from_body;
  }
  return out;
}

TumRgbdFiles ReadTumRgbdFolder(const std::string& root) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw InputError(root, "TUM RGB-D folder not found");
  TumRgbdFiles files;
  files.root = root;
  const fs::path dir(root);
  files.rgb = ReadTumFileList((dir / "rgb.txt").string());
  if (fs::exists(dir / "depth.txt", ec))
    files.depth = ReadTumFileList((dir / "depth.txt").string());
  if (fs::exists(dir / "accelerometer.txt", ec)) {
    // imumatch does not integrate TUM's accelerometer (there is no gyro): a bad row in it must
    // not block the run, but is said.
    try {
      files.accelerometer = ReadTumAccelerometer((dir / "accelerometer.txt").string());
    } catch (const InputError& e) {
      files.warnings.push_back(std::string("accelerometer.txt not read (it is not used): ") +
                               e.what());
    }
  }
  if (fs::exists(dir / "groundtruth.txt", ec)) {
    files.groundtruth = ReadTumGroundTruth((dir / "groundtruth.txt").string());
  }
  return files;
}

}  // namespace imumatch
