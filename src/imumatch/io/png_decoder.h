#pragma once

#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

namespace imumatch {

// A PNG decoder for the images that datasets of the field hold (TUM RGB-D: 8-bit RGB and 16-bit
// depth; EuRoC/ASL: 8-bit gray, 16-bit depth), about twice as fast as cv::imdecode's libpng:
// the zlib stream is inflated in one call by libdeflate (Debian's libdeflate) into a buffer of
// the exact size the header announces, the rows are unfiltered in place, and an RGB image meant
// to be gray is converted in the same pass.
//
// Handled: non-interlaced PNGs of 8-bit gray, RGB or RGBA, and 16-bit gray, without a tRNS chunk.
// Everything else (palette, interlaced, 1/2/4-bit, 16-bit colour, gray + alpha, transparency) and
// anything not exactly as the format says (a chunk past the end, a CRC that does not match, a
// zlib stream that is corrupt or holds more or fewer bytes than the rows need, an unknown filter
// type) returns an empty Mat: the caller then decodes with OpenCV, whose verdict stands. Where
// both decode, the pixels are equal (tests and the png_decoder fuzz target check it). One
// difference is kept: libdeflate maps some invalid deflate codes to valid ones instead of failing
// (by design: detecting corruption is the checksum's job), so a stream that zlib refuses but whose
// Adler-32 matches what libdeflate decoded is accepted here, with the pixels that checksum vouches
// for.
enum class PngOutput {
  kUnchanged,  // as cv::IMREAD_UNCHANGED: CV_8UC1, CV_8UC3 (BGR), CV_8UC4 (BGRA) or CV_16UC1
  kGray,       // CV_8UC1; colour converted as cv::cvtColor(COLOR_BGR2GRAY / BGRA2GRAY) does,
               // bit for bit: (9798 R + 19235 G + 3735 B + 16384) >> 15. 16-bit: not handled.
};

// Decodes `size` bytes of a PNG file; an empty Mat when the file is outside the fast path (see
// above). Never throws for bad input; throws only std::bad_alloc.
cv::Mat DecodePngFast(const uint8_t* data, size_t size, PngOutput output);

}  // namespace imumatch
