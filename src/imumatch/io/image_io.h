#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace imumatch {

// Images are read whole, their header's size checked, then decoded: PNGs of the kinds datasets
// hold (8-bit gray / RGB / RGBA, 16-bit gray) by DecodePngFast (png_decoder.h, about twice as
// fast as libpng), everything else by cv::imdecode. Every failure is an InputError naming the file.

enum class ImageColor {
  kGray,   // CV_8UC1 (colour images converted)
  kColor,  // CV_8UC3 BGR (gray images expanded)
};

// What a 16-bit single-channel camera image becomes: refused (a depth PNG listed as an image by
// mistake is the likelier cause in layouts of 8-bit cameras), or scaled to 8 bits as cv::imread
// does for gray (value / 257, rounded), for layouts whose cameras record 16 bits (TUM-VI's EuRoC
// exports are 16-bit PNGs).
enum class SixteenBitImages { kRefuse, kScaleTo8Bit };

// Loads an 8-bit image. Throws InputError(path, ...) when the file is missing, empty (0 bytes),
// not decodable, decodes to an empty image, or is not 8-bit (e.g. a 16-bit depth PNG by mistake;
// unless sixteen_bit says to scale a 16-bit gray image).
cv::Mat LoadImage(const std::string& path, ImageColor color = ImageColor::kGray,
                  SixteenBitImages sixteen_bit = SixteenBitImages::kRefuse);

// Loads a 16-bit single-channel depth image (CV_16UC1, raw units; metres = raw / depth_scale).
// Throws InputError(path, ...) for the cases above, for an 8-bit or multi-channel image ("depth
// must be a 16-bit single-channel PNG"), and when expected_size is given and differs.
cv::Mat LoadDepth(const std::string& path, cv::Size expected_size = cv::Size());

// The same from a file's bytes already in memory (e.g. a PNG-encoded stream); `name` is what the
// errors call it.
cv::Mat DecodeImage(const std::string& bytes, const std::string& name,
                    ImageColor color = ImageColor::kGray,
                    SixteenBitImages sixteen_bit = SixteenBitImages::kRefuse);
cv::Mat DecodeDepth(const std::string& bytes, const std::string& name,
                    cv::Size expected_size = cv::Size());

// An image and its registered depth image of the same size.
struct RgbdImages {
  cv::Mat image;  // CV_8UC1 or CV_8UC3
  cv::Mat depth;  // CV_16UC1
};
// Throws InputError(depth_path, ...) when the two sizes differ.
RgbdImages LoadRgbd(const std::string& image_path, const std::string& depth_path,
                    ImageColor color = ImageColor::kGray);

// Raw 16-bit depth -> CV_32FC1 metres (raw / depth_scale); 0 (no reading) becomes NaN.
cv::Mat DepthToMetres(const cv::Mat& raw_depth, double depth_scale);

// Writes an image (8-bit, or 16-bit single channel for PNG depth). Creates no folders. Throws
// Error when the encoder fails or the file cannot be written.
void WriteImage(const std::string& path, const cv::Mat& image);

}  // namespace imumatch
