#include "imumatch/eval/track_run.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "imumatch/core/error.h"
#include "imumatch/core/time.h"
#include "imumatch/eval/match_image.h"
#include "imumatch/io/output_files.h"

namespace imumatch {

void TrackRunOptions::Check() const {
  front_end.Check();
  ground_truth.Check();
  IMUMATCH_CHECK(!thresholds_px.empty(), "no threshold");
  for (double t : thresholds_px) IMUMATCH_CHECK(std::isfinite(t) && t > 0.0, "threshold " << t);
  IMUMATCH_CHECK(keep_visuals >= 0, "keep_visuals=" << keep_visuals);
}

int TrackRunResult::FallbackCount() const {
  int n = 0;
  for (const TrackFrameRecord& f : frames) {
    n += f.error.empty() && f.result.status == FrameStatus::kBruteForce ? 1 : 0;
  }
  return n;
}

TrackRunResult RunTrack(const EvalSource& source, const TrackRunOptions& options) {
  options.Check();
  const Dataset& d = source.dataset;
  if (d.imu.empty()) {
    throw InputError(d.root,
                     "the dataset has no IMU: `track` needs one (TUM RGB-D: simulated "
                     "from the ground truth unless disabled)");
  }
  const auto wall0 = SteadyClock::now();
  TrackRunResult out;
  out.dataset_name = d.name;
  FrontEndOptions front_end = options.front_end;
  // A recorded IMU: every fitted rotation is kept, to measure the camera's clock offset over the
  // run (a simulated IMU shares the frames' clock).
  if (!d.imu_simulated) front_end.keep_fitted_rotations = true;
  FrontEnd fe(d.camera, d.imu_params, d.cam_from_imu, front_end);
  const std::vector<ImuSample>& imu = d.imu.samples();
  size_t next_imu = 0;
  const size_t first = std::min(options.first_frame, d.frames.size());
  const size_t end = options.max_frames > 0 ? std::min(d.frames.size(), first + options.max_frames)
                                            : d.frames.size();
  // The previous processed frame, for judging.
  bool have_prev = false;
  size_t prev_index = 0;
  cv::Mat prev_image, prev_depth;
  std::vector<cv::KeyPoint> prev_keypoints;
  std::vector<std::optional<Rigid3d>> estimated, truth;
  for (size_t k = first; k < end; ++k) {
    const FrameRecord& fr = d.frames[k];
    // The IMU up to one sample past the frame (the integration interpolates at its timestamp),
    // or past the frame plus the largest offset an estimated camera clock offset may take.
    const int64_t imu_until =
        fr.t_ns + (options.front_end.estimate_time_offset
                       ? SecondsToNs(options.front_end.time_offset.max_offset_s)
                       : 0);
    while (next_imu < imu.size()) {
      fe.AddImu(imu[next_imu]);
      if (imu[next_imu++].t_ns >= imu_until) break;
    }
    TrackFrameRecord rec;
    rec.frame = k;
    const auto t0 = SteadyClock::now();
    FrameImages images;
    try {
      images = source.reader(k, true);
    } catch (const Error& e) {
      rec.error = e.what();
    } catch (const cv::Exception& e) {
      rec.error = std::string("cannot decode: ") + e.what();
    }
    rec.read_ms = MsSince(t0);
    if (rec.error.empty()) {
      FrontEndFrame in;
      in.t_ns = fr.t_ns;
      in.image = images.image;
      if (!options.monocular) in.depth = images.depth;
      try {
        rec.result = fe.Process(in);
      } catch (const InvalidArgument& e) {
        rec.error = e.what();  // an image of another size, ...: the frame is skipped
      }
    }
    if (!rec.error.empty()) {
      out.frames.push_back(std::move(rec));
      if (options.progress) options.progress(k - first + 1, end - first);
      continue;
    }
    const FrontEndResult& r = rec.result;
    if (r.status != FrameStatus::kFirst && have_prev && fr.world_from_cam &&
        d.frames[prev_index].world_from_cam) {
      const Rigid3d gt =
          fr.world_from_cam->Inverse() * *d.frames[prev_index].world_from_cam;  // b_from_a
      const PairGroundTruth judge(d.camera, gt, prev_depth, prev_keypoints, r.keypoints,
                                  options.ground_truth);
      const std::vector<MatchResidual> res_final = judge.Judge(r.matches);
      const std::vector<MatchResidual> res_pass1 = judge.Judge(r.matches_pass1);
      for (double t : options.thresholds_px) {
        rec.final_counts.push_back(CountCorrect(res_final, t));
        rec.pass1_counts.push_back(CountCorrect(res_pass1, t));
      }
      rec.judged = true;
      if (static_cast<int>(out.visuals.size()) < options.keep_visuals && !r.matches.empty()) {
        PairVisual v;
        v.case_name = d.name;
        v.pair_index = k;
        v.detector = options.front_end.features.kind;
        v.image_a = prev_image;
        v.image_b = images.image;
        v.keypoints_a = prev_keypoints;
        v.keypoints_b = r.keypoints;
        v.camera = d.camera;
        v.runs.push_back({options.front_end.hybrid ? MatchMethod::kHybrid : MatchMethod::kGuided,
                          r.matches,
                          res_final,
                          {}});
        out.visuals.push_back(std::move(v));
      }
    }
    // Estimated poses count from the initialised state on.
    estimated.push_back(r.has_state ? std::optional<Rigid3d>(r.world_from_cam) : std::nullopt);
    truth.push_back(fr.world_from_cam);
    if (estimated.size() >= 2 && estimated[estimated.size() - 2] && estimated.back() &&
        truth[truth.size() - 2] && truth.back()) {
      const RelativePoseError e =
          ComputeRelativePoseError({estimated[estimated.size() - 2], estimated.back()},
                                   {truth[truth.size() - 2], truth.back()});
      rec.rpe_translation_m = e.translation_m[0];
      rec.rpe_rotation_deg = e.rotation_deg[0];
    }
    have_prev = true;
    prev_index = k;
    prev_image = images.image;
    prev_depth = images.depth;
    prev_keypoints = r.keypoints;
    out.frames.push_back(std::move(rec));
    if (options.progress) options.progress(k - first + 1, end - first);
  }
  out.notes = fe.notes();
  if (const GyroBiasFilter* filter = fe.gyro_bias_filter(); filter != nullptr) {
    out.learnt_gyro_bias = filter->bias();
    int64_t last_t_ns = 0;  // the filter's sigma at the last frame processed
    for (const TrackFrameRecord& f : out.frames) last_t_ns = std::max(last_t_ns, f.result.t_ns);
    out.notes.push_back("gyro bias learnt from the fitted rotations: " +
                        filter->Summary(last_t_ns));
  }
  if (!d.imu_simulated && !fe.fitted_rotations().empty()) {
    // The fitted rotations measure the camera's clock offset from the IMU's.
    const TimeOffsetEstimate offset =
        TryEstimateTimeOffset(d.imu, d.imu_params, fe.gyro_bias(), fe.fitted_rotations());
    out.time_offset = offset;
    out.notes.push_back(
        "camera-IMU time offset measured from the fitted rotations (t_imu = t_cam + offset): " +
        offset.Summary());
    out.imu_time_offset_s = NsToSeconds(fe.imu_time_offset_ns());
    if (const std::optional<TimeOffsetEstimate>& online = fe.online_time_offset(); online) {
      out.notes.push_back(
          "the IMU was read in the camera's clock, offset by the online estimate of the last " +
          std::to_string(online->observations) +
          " fitted rotations: " + FormatOffsetMs(out.imu_time_offset_s) +
          " in use at the end of the run (last estimate: " + online->Summary() + ")");
    }
    // Advice only when no online offset was in use (the batch estimate is then the whole
    // correction): with one in use, the run already read the IMU where the fits put it.
    if (fe.imu_time_offset_ns() == 0) {
      if (const std::string advice = TimeOffsetAdvice(offset, d.timeshift_cam_imu_s);
          !advice.empty()) {
        out.warnings.push_back(advice);
      }
    }
  }
  out.has_truth =
      std::any_of(truth.begin(), truth.end(), [](const auto& t) { return t.has_value(); });
  if (out.has_truth) out.rpe = ComputeRelativePoseError(estimated, truth);
  out.wall_s = std::chrono::duration<double>(SteadyClock::now() - wall0).count();
  return out;
}

namespace {

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

}  // namespace

std::string TrackReportMarkdown(const TrackRunResult& result, const TrackRunOptions& options,
                                const std::vector<std::pair<std::string, std::string>>& config) {
  std::ostringstream out;
  out << "# imumatch track: " << result.dataset_name << "\n\n";
  for (const auto& [k, v] : config) out << "- " << k << ": " << v << "\n";
  int processed = 0, skipped = 0, first = 0;
  double matches = 0, pass1 = 0, ms = 0, extract = 0, match1 = 0, pose = 0, match2 = 0;
  int matched_frames = 0, with_depth = 0, second = 0;
  for (const TrackFrameRecord& f : result.frames) {
    if (!f.error.empty()) {
      ++skipped;
      continue;
    }
    ++processed;
    const FrontEndResult& r = f.result;
    ms += r.total_ms;
    extract += r.extract_ms;
    if (r.status == FrameStatus::kFirst) {
      ++first;
      continue;
    }
    ++matched_frames;
    matches += static_cast<double>(r.matches.size());
    pass1 += static_cast<double>(r.matches_pass1.size());
    match1 += r.motion_ms + r.match1_ms;
    pose += r.pose_ms;
    match2 += r.match2_ms;
    with_depth += r.pose_from_depth ? 1 : 0;
    second += r.second_pass ? 1 : 0;
  }
  const double n = std::max(1, matched_frames);
  out << "- frames: " << result.frames.size() << " (" << processed << " processed, " << skipped
      << " unreadable and skipped, " << first << " waiting for or initialising the IMU state)\n";
  out << "- matched frames: " << matched_frames
      << "; fell back to brute force: " << result.FallbackCount()
      << "; pose from depth (PnP): " << with_depth << "; second pass: " << second << "\n";
  out << "- wall time " << Fixed(result.wall_s, 1) << " s\n";
  for (const std::string& w : result.warnings) out << "- **warning**: " << w << "\n";
  for (const std::string& note : result.notes) out << "- note: " << note << "\n";
  out << "\n## Per frame (mean over matched frames)\n\n"
      << "| matches pass 1 | matches final | extract ms | IMU + pass 1 ms | pose ms | pass 2 ms | "
         "total ms |\n|---:|---:|---:|---:|---:|---:|---:|\n"
      << "| " << Fixed(pass1 / n, 1) << " | " << Fixed(matches / n, 1) << " | "
      << Fixed(extract / std::max(1, processed), 2) << " | " << Fixed(match1 / n, 2) << " | "
      << Fixed(pose / n, 2) << " | " << Fixed(match2 / n, 2) << " | "
      << Fixed(ms / std::max(1, processed), 2) << " |\n";
  if (result.has_truth) {
    out << "\n## Judged by the ground truth (not given to the front end)\n\n"
        << "| pass | matches |";
    for (double t : options.thresholds_px) out << " precision @" << Fixed(t, 1) << " px |";
    out << "\n|---|---:|";
    for (size_t i = 0; i < options.thresholds_px.size(); ++i) out << "---:|";
    out << "\n";
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<double> correct(options.thresholds_px.size(), 0.0);
      double total = 0;
      int frames = 0;
      for (const TrackFrameRecord& f : result.frames) {
        if (!f.judged) continue;
        const auto& c = pass == 0 ? f.pass1_counts : f.final_counts;
        for (size_t i = 0; i < c.size(); ++i) correct[i] += c[i].correct;
        total += c.empty() ? 0 : c[0].matches;
        ++frames;
      }
      out << "| " << (pass == 0 ? "first (IMU prediction)" : "final (fitted pose)") << " | "
          << Fixed(total / std::max(1, frames), 1) << " |";
      for (double c : correct) out << " " << (total > 0 ? Fixed(c / total, 3) : "-") << " |";
      out << "\n";
    }
    out << "\nRelative pose error (TUM benchmark, consecutive frames, " << result.rpe.pairs()
        << " pairs): translation RMSE " << Fixed(result.rpe.rmse_translation_m * 1000.0, 2)
        << " mm (mean " << Fixed(result.rpe.mean_translation_m * 1000.0, 2)
        << " mm), rotation RMSE " << Fixed(result.rpe.rmse_rotation_deg, 3) << " deg (mean "
        << Fixed(result.rpe.mean_rotation_deg, 3) << " deg)\n";
  } else {
    out << "\nNo ground truth: nothing judged (matches, poses and timing are in frames.csv and "
           "trajectory.txt).\n";
  }
  // Consecutive frames with the same event are listed once.
  std::vector<std::string> events;
  for (size_t i = 0; i < result.frames.size();) {
    const TrackFrameRecord& f = result.frames[i];
    const std::string what = !f.error.empty() ? "skipped: " + f.error : f.result.event;
    size_t j = i + 1;
    while (j < result.frames.size() &&
           (!result.frames[j].error.empty() ? "skipped: " + result.frames[j].error
                                            : result.frames[j].result.event) == what) {
      ++j;
    }
    if (!what.empty()) {
      const std::string frames = j - i > 1 ? "frames " + std::to_string(f.frame) + "-" +
                                                 std::to_string(result.frames[j - 1].frame)
                                           : "frame " + std::to_string(f.frame);
      events.push_back(frames + " (" + (f.error.empty() ? ToString(f.result.status) : "skipped") +
                       "): " + what);
    }
    i = j;
  }
  if (!events.empty()) {
    out << "\n## Events\n\n";
    for (size_t i = 0; i < events.size() && i < 50; ++i) out << "- " << events[i] << "\n";
    if (events.size() > 50) out << "- ... " << events.size() - 50 << " more in frames.csv\n";
  }
  return out.str();
}

