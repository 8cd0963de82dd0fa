// Writes small seed images for the load_image and load_depth fuzz targets: a 32x32 crop of each
// given image in every format cv::imwrite can encode here (8-bit: gray, colour and BGRA; 16-bit
// single channel: depth). Not a fuzz target; scripts/fuzz-smoke and scripts/fuzz-campaign call it
// with the shared data excerpts.
//   imumatch_fuzz_image_seeds <image seed dir> <depth seed dir> <image or depth file>...
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace {

int Write(const std::filesystem::path& path, const cv::Mat& image) {
  try {
    return cv::imwrite(path.string(), image) ? 1 : 0;
  } catch (const cv::Exception&) {
    return 0;  // format not built into this OpenCV
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s <image seed dir> <depth seed dir> <file>...\n", argv[0]);
    return 2;
  }
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  const std::filesystem::path image_dir = argv[1], depth_dir = argv[2];
  std::filesystem::create_directories(image_dir);
  std::filesystem::create_directories(depth_dir);
  int written = 0;
  for (int a = 3; a < argc; ++a) {
    const cv::Mat full = cv::imread(argv[a], cv::IMREAD_UNCHANGED);
    if (full.empty() || full.cols < 32 || full.rows < 32) {
      std::fprintf(stderr, "skipping %s (not an image of at least 32x32)\n", argv[a]);
      continue;
    }
    const cv::Mat crop = full(cv::Rect((full.cols - 32) / 2, (full.rows - 32) / 2, 32, 32)).clone();
    const std::string stem = std::filesystem::path(argv[a]).stem().string();
    if (crop.depth() == CV_16U && crop.channels() == 1) {
      for (const char* ext : {".png", ".tiff", ".pgm"}) {
        written += Write(depth_dir / (stem + ext), crop);
      }
      continue;
    }
    if (crop.depth() != CV_8U) continue;
    cv::Mat gray, color, bgra;
    if (crop.channels() == 1) {
      gray = crop;
      cv::cvtColor(crop, color, cv::COLOR_GRAY2BGR);
    } else {
      color = crop.channels() == 3 ? crop : cv::Mat();
      if (color.empty()) cv::cvtColor(crop, color, cv::COLOR_BGRA2BGR);
      cv::cvtColor(color, gray, cv::COLOR_BGR2GRAY);
    }
    cv::cvtColor(color, bgra, cv::COLOR_BGR2BGRA);
    for (const char* ext : {".png", ".jpg", ".bmp", ".tiff", ".webp", ".jp2", ".ras"}) {
      written += Write(image_dir / (stem + "_gray" + ext), gray);
      written += Write(image_dir / (stem + "_color" + ext), color);
    }
    written += Write(image_dir / (stem + "_gray.pgm"), gray);
    written += Write(image_dir / (stem + "_color.ppm"), color);
    written += Write(image_dir / (stem + "_bgra.png"), bgra);
  }
  std::printf("%d seed images written\n", written);
  return written > 0 ? 0 : 1;
}
