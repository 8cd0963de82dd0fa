#include "imumatch/eval/evaluation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <iomanip>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>
#include <utility>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/core/so3.h"
#include "imumatch/core/time.h"
#include "imumatch/io/image_io.h"
#include "imumatch/matching/baseline_matchers.h"
#include "imumatch/matching/descriptor_distance.h"
#include "imumatch/matching/grid_index.h"

namespace imumatch {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// A bounded FIFO between the reader thread and the processing thread.
template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(size_t capacity) : capacity_(std::max<size_t>(1, capacity)) {}
  // Returns false when the queue was closed (the consumer gave up).
  bool Push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return closed_ || items_.size() < capacity_; });
    if (closed_) return false;
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }
  T Pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return !items_.empty(); });
    T item = std::move(items_.front());
    items_.pop_front();
    not_full_.notify_one();
    return item;
  }
  void Close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_full_.notify_all();
  }

 private:
  size_t capacity_;
  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::deque<T> items_;
  bool closed_ = false;
};

// Runs producer(i, queue) for i in [0, n) on its own thread (or inline when capacity is 0) and
// hands the items to the consumer in order. The reader stops early when the consumer throws.
template <typename T, typename Producer, typename Consumer>
void RunPipelined(size_t n, int capacity, Producer producer, Consumer consumer) {
  if (capacity <= 0) {
    for (size_t i = 0; i < n; ++i) consumer(producer(i));
    return;
  }
  BoundedQueue<T> queue(static_cast<size_t>(capacity));
  std::thread reader([&] {
    for (size_t i = 0; i < n; ++i) {
      if (!queue.Push(producer(i))) return;
    }
  });
  struct Joiner {
    BoundedQueue<T>& q;
    std::thread& t;
    ~Joiner() {
      q.Close();
      t.join();
    }
  } joiner{queue, reader};
  for (size_t i = 0; i < n; ++i) consumer(queue.Pop());
}

// A decoded frame pair, or the reason it could not be read.
struct PairItem {
  FrameImages a, b;
  double read_ms = 0.0;
  std::string error;
};

// Decodes pairs in order, reusing the previous pair's frame B when it is this pair's frame A.
class PairReader {
 public:
  PairReader(const FrameReader& reader, const std::vector<FramePair>& pairs)
      : reader_(reader), pairs_(pairs) {}
  PairItem operator()(size_t i) {
    PairItem item;
    const FramePair& p = pairs_[i];
    const auto t0 = Clock::now();
    try {
      if (has_last_ && last_index_ == p.a) {
        item.a = last_;
      } else {
        item.a = reader_(p.a, true);
      }
      item.b = reader_(p.b, true);
      last_ = item.b;
      last_index_ = p.b;
      has_last_ = true;
    } catch (const Error& e) {
      item.error = std::string("cannot read frame: ") + e.what();
      has_last_ = false;
    } catch (const cv::Exception& e) {
      item.error = std::string("cannot decode frame: ") + e.what();
      has_last_ = false;
    }
    item.read_ms = MsSince(t0);
    return item;
  }

 private:
  const FrameReader& reader_;
  const std::vector<FramePair>& pairs_;
  FrameImages last_;
  size_t last_index_ = 0;
  bool has_last_ = false;
};

// The IMU's velocity at a frame: the dataset's value, else a finite difference of the
// ground-truth poses of the neighbouring frames (IMU origin = world_from_cam * cam_from_imu).
std::optional<Eigen::Vector3d> ImuVelocityAt(const Dataset& dataset, size_t index) {
  const auto& frames = dataset.frames;
  if (frames[index].imu_velocity_in_world) return frames[index].imu_velocity_in_world;
  const size_t lo = index > 0 ? index - 1 : index;
  const size_t hi = index + 1 < frames.size() ? index + 1 : index;
  if (lo == hi || !frames[lo].world_from_cam || !frames[hi].world_from_cam) return std::nullopt;
  const double dt = NsToSeconds(frames[hi].t_ns - frames[lo].t_ns);
  if (!(dt > 0.0)) return std::nullopt;
  const Eigen::Vector3d p_hi =
      (*frames[hi].world_from_cam * dataset.cam_from_imu.Inverse()).translation;
  const Eigen::Vector3d p_lo =
      (*frames[lo].world_from_cam * dataset.cam_from_imu.Inverse()).translation;
  return (p_hi - p_lo) / dt;
}

