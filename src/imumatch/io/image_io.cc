#include "imumatch/io/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/output_files.h"
#include "imumatch/io/plausibility.h"
#include "imumatch/io/png_decoder.h"

namespace imumatch {
namespace {

std::string SizeText(const cv::Size& s) {
  std::ostringstream out;
  out << s.width << "x" << s.height;
  return out.str();
}

std::string DepthText(int depth) {
  switch (depth) {
    case CV_8U:
      return "8-bit unsigned";
    case CV_8S:
      return "8-bit signed";
    case CV_16U:
      return "16-bit unsigned";
    case CV_16S:
      return "16-bit signed";
    case CV_32F:
      return "32-bit float";
    default:
      return "type " + std::to_string(depth);
  }
}

// The size an image file claims in its header, read before decoding so that a few bytes cannot
// make the decoder allocate gigabytes. PNG, JPEG, BMP and PNM (PGM/PPM) are read; any other
// format is refused (InputError), since its size could not be checked first.
std::pair<int64_t, int64_t> HeaderSize(const std::string& bytes, const std::string& path) {
  const std::string_view head(bytes.data(), std::min<size_t>(bytes.size(), 65536));
  auto byte = [&](size_t i) { return static_cast<uint32_t>(static_cast<unsigned char>(head[i])); };
  auto be32 = [&](size_t i) {
    return byte(i) << 24 | byte(i + 1) << 16 | byte(i + 2) << 8 | byte(i + 3);
  };
  auto be16 = [&](size_t i) { return byte(i) << 8 | byte(i + 1); };
  auto le32 = [&](size_t i) {
    return static_cast<int32_t>(byte(i) | byte(i + 1) << 8 | byte(i + 2) << 16 | byte(i + 3) << 24);
  };
  if (head.size() >= 24 && head.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0 &&
      head.compare(12, 4, "IHDR") == 0) {
    return {int64_t{be32(16)}, int64_t{be32(20)}};
  }
  if (head.size() >= 4 && byte(0) == 0xFF && byte(1) == 0xD8) {  // JPEG: walk the markers
    size_t i = 2;
    while (i + 9 < head.size() && byte(i) == 0xFF) {
      const uint32_t marker = byte(i + 1);
      const bool sof =
          marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
      if (sof) return {int64_t{be16(i + 7)}, int64_t{be16(i + 5)}};
      i += 2 + be16(i + 2);
    }
    throw InputError(path, "JPEG without a frame header in its first 64 KiB");
  }
  if (head.size() >= 26 && head.compare(0, 2, "BM") == 0) {  // BMP: BITMAPINFOHEADER or later
    const int64_t w = le32(18), h = le32(22);
    return {w, h < 0 ? -h : h};
  }
  if (head.size() >= 3 && head[0] == 'P' && head[1] >= '1' && head[1] <= '6') {  // PNM
    std::istringstream text(std::string(head.substr(2)));
    int64_t w = 0, h = 0;
    std::string token;
    std::vector<int64_t> v;
    while (v.size() < 2 && text >> token) {
      if (token[0] == '#') {
        std::getline(text, token);
        continue;
      }
      try {
        v.push_back(std::stoll(token));
      } catch (const std::exception&) {
        throw InputError(path, "PNM header without a valid size");
      }
    }
    if (v.size() < 2) throw InputError(path, "PNM header without a valid size");
    w = v[0];
    h = v[1];
    return {w, h};
  }
  throw InputError(path,
                   "not a PNG, JPEG, BMP or PNM image (the formats whose size imumatch checks "
                   "before decoding)");
}

// The whole file, with the checks that need the path (exists, not a folder); DecodeChecked checks
// the bytes (empty, too large, header size).
std::string ReadFileChecked(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "image file not found");
  if (fs::is_directory(path, ec)) throw InputError(path, "is a folder, not an image file");
  // Read once: the header's size is checked on the same bytes that are then decoded.
  std::string file;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "cannot open image file");
    std::ostringstream buffer;
    buffer << in.rdbuf();
    file = buffer.str();
  }
  return file;
}