std::vector<std::string> WriteTrackOutputs(const std::string& dir, const TrackRunResult& result,
                                           const TrackRunOptions& options,
                                           const std::string& report_markdown) {
  std::filesystem::create_directories(dir);
  std::vector<std::string> written;
  auto write = [&](const std::string& name, const std::string& text) {
    WriteFileAtomic((std::filesystem::path(dir) / name).string(), text);
    written.push_back(name);
  };
  write("report.md", report_markdown);
  std::ostringstream csv, traj;
  csv << std::setprecision(9);
  csv << "frame,t_ns,status,keypoints,matches_pass1,matches,from_tracks,second_pass,"
         "pose_from_depth,pose_inliers,pose_rms_px,vx,vy,vz,velocity_sigma,extract_ms,motion_ms,"
         "match1_ms,pose_ms,match2_ms,total_ms,read_ms";
  for (double t : options.thresholds_px) csv << ",precision_pass1_" << Fixed(t, 1) << "px";
  for (double t : options.thresholds_px) csv << ",precision_" << Fixed(t, 1) << "px";
  csv << ",rpe_translation_m,rpe_rotation_deg,event\n";
  traj << "# imumatch track: " << result.dataset_name
       << " (world_from_cam; world: gravity-aligned at the IMU's still start)\n"
       << "# timestamp tx ty tz qx qy qz qw\n";
  traj << std::setprecision(17);
  for (const TrackFrameRecord& f : result.frames) {
    const FrontEndResult& r = f.result;
    std::string event = f.error.empty() ? r.event : "skipped: " + f.error;
    std::replace(event.begin(), event.end(), '"', '\'');
    csv << f.frame << "," << r.t_ns << "," << (f.error.empty() ? ToString(r.status) : "skipped")
        << "," << r.keypoints.size() << "," << r.matches_pass1.size() << "," << r.matches.size()
        << "," << r.from_tracks << "," << (r.second_pass ? 1 : 0) << ","
        << (r.pose_from_depth ? 1 : 0) << "," << r.pose.inliers << "," << r.pose.rms_px << ","
        << r.velocity_in_world.x() << "," << r.velocity_in_world.y() << ","
        << r.velocity_in_world.z() << "," << r.velocity_sigma << "," << r.extract_ms << ","
        << r.motion_ms << "," << r.match1_ms << "," << r.pose_ms << "," << r.match2_ms << ","
        << r.total_ms << "," << f.read_ms;
    for (int pass = 0; pass < 2; ++pass) {
      const auto& c = pass == 0 ? f.pass1_counts : f.final_counts;
      for (size_t i = 0; i < options.thresholds_px.size(); ++i) {
        csv << ",";
        if (i < c.size() && c[i].matches > 0)
          csv << static_cast<double>(c[i].correct) / c[i].matches;
      }
    }
    csv << "," << f.rpe_translation_m << "," << f.rpe_rotation_deg << ",\"" << event << "\"\n";
    if (f.error.empty() && r.has_state) {
      const Eigen::Quaterniond& q = r.world_from_cam.rotation;
      const Eigen::Vector3d& p = r.world_from_cam.translation;
      traj << FormatNsAsSeconds(r.t_ns) << " " << p.x() << " " << p.y() << " " << p.z() << " "
           << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
    }
  }
  write("frames.csv", csv.str());
  write("trajectory.txt", traj.str());
  MatchImageOptions mo;
  mo.threshold_px =
      options.thresholds_px.size() > 1 ? options.thresholds_px[1] : options.thresholds_px[0];
  for (const std::string& path : WriteMatchImages(dir, result.visuals, mo)) {
    written.push_back(std::filesystem::path(path).filename().string());
  }
  return written;
}

}  // namespace imumatch