struct PairMotion {
  CameraMotion motion;
  double ms = 0.0;
};

// The motion the predictor is given, or a skip reason.
std::optional<PairMotion> ComputePairMotion(const Dataset& dataset, const FramePair& pair,
                                            size_t pair_index, const EvaluationOptions& options,
                                            std::string& reason) {
  const FrameRecord& fa = dataset.frames[pair.a];
  const FrameRecord& fb = dataset.frames[pair.b];
  PairMotion out;
  const auto t0 = Clock::now();
  if (options.motion_source == MotionSource::kGroundTruth) {
    out.motion = CameraMotionFromPoses(fa.t_ns, *fa.world_from_cam, fb.t_ns, *fb.world_from_cam);
    out.ms = MsSince(t0);
    return out;
  }
  if (dataset.imu.empty()) {
    reason = "no IMU data in the dataset (use --motion-source gt)";
    return std::nullopt;
  }
  const std::optional<Eigen::Vector3d> velocity = ImuVelocityAt(dataset, pair.a);
  if (!velocity) {
    reason = "no ground-truth velocity at frame A to seed the IMU integration";
    return std::nullopt;
  }
  // The state a VIO back-end would supply: ground truth perturbed by the stated sigmas.
  const double v_sigma = options.velocity_perturbation_sigma >= 0.0
                             ? options.velocity_perturbation_sigma
                             : options.motion.velocity_sigma;
  const double a_sigma = options.attitude_perturbation_sigma >= 0.0
                             ? options.attitude_perturbation_sigma
                             : options.motion.attitude_sigma;
  std::mt19937_64 rng(options.seed + 1000003ULL * pair_index);
  std::normal_distribution<double> normal(0.0, 1.0);
  ImuStateAtFrame state;
  const Rigid3d world_from_imu = *fa.world_from_cam * dataset.cam_from_imu;
  const Eigen::Vector3d tilt(a_sigma * normal(rng), a_sigma * normal(rng), 0.0);
  state.world_from_imu = Rigid3d(Eigen::Quaterniond(ExpSO3(tilt)) * world_from_imu.rotation,
                                 world_from_imu.translation);
  state.velocity_in_world =
      *velocity + v_sigma * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  try {
    out.motion = ComputeCameraMotion(dataset.imu, fa.t_ns, fb.t_ns, state, dataset.imu_params,
                                     dataset.cam_from_imu, options.motion);
  } catch (const OutOfRange& e) {
    reason = std::string("IMU interval not available: ") + e.what();
    return std::nullopt;
  }
  out.ms = MsSince(t0);
  return out;
}

struct CachedFeatures {
  size_t frame = 0;
  DetectorKind kind = DetectorKind::kOrb;
  Features features;
  double ms = 0.0;
};

