// Speed and quality of the feature detectors/descriptors.
//
//   features_benchmark [--benchmark_... flags] [image.png] [opencv_data_dir]
//
// image.png defaults to <IMUMATCH_DATA_DIR>/tum_fr1_xyz_pair/img_prev.png (640x480, also read
// from the IMUMATCH_DATA_DIR environment variable); opencv_data_dir (graf1.png, graf3.png,
// H1to3p.xml, from the opencv-doc package) defaults to /usr/share/doc/opencv-doc/examples/data.
// After the Google Benchmark runs, prints a median-of-runs timing summary with the SURF/SIFT
// ratio and a quality table (repeatability and matching precision on graf1 -> graf3 and on a
// synthetic 30-degree rotation of the input image).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/features/feature_factory.h"
#include "imumatch/features/homography_eval.h"
#include "imumatch/features/surf.h"

namespace {

std::string g_image_path;
std::string g_opencv_data_dir = IMUMATCH_BENCH_OPENCV_DATA_DIR;

const cv::Mat& Image() {
  static const cv::Mat image = [] {
    cv::Mat img = cv::imread(g_image_path, cv::IMREAD_GRAYSCALE);
    if (img.empty()) {
      std::fprintf(stderr, "cannot read %s\n", g_image_path.c_str());
      std::exit(2);
    }
    return img;
  }();
  return image;
}

cv::Ptr<cv::Feature2D> MakeDetector(const std::string& name, bool capped) {
  if (name == "sift_all") return cv::SIFT::create();
  if (name == "surf_all") return imumatch::Surf::Create();
  imumatch::FeatureOptions options;
  options.kind = imumatch::ParseDetectorKind(name);
  options.max_keypoints = capped ? 1000 : 100000;
  return imumatch::CreateFeature2D(options);
}

void RunDetector(benchmark::State& state, const std::string& name) {
  cv::Ptr<cv::Feature2D> detector = MakeDetector(name, true);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    detector->detectAndCompute(Image(), cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(keypoints.size());
}

void BM_SurfAll(benchmark::State& state) { RunDetector(state, "surf_all"); }
void BM_SiftAll(benchmark::State& state) { RunDetector(state, "sift_all"); }
void BM_Surf1000(benchmark::State& state) { RunDetector(state, "surf"); }
void BM_Sift1000(benchmark::State& state) { RunDetector(state, "sift"); }
void BM_Orb1000(benchmark::State& state) { RunDetector(state, "orb"); }
void BM_FastBrief1000(benchmark::State& state) { RunDetector(state, "fast_brief"); }
void BM_SurfUpright(benchmark::State& state) {
  imumatch::SurfOptions options;
  options.upright = true;
  cv::Ptr<cv::Feature2D> detector = imumatch::Surf::Create(options);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    detector->detectAndCompute(Image(), cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(keypoints.size());
}

void BM_SurfDetectOnly(benchmark::State& state) {
  cv::Ptr<cv::Feature2D> detector = imumatch::Surf::Create();
  std::vector<cv::KeyPoint> keypoints;
  for (auto _ : state) {
    detector->detect(Image(), keypoints);
    benchmark::DoNotOptimize(keypoints.data());
  }
  state.counters["keypoints"] = static_cast<double>(keypoints.size());
}

BENCHMARK(BM_SurfDetectOnly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SurfAll)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SiftAll)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SurfUpright)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Surf1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Sift1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Orb1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FastBrief1000)->Unit(benchmark::kMillisecond);

// Median wall time (ms) of `runs` detectAndCompute calls, and the keypoint count.
double MedianMs(const cv::Ptr<cv::Feature2D>& detector, int runs, size_t* count) {
  std::vector<double> times;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    detector->detectAndCompute(Image(), cv::noArray(), keypoints, descriptors);
    const auto t1 = std::chrono::steady_clock::now();
    times.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  std::sort(times.begin(), times.end());
  *count = keypoints.size();
  return times[times.size() / 2];
}