// Decodes an image file's bytes: PNGs through DecodePngFast when it handles them, everything else
// (and every PNG it refuses) with cv::imdecode(IMREAD_UNCHANGED). The header's size is checked
// before anything is allocated. gray: an 8-bit colour image comes back as gray, converted as
// cv::cvtColor does (the fast path fuses it into its pass); other images come back unchanged.
cv::Mat DecodeChecked(const std::string& file, const std::string& path, bool gray) {
  if (file.empty()) throw InputError(path, "image file is empty (0 bytes)");
  if (file.size() > static_cast<size_t>(std::numeric_limits<int>::max())) {
    throw InputError(path, "image file larger than 2 GiB");
  }
  const auto [width, height] = HeaderSize(file, path);
  plausibility::CheckImageSize(width, height, path);
  cv::Mat image = DecodePngFast(reinterpret_cast<const uint8_t*>(file.data()), file.size(),
                                gray ? PngOutput::kGray : PngOutput::kUnchanged);
  if (image.empty()) {
    try {
      image = cv::imdecode(
          cv::Mat(1, static_cast<int>(file.size()), CV_8UC1, const_cast<char*>(file.data())),
          cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
      throw InputError(path, std::string("cannot decode image: ") + e.what());
    }
    if (image.empty()) {
      throw InputError(path, "cannot decode image (unreadable, truncated or not an image format)");
    }
  }
  plausibility::CheckImageSize(image.cols, image.rows, path);
  return image;
}

cv::Mat ToImage(const cv::Mat& decoded, const std::string& path, ImageColor color,
                SixteenBitImages sixteen_bit) {
  cv::Mat raw = decoded;
  if (raw.type() == CV_16UC1 && sixteen_bit == SixteenBitImages::kScaleTo8Bit) {
    raw.convertTo(raw, CV_8U, 1.0 / 257.0);  // 65535 -> 255, rounded (saturate_cast)
  }
  if (raw.depth() != CV_8U) {
    throw InputError(path, "expected an 8-bit image, got " + DepthText(raw.depth()) +
                               " (is this a depth image?)");
  }
  cv::Mat out;
  const int channels = raw.channels();
  if (color == ImageColor::kGray) {
    if (channels == 1) {
      out = raw;
    } else if (channels == 3) {
      cv::cvtColor(raw, out, cv::COLOR_BGR2GRAY);
    } else if (channels == 4) {
      cv::cvtColor(raw, out, cv::COLOR_BGRA2GRAY);
    }
  } else {
    if (channels == 1) {
      cv::cvtColor(raw, out, cv::COLOR_GRAY2BGR);
    } else if (channels == 3) {
      out = raw;
    } else if (channels == 4) {
      cv::cvtColor(raw, out, cv::COLOR_BGRA2BGR);
    }
  }
  if (out.empty()) {
    throw InputError(path, "unsupported number of channels: " + std::to_string(channels));
  }
  return out;
}

cv::Mat ToDepth(const cv::Mat& raw, const std::string& path, cv::Size expected_size) {
  if (raw.depth() != CV_16U || raw.channels() != 1) {
    throw InputError(path,
                     "depth must be a 16-bit single-channel PNG (raw / depth_scale = metres), "
                     "got " +
                         DepthText(raw.depth()) + " with " + std::to_string(raw.channels()) +
                         " channel(s)");
  }
  if (expected_size != cv::Size() && raw.size() != expected_size) {
    throw InputError(
        path, "depth image is " + SizeText(raw.size()) + ", expected " + SizeText(expected_size));
  }
  return raw;
}

}  // namespace

cv::Mat LoadImage(const std::string& path, ImageColor color, SixteenBitImages sixteen_bit) {
  return DecodeImage(ReadFileChecked(path), path, color, sixteen_bit);
}

cv::Mat LoadDepth(const std::string& path, cv::Size expected_size) {
  return DecodeDepth(ReadFileChecked(path), path, expected_size);
}

cv::Mat DecodeImage(const std::string& bytes, const std::string& name, ImageColor color,
                    SixteenBitImages sixteen_bit) {
  return ToImage(DecodeChecked(bytes, name, color == ImageColor::kGray), name, color, sixteen_bit);
}

cv::Mat DecodeDepth(const std::string& bytes, const std::string& name, cv::Size expected_size) {
  return ToDepth(DecodeChecked(bytes, name, false), name, expected_size);
}

RgbdImages LoadRgbd(const std::string& image_path, const std::string& depth_path,
                    ImageColor color) {
  RgbdImages out;
  out.image = LoadImage(image_path, color, SixteenBitImages::kRefuse);
  const cv::Mat depth = LoadDepth(depth_path);
  if (depth.size() != out.image.size()) {
    throw InputError(depth_path, "depth image is " + SizeText(depth.size()) +
                                     " but the colour image " + image_path + " is " +
                                     SizeText(out.image.size()));
  }
  out.depth = depth;
  return out;
}

cv::Mat DepthToMetres(const cv::Mat& raw_depth, double depth_scale) {
  IMUMATCH_CHECK(raw_depth.type() == CV_16UC1, "raw depth must be CV_16UC1");
  IMUMATCH_CHECK(depth_scale > 0 && std::isfinite(depth_scale), "depth_scale must be positive");
  cv::Mat metres(raw_depth.size(), CV_32FC1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int r = 0; r < raw_depth.rows; ++r) {
    const uint16_t* in = raw_depth.ptr<uint16_t>(r);
    float* out = metres.ptr<float>(r);
    for (int c = 0; c < raw_depth.cols; ++c) {
      out[c] = in[c] == 0 ? nan : static_cast<float>(in[c] / depth_scale);
    }
  }
  return metres;
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  IMUMATCH_CHECK(!image.empty(), "cannot write an empty image to " << path);
  const std::string ext = std::filesystem::path(path).extension().string();
  std::vector<uchar> bytes;
  bool ok = false;
  try {
    ok = cv::imencode(ext.empty() ? ".png" : ext, image, bytes);
  } catch (const cv::Exception& e) {
    throw Error("cannot write image " + path + ": " + e.what());
  }
  if (!ok) throw Error("cannot write image " + path);
  // Temporary file + rename: never a truncated image, never a hard-linked file rewritten in place.
  WriteFileAtomic(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace imumatch