// Runs one method on one detector's features.
MethodRun RunMethod(MatchMethod method, const PinholeCamera& camera, const CameraMotion& motion,
                    const Features& fa, const Features& fb, const cv::Mat& depth_a,
                    const EvaluationOptions& options, std::vector<Match>& matches,
                    std::vector<KeypointPrediction>& predictions) {
  MethodRun run;
  run.method = method;
  predictions.clear();
  if (method == MatchMethod::kBruteForce || method == MatchMethod::kOwnBruteForce) {
    const auto t0 = Clock::now();
    if (method == MatchMethod::kBruteForce) {
      matches = MatchOpenCvKnnRatio(fa.descriptors, fb.descriptors, options.ratio);
    } else {
      BruteForceOptions bf;
      bf.ratio = options.ratio;
      matches = MatchBruteForce(fa.descriptors, fb.descriptors, bf);
    }
    run.match_ms = MsSince(t0);
    return run;
  }
  PredictionOptions popts = options.prediction;
  if (method == MatchMethod::kFixedWindow) popts.window_mode = WindowMode::kFixed;
  auto t0 = Clock::now();
  const std::vector<KeypointInfo> info_a = ToKeypointInfos(fa.keypoints);
  std::vector<float> depths;
  if (!depth_a.empty())
    depths = SampleDepths(depth_a, camera.depth_scale, info_a, popts.depth_sampling);
  predictions = PredictKeypoints(camera, motion, info_a, depths, popts);
  run.predict_ms = MsSince(t0);
  t0 = Clock::now();
  const std::vector<KeypointInfo> info_b = ToKeypointInfos(fb.keypoints);
  GridIndex grid;
  grid.Build(info_b, camera.width, camera.height,
             static_cast<float>(options.guided.grid_cell_size));
  MatchResult result =
      MatchGuided(predictions, info_a, DescriptorView::FromMat(fa.descriptors), info_b, grid,
                  DescriptorView::FromMat(fb.descriptors), options.guided);
  run.match_ms = MsSince(t0);
  run.stats = result.stats;
  matches = std::move(result.matches);
  return run;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

cv::Mat PadBinaryDescriptors(const cv::Mat& descriptors) {
  if (descriptors.empty() || descriptors.type() != CV_8UC1 || descriptors.cols % 8 == 0) {
    return descriptors;
  }
  const int cols = (descriptors.cols + 7) / 8 * 8;
  cv::Mat padded = cv::Mat::zeros(descriptors.rows, cols, CV_8UC1);
  descriptors.copyTo(padded(cv::Rect(0, 0, descriptors.cols, descriptors.rows)));
  return padded;
}

FrameReader MakeDiskFrameReader(const Dataset& dataset) {
  auto frames = std::make_shared<std::vector<FrameRecord>>(dataset.frames);
  const int width = dataset.camera.width, height = dataset.camera.height;
  return [frames, width, height](size_t index, bool with_depth) {
    IMUMATCH_CHECK(index < frames->size(), "frame index " << index);
    const FrameRecord& f = (*frames)[index];
    FrameImages out;
    out.image = LoadImage(f.image_path, ImageColor::kGray);
    if (width > 0 && height > 0 && (out.image.cols != width || out.image.rows != height)) {
      throw InputError(f.image_path, "image is " + std::to_string(out.image.cols) + "x" +
                                         std::to_string(out.image.rows) + ", the camera is " +
                                         std::to_string(width) + "x" + std::to_string(height));
    }
    if (with_depth && !f.depth_path.empty()) out.depth = LoadDepth(f.depth_path, out.image.size());
    return out;
  };
}

EvalSource MakeDiskSource(Dataset dataset) {
  EvalSource source;
  source.reader = MakeDiskFrameReader(dataset);
  source.exact_ground_truth = dataset.kind == DatasetKind::kSynthetic;
  source.dataset = std::move(dataset);
  return source;
}

EvalSource MakeSyntheticSource(const SyntheticSequence& sequence, const std::string& case_name) {
  EvalSource source;
  Dataset& d = source.dataset;
  d.name = case_name.empty() ? sequence.motion : case_name;
  d.root = "<memory>";
  d.kind = DatasetKind::kSynthetic;
  d.camera = sequence.camera;
  d.imu_params = sequence.imu_params;
  d.cam_from_imu = sequence.cam_from_imu;
  d.imu_simulated = true;
  d.imu_source_note = "simulated IMU (in-memory synthetic sequence)";
  for (const ImuSample& s : sequence.imu) d.imu.Push(s, "synthetic imu");
  struct Encoded {
    std::vector<uchar> image, depth;
  };
  auto encoded = std::make_shared<std::vector<Encoded>>();
  for (size_t i = 0; i < sequence.frames.size(); ++i) {
    const SyntheticFrame& f = sequence.frames[i];
    FrameRecord r;
    r.t_ns = f.t_ns;
    r.image_path = "<memory>/rgb/" + std::to_string(i) + ".png";
    r.depth_path = "<memory>/depth/" + std::to_string(i) + ".png";
    r.world_from_cam = f.world_from_cam;
    r.imu_velocity_in_world = f.imu_velocity_in_world;
    d.frames.push_back(r);
    d.groundtruth_world_from_cam.push_back({f.t_ns, f.world_from_cam});
    Encoded e;
    cv::imencode(".png", f.rgb, e.image);
    cv::imencode(".png", f.depth, e.depth);
    encoded->push_back(std::move(e));
  }
  source.reader = [encoded](size_t index, bool with_depth) {
    IMUMATCH_CHECK(index < encoded->size(), "frame index " << index);
    FrameImages out;
    out.image = cv::imdecode((*encoded)[index].image, cv::IMREAD_GRAYSCALE);
    if (with_depth) out.depth = cv::imdecode((*encoded)[index].depth, cv::IMREAD_UNCHANGED);
    return out;
  };
  source.exact_ground_truth = true;
  return source;
}

// ---------------------------------------------------------------------------------------------

void PairSelection::Check() const {
  IMUMATCH_CHECK(std::isfinite(interval_s) && interval_s >= 0.0, "interval_s = " << interval_s);
  IMUMATCH_CHECK(step >= 1, "step = " << step);
}

std::vector<FramePair> SelectFramePairs(const std::vector<FrameRecord>& frames,
                                        const PairSelection& selection) {
  selection.Check();
  std::vector<FramePair> pairs;
  const size_t n = frames.size();
  auto full = [&] { return selection.max_pairs > 0 && pairs.size() >= selection.max_pairs; };
  if (!selection.explicit_pairs.empty()) {
    for (const FramePair& p : selection.explicit_pairs) {
      IMUMATCH_CHECK(p.a < n && p.b < n,
                     "frame pair (" << p.a << ", " << p.b << ") outside the " << n << " frames");
      IMUMATCH_CHECK(p.a != p.b, "frame pair (" << p.a << ", " << p.b << ") uses one frame twice");
      if (full()) break;
      pairs.push_back(p);
    }
    return pairs;
  }
  if (selection.interval_s > 0.0) {
    const int64_t interval_ns = SecondsToNs(selection.interval_s);
    size_t a = 0;
    while (a + 1 < n && !full()) {
      const int64_t target = frames[a].t_ns + interval_ns;
      size_t b = a + 1;
      while (b + 1 < n &&
             std::llabs(frames[b + 1].t_ns - target) <= std::llabs(frames[b].t_ns - target))
        ++b;
      // Stop when the sequence ends before the interval is (nearly) covered.
      if (frames[b].t_ns - frames[a].t_ns < interval_ns / 2) break;
      pairs.push_back({a, b});
      a = b;
    }
    return pairs;
  }
  const size_t step = static_cast<size_t>(selection.step);
  for (size_t a = 0; a + step < n && !full(); a += step) pairs.push_back({a, a + step});
  return pairs;
}

// ---------------------------------------------------------------------------------------------

std::string ToString(MatchMethod method) {
  switch (method) {
    case MatchMethod::kBruteForce:
      return "bf";
    case MatchMethod::kGuided:
      return "guided";
    case MatchMethod::kFixedWindow:
      return "fixed10";
    case MatchMethod::kOwnBruteForce:
      return "bf_own";
  }
  return "?";
}

std::string DisplayName(MatchMethod method) {
  switch (method) {
    case MatchMethod::kBruteForce:
      return "BF knn+ratio (OpenCV)";
    case MatchMethod::kGuided:
      return "IMU-guided";
    case MatchMethod::kFixedWindow:
      return "IMU fixed +-10 px";
    case MatchMethod::kOwnBruteForce:
      return "BF ratio (imumatch)";
  }
  return "?";
}

MatchMethod ParseMatchMethod(std::string_view name) {
  const std::string n = Lower(name);
  if (n == "bf" || n == "bf_opencv") return MatchMethod::kBruteForce;
  if (n == "guided") return MatchMethod::kGuided;
  if (n == "fixed10" || n == "fixed") return MatchMethod::kFixedWindow;
  if (n == "bf_own") return MatchMethod::kOwnBruteForce;
  throw InvalidArgument("unknown method '" + std::string(name) +
                        "' (valid: bf, guided, fixed10, bf_own)");
}

bool UsesPrediction(MatchMethod method) {
  return method == MatchMethod::kGuided || method == MatchMethod::kFixedWindow;
}

MotionSource ParseMotionSource(std::string_view name) {
  const std::string n = Lower(name);
  if (n == "imu") return MotionSource::kImu;
  if (n == "gt" || n == "groundtruth") return MotionSource::kGroundTruth;
  throw InvalidArgument("unknown motion source '" + std::string(name) + "' (valid: imu, gt)");
}

const char* ToString(MotionSource source) { return source == MotionSource::kImu ? "imu" : "gt"; }

void EvaluationOptions::Check() const {
  IMUMATCH_CHECK(!detectors.empty(), "no detector selected");
  IMUMATCH_CHECK(!methods.empty(), "no method selected");
  features.Check();
  IMUMATCH_CHECK(ratio > 0.0 && ratio <= 1.0, "ratio = " << ratio);
  motion.Check();
  prediction.Check();
  guided.Check();
  ground_truth.Check();
  IMUMATCH_CHECK(keep_visuals >= 0, "keep_visuals = " << keep_visuals);
  IMUMATCH_CHECK(queue_capacity >= 0 && queue_capacity <= 16,
                 "queue_capacity = " << queue_capacity);
}

void EvaluationResult::Append(EvaluationResult other) {
  for (auto& r : other.records) records.push_back(std::move(r));
  for (auto& s : other.skipped) skipped.push_back(std::move(s));
  for (auto& v : other.visuals) visuals.push_back(std::move(v));
  for (auto& n : other.notes) notes.push_back(std::move(n));
  pairs_total += other.pairs_total;
  wall_s += other.wall_s;
}

EvaluationResult EvaluateSource(const EvalSource& source, const std::vector<FramePair>& pairs,
                                const EvaluationOptions& options, const std::string& case_name) {
  options.Check();
  IMUMATCH_CHECK(static_cast<bool>(source.reader), "the source has no frame reader");
  const Dataset& dataset = source.dataset;
  const std::string name = case_name.empty() ? dataset.name : case_name;
  EvaluationResult result;
  result.pairs_total = pairs.size();
  for (const FramePair& p : pairs) {
    IMUMATCH_CHECK(p.a < dataset.frames.size() && p.b < dataset.frames.size(),
                   "frame pair outside the dataset");
  }
  const bool dataset_has_depth =
      std::any_of(dataset.frames.begin(), dataset.frames.end(),
                  [](const FrameRecord& f) { return !f.depth_path.empty(); });
  if (!dataset_has_depth) {
    result.notes.push_back(name +
                           ": no depth images: predictions use epipolar segments and "
                           "matches are judged by epipolar distance only");
  }
  const auto wall0 = Clock::now();
  std::vector<CachedFeatures> cache;  // features of the previous pair's frame B

  PairReader pair_reader(source.reader, pairs);
  size_t done = 0;
  auto process = [&](PairItem item) {
    const size_t index = done++;
    const FramePair& pair = pairs[index];
    auto skip = [&](const std::string& detector, const std::string& reason) {
      result.skipped.push_back({name, index, pair.a, pair.b, detector, reason});
    };
    auto report_progress = [&] {
      if (options.progress) options.progress(done, pairs.size());
    };
    const FrameRecord& fa = dataset.frames[pair.a];
    const FrameRecord& fb = dataset.frames[pair.b];
    if (!item.error.empty()) {
      skip("", item.error);
      cache.clear();
      return report_progress();
    }
    if (!fa.world_from_cam || !fb.world_from_cam) {
      skip("",
           "no ground-truth pose for frame " + std::to_string(fa.world_from_cam ? pair.b : pair.a));
      return report_progress();
    }
    if (dataset_has_depth && item.a.depth.empty()) {
      skip("", "no depth image for frame A (" + std::to_string(pair.a) + ")");
      return report_progress();
    }
    std::string reason;
    const std::optional<PairMotion> motion =
        ComputePairMotion(dataset, pair, index, options, reason);
    if (!motion) {
      skip("", reason);
      return report_progress();
    }
    const CameraMotion gt =
        CameraMotionFromPoses(fa.t_ns, *fa.world_from_cam, fb.t_ns, *fb.world_from_cam);

    std::vector<CachedFeatures> next_cache;
    for (DetectorKind kind : options.detectors) {
      FeatureOptions fopts = options.features;
      fopts.kind = kind;
      auto extract = [&](size_t frame, const cv::Mat& image) {
        for (CachedFeatures& c : cache) {
          if (c.frame == frame && c.kind == kind) return c;
        }
        CachedFeatures c;
        c.frame = frame;
        c.kind = kind;
        const auto t0 = Clock::now();
        c.features = ExtractFeatures(image, fopts);
        c.features.descriptors = PadBinaryDescriptors(c.features.descriptors);
        c.ms = MsSince(t0);
        return c;
      };
      const CachedFeatures ca = extract(pair.a, item.a.image);
      const CachedFeatures cb = extract(pair.b, item.b.image);
      next_cache.push_back(cb);
      const Features& feat_a = ca.features;
      const Features& feat_b = cb.features;
      const int na = static_cast<int>(feat_a.keypoints.size());
      const int nb = static_cast<int>(feat_b.keypoints.size());
      if (na < 2 || nb < 2) {
        skip(ToString(kind),
             "too few features (A: " + std::to_string(na) + ", B: " + std::to_string(nb) + ")");
        continue;
      }
      const PairGroundTruth judge(dataset.camera, gt.cam_b_from_cam_a, item.a.depth,
                                  feat_a.keypoints, feat_b.keypoints, options.ground_truth);
      DetectorPairRecord rec;
      rec.case_name = name;
      rec.pair_index = index;
      rec.frame_a = pair.a;
      rec.frame_b = pair.b;
      rec.t_a_ns = fa.t_ns;
      rec.t_b_ns = fb.t_ns;
      rec.detector = kind;
      rec.keypoints_a = na;
      rec.keypoints_b = nb;
      rec.keypoints_a_with_depth = judge.num_with_depth();
      rec.read_ms = item.read_ms;
      rec.extract_ms = ca.ms + cb.ms;
      rec.motion_ms = motion->ms;
      rec.motion_rotation_error_deg =
          RotationDistance(motion->motion.cam_b_from_cam_a.rotation, gt.cam_b_from_cam_a.rotation) *
          180.0 / M_PI;
      rec.motion_translation_error_m =
          (motion->motion.cam_b_from_cam_a.translation - gt.cam_b_from_cam_a.translation).norm();
      rec.candidates = judge.candidates();
      PairVisual visual;
      const bool keep_visual = static_cast<int>(index) < options.keep_visuals;
      if (keep_visual) {
        visual.case_name = name;
        visual.pair_index = index;
        visual.detector = kind;
        visual.image_a = item.a.image;
        visual.image_b = item.b.image;
        visual.keypoints_a = feat_a.keypoints;
        visual.keypoints_b = feat_b.keypoints;
      }
      std::vector<Match> matches;
      std::vector<KeypointPrediction> predictions;
      for (MatchMethod method : options.methods) {
        MethodRun run = RunMethod(method, dataset.camera, motion->motion, feat_a, feat_b,
                                  item.a.depth, options, matches, predictions);
        run.residuals = judge.Judge(matches);
        if (keep_visual) {
          visual.runs.push_back({method, matches, run.residuals, predictions});
        }
        rec.runs.push_back(std::move(run));
      }
      result.records.push_back(std::move(rec));
      if (keep_visual) result.visuals.push_back(std::move(visual));
    }
    cache = std::move(next_cache);
    report_progress();
  };
  RunPipelined<PairItem>(
      pairs.size(), options.queue_capacity, [&](size_t i) { return pair_reader(i); }, process);
  result.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  return result;
}

ThresholdChoice ChooseThreshold(const EvaluationResult& result, bool exact_ground_truth,
                                std::optional<double> explicit_px) {
  ThresholdChoice choice;
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  if (explicit_px) {
    IMUMATCH_CHECK(std::isfinite(*explicit_px) && *explicit_px > 0.0,
                   "threshold = " << *explicit_px);
    choice.threshold_px = *explicit_px;
    out << "threshold " << choice.threshold_px << " px (given)";
  } else if (exact_ground_truth) {
    choice.threshold_px = 1.5;
    out << "threshold 1.50 px (exact synthetic ground truth)";
  } else {
    std::vector<float> residuals;
    for (const DetectorPairRecord& rec : result.records) {
      for (const MethodRun& run : rec.runs) {
        if (run.method != MatchMethod::kBruteForce && run.method != MatchMethod::kOwnBruteForce)
          continue;
        for (const MatchResidual& r : run.residuals) {
          if (r.kind == ResidualKind::kDepth) residuals.push_back(r.residual_px);
        }
        break;  // one brute-force method per record is enough
      }
    }
    const AutoThreshold a = ComputeAutoThreshold(residuals);
    choice.automatic = a;
    choice.threshold_px = a.threshold_px;
    out << a.Describe();
  }
  choice.description = out.str();
  return choice;
}

// ---------------------------------------------------------------------------------------------

StageStats ComputeStageStats(std::vector<double> values) {
  StageStats s;
  s.count = static_cast<int>(values.size());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  double sum = 0.0;
  for (double v : values) sum += v;
  s.mean = sum / static_cast<double>(values.size());
  auto rank = [&](double q) {
    const size_t k = static_cast<size_t>(std::ceil(q * static_cast<double>(values.size())));
    return values[std::min(values.size() - 1, k == 0 ? 0 : k - 1)];
  };
  s.p50 = rank(0.50);
  s.p90 = rank(0.90);
  s.p99 = rank(0.99);
  return s;
}

RunCounts CountRun(const DetectorPairRecord& record, const MethodRun& run, double threshold_px) {
  RunCounts c;
  c.counts = CountCorrect(run.residuals, threshold_px);
  c.possible = CountPossibleCorrespondences(record.candidates, threshold_px);
  c.precision =
      c.counts.matches > 0 ? static_cast<double>(c.counts.correct) / c.counts.matches : 0.0;
  c.recall = c.possible > 0
                 ? std::min(1.0, static_cast<double>(c.counts.correct_by_depth) / c.possible)
                 : 0.0;
  return c;
}

std::vector<MethodSummary> Summarize(const std::vector<DetectorPairRecord>& records,
                                     double threshold_px) {
  // Keys in order of first appearance of the case, then detector and method enum order.
  std::vector<std::string> cases;
  for (const auto& r : records) {
    if (std::find(cases.begin(), cases.end(), r.case_name) == cases.end())
      cases.push_back(r.case_name);
  }
  struct Acc {
    std::vector<double> read, extract, predict, match, total;
    double keypoints = 0, matches = 0, correct = 0, wrong = 0, possible = 0, correct_depth = 0,
           epipolar = 0;
    int pairs = 0;
  };
  std::map<std::tuple<size_t, int, int>, Acc> acc;
  for (const auto& r : records) {
    const size_t case_index =
        static_cast<size_t>(std::find(cases.begin(), cases.end(), r.case_name) - cases.begin());
    for (const MethodRun& run : r.runs) {
      Acc& a = acc[{case_index, static_cast<int>(r.detector), static_cast<int>(run.method)}];
      const RunCounts c = CountRun(r, run, threshold_px);
      const double motion = UsesPrediction(run.method) ? r.motion_ms : 0.0;
      a.read.push_back(r.read_ms);
      a.extract.push_back(r.extract_ms);
      a.predict.push_back(run.predict_ms + motion);
      a.match.push_back(run.match_ms);
      a.total.push_back(r.extract_ms + motion + run.predict_ms + run.match_ms);
      a.keypoints += 0.5 * (r.keypoints_a + r.keypoints_b);
      a.matches += c.counts.matches;
      a.correct += c.counts.correct;
      a.wrong += c.counts.wrong;
      a.possible += c.possible;
      a.correct_depth += c.counts.correct_by_depth;
      a.epipolar += c.counts.matches - c.counts.judged_by_depth;
      ++a.pairs;
    }
  }
  std::vector<MethodSummary> out;
  for (const auto& [key, a] : acc) {
    MethodSummary s;
    s.case_name = cases[std::get<0>(key)];
    s.detector = static_cast<DetectorKind>(std::get<1>(key));
    s.method = static_cast<MatchMethod>(std::get<2>(key));
    s.pairs = a.pairs;
    const double n = std::max(1, a.pairs);
    s.keypoints = a.keypoints / n;
    s.read_ms = ComputeStageStats(a.read);
    s.extract_ms = ComputeStageStats(a.extract);
    s.predict_ms = ComputeStageStats(a.predict);
    s.match_ms = ComputeStageStats(a.match);
    s.total_ms = ComputeStageStats(a.total);
    s.matches = a.matches / n;
    s.correct = a.correct / n;
    s.wrong = a.wrong / n;
    s.possible = a.possible / n;
    s.precision = a.matches > 0 ? a.correct / a.matches : 0.0;
    s.recall = a.possible > 0 ? std::min(1.0, a.correct_depth / a.possible) : 0.0;
    s.epipolar_fraction = a.matches > 0 ? a.epipolar / a.matches : 0.0;
    out.push_back(s);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------

void EndToEndOptions::Check() const {
  IMUMATCH_CHECK(max_frames >= 2, "max_frames = " << max_frames);
  IMUMATCH_CHECK(max_keypoints >= 1, "max_keypoints = " << max_keypoints);
}

std::string EndToEndTiming::Describe() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  out << "end-to-end ORB pipeline over " << frames << " frames (" << width << "x" << height
      << "): sequential OpenCV (imread + ORB + BFMatcher knn/ratio) " << sequential_ms_per_frame
      << " ms/frame, imumatch pipelined (reader thread + ORB + IMU + guided) "
      << pipelined_ms_per_frame << " ms/frame";
  if (pipelined_ms_per_frame > 0.0) {
    out << " (x" << sequential_ms_per_frame / pipelined_ms_per_frame << ")";
  }
  if (motion_failures > 0) out << "; " << motion_failures << " frames had no motion";
  return out.str();
}

EndToEndTiming MeasureEndToEnd(const EvalSource& source, const EvaluationOptions& options,
                               const EndToEndOptions& e2e) {
  e2e.Check();
  options.Check();
  const Dataset& dataset = source.dataset;
  EndToEndTiming timing;
  if (e2e.first_frame >= dataset.frames.size()) return timing;
  const size_t n = std::min(e2e.max_frames, dataset.frames.size() - e2e.first_frame);
  if (n < 2) return timing;
  timing.frames = static_cast<int>(n);

  // Sequential plain OpenCV.
  {
    cv::Ptr<cv::ORB> orb = cv::ORB::create(e2e.max_keypoints);
    cv::BFMatcher matcher(cv::NORM_HAMMING);
    std::vector<cv::KeyPoint> kp_prev, kp;
    cv::Mat desc_prev, desc;
    const auto t0 = Clock::now();
    for (size_t i = 0; i < n; ++i) {
      const FrameImages img = source.reader(e2e.first_frame + i, false);
      timing.width = img.image.cols;
      timing.height = img.image.rows;
      orb->detectAndCompute(img.image, cv::noArray(), kp, desc);
      if (i > 0 && !desc.empty() && !desc_prev.empty()) {
        std::vector<std::vector<cv::DMatch>> knn;
        matcher.knnMatch(desc_prev, desc, knn, 2);
        for (const auto& m : knn) {
          if (m.size() == 1 || (m.size() >= 2 && m[0].distance < options.ratio * m[1].distance))
            ++timing.sequential_matches;
        }
      }
      std::swap(kp_prev, kp);
      std::swap(desc_prev, desc);
    }
    timing.sequential_ms_per_frame = MsSince(t0) / static_cast<double>(n);
  }

  // imumatch, pipelined.
  {
    FeatureOptions fopts = options.features;
    fopts.kind = DetectorKind::kOrb;
    fopts.max_keypoints = e2e.max_keypoints;
    GuidedMatcherWorkspace workspace;
    Features prev;
    cv::Mat prev_depth;
    const auto t0 = Clock::now();
    size_t i = 0;
    RunPipelined<FrameImages>(
        n, 2, [&](size_t k) { return source.reader(e2e.first_frame + k, true); },
        [&](FrameImages img) {
          const size_t index = e2e.first_frame + i;
          Features cur = ExtractFeatures(img.image, fopts);
          if (i > 0) {
            std::string reason;
            const std::optional<PairMotion> motion =
                (dataset.frames[index - 1].world_from_cam && dataset.frames[index].world_from_cam)
                    ? ComputePairMotion(dataset, {index - 1, index}, i, options, reason)
                    : std::nullopt;
            if (motion) {
              const MatchResult r = workspace.Match(
                  dataset.camera, motion->motion, prev.keypoints, prev.descriptors, prev_depth,
                  cur.keypoints, cur.descriptors, options.prediction, options.guided);
              timing.pipelined_matches += static_cast<int>(r.matches.size());
            } else {
              ++timing.motion_failures;
              timing.pipelined_matches += static_cast<int>(
                  MatchOpenCvKnnRatio(prev.descriptors, cur.descriptors, options.ratio).size());
            }
          }
          prev = std::move(cur);
          prev_depth = img.depth;
          ++i;
        });
    timing.pipelined_ms_per_frame = MsSince(t0) / static_cast<double>(n);
  }
  return timing;
}

}  // namespace imumatch