void PrintSpeedSummary() {
  // Single-threaded first: less sensitive to other processes on the machine.
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  size_t n1 = 0;
  size_t n2 = 0;
  const double surf_st_ms = MedianMs(MakeDetector("surf_all", false), 11, &n1);
  const double sift_st_ms = MedianMs(MakeDetector("sift_all", false), 11, &n2);
  cv::setNumThreads(threads);
  std::printf(
      "\nSingle thread, all keypoints: SURF %.1f ms (%zu kp), SIFT %.1f ms (%zu kp): "
      "SURF is %.1fx faster than SIFT\n",
      surf_st_ms, n1, sift_st_ms, n2, sift_st_ms / surf_st_ms);
  size_t n_surf = 0;
  size_t n_sift = 0;
  const double surf_ms = MedianMs(MakeDetector("surf_all", false), 15, &n_surf);
  const double sift_ms = MedianMs(MakeDetector("sift_all", false), 15, &n_sift);
  size_t n_surf_c = 0;
  size_t n_sift_c = 0;
  const double surf_c_ms = MedianMs(MakeDetector("surf", true), 15, &n_surf_c);
  const double sift_c_ms = MedianMs(MakeDetector("sift", true), 15, &n_sift_c);
  std::printf("Speed on %s (%dx%d), %d threads, median of 15 runs, detect+describe:\n",
              g_image_path.c_str(), Image().cols, Image().rows, threads);
  std::printf("  all keypoints: SURF %.1f ms (%zu kp), SIFT %.1f ms (%zu kp)\n", surf_ms, n_surf,
              sift_ms, n_sift);
  std::printf("  capped 1000  : SURF %.1f ms (%zu kp), SIFT %.1f ms (%zu kp)\n", surf_c_ms,
              n_surf_c, sift_c_ms, n_sift_c);
  std::printf("SURF is %.1fx faster than SIFT (all keypoints), %.1fx (1000 keypoints)\n",
              sift_ms / surf_ms, sift_c_ms / surf_c_ms);
}

void PrintQualityRow(const char* pair, const std::string& kind, const cv::Mat& img1,
                     const cv::Mat& img2, const cv::Mat& h) {
  imumatch::FeatureOptions options;
  options.kind = imumatch::ParseDetectorKind(kind);
  options.max_keypoints = 1000;
  const imumatch::Features f1 = imumatch::ExtractFeatures(img1, options);
  const imumatch::Features f2 = imumatch::ExtractFeatures(img2, options);
  const int norm = imumatch::IsBinaryDescriptor(options.kind) ? cv::NORM_HAMMING : cv::NORM_L2;
  const imumatch::HomographyEval e =
      imumatch::EvaluateOnHomography(f1, f2, h, img1.size(), img2.size(), norm);
  std::printf("  %-14s %-10s %5d %5d   %5.3f   %5d %5d   %5.3f\n", pair, kind.c_str(), e.keypoints1,
              e.keypoints2, e.repeatability, e.matches, e.correct_matches, e.precision);
}

void PrintQualitySummary() {
  const std::vector<std::string> kinds = {"surf", "sift", "orb", "fast_brief", "akaze", "brisk"};
  std::printf(
      "\nQuality (max 1000 keypoints, tolerance 3 px, ratio test 0.8):\n"
      "  pair           detector     kp1   kp2   repeat.  match corr.  precision\n");
  const cv::Mat graf1 = cv::imread(g_opencv_data_dir + "/graf1.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat graf3 = cv::imread(g_opencv_data_dir + "/graf3.png", cv::IMREAD_GRAYSCALE);
  cv::Mat h13;
  cv::FileStorage fs(g_opencv_data_dir + "/H1to3p.xml", cv::FileStorage::READ);
  if (fs.isOpened()) fs.getFirstTopLevelNode() >> h13;
  if (graf1.empty() || graf3.empty() || h13.empty()) {
    std::printf("  (graf1/graf3/H1to3p.xml not found in %s; install opencv-doc)\n",
                g_opencv_data_dir.c_str());
  } else {
    for (const std::string& kind : kinds) PrintQualityRow("graf1->graf3", kind, graf1, graf3, h13);
  }
  // Synthetic: rotate the input image by 30 degrees about its centre (same canvas).
  const cv::Mat& img = Image();
  const cv::Point2f centre(0.5f * (img.cols - 1), 0.5f * (img.rows - 1));
  const cv::Mat rot = cv::getRotationMatrix2D(centre, 30.0, 1.0);
  cv::Mat rotated;
  cv::warpAffine(img, rotated, rot, img.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::Mat h = cv::Mat::eye(3, 3, CV_64F);
  rot.copyTo(h.rowRange(0, 2));
  for (const std::string& kind : kinds) PrintQualityRow("rotate 30 deg", kind, img, rotated, h);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::string data_dir = IMUMATCH_BENCH_DATA_DIR;
  if (const char* env = std::getenv("IMUMATCH_DATA_DIR"); env != nullptr && *env != '\0') {
    data_dir = env;
  }
  g_image_path = data_dir + "/tum_fr1_xyz_pair/img_prev.png";
  if (argc > 1) g_image_path = argv[1];
  if (argc > 2) g_opencv_data_dir = argv[2];
  (void)Image();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  PrintSpeedSummary();
  PrintQualitySummary();
  return 0;
}
