#include "imumatch/io/png_decoder.h"

#include <libdeflate.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

namespace imumatch {
namespace {

uint32_t Be32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) << 24 | static_cast<uint32_t>(p[1]) << 16 |
         static_cast<uint32_t>(p[2]) << 8 | static_cast<uint32_t>(p[3]);
}

bool IsType(const uint8_t* chunk, const char* type) { return std::memcmp(chunk + 4, type, 4) == 0; }

// Chunk types are four ASCII letters (PNG specification 5.4); libpng refuses anything else.
bool ValidType(const uint8_t* chunk) {
  for (int k = 4; k < 8; ++k) {
    const uint8_t c = chunk[k];
    if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'))) return false;
  }
  return true;
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

// One decompressor per thread (it holds ~32 KB of tables; allocating it per image would cost more
// than a small image's inflate).
libdeflate_decompressor* ThreadDecompressor() {
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> d(
      libdeflate_alloc_decompressor());
  return d.get();
}

// Paeth predictor (PNG specification, section 9.4), without branches on the data.
inline int Paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  const int ab = pa <= pb ? a : b;
  const int pab = pa <= pb ? pa : pb;
  return pab <= pc ? ab : c;
}

// Reverses the filter of one row in place. prior: the previous row, already unfiltered (zeros for
// the first row). bpp: bytes per complete pixel (at least 1). Returns false for an unknown filter.
bool Unfilter(int filter, uint8_t* row, const uint8_t* prior, size_t n, size_t bpp) {
  switch (filter) {
    case 0:  // None
      return true;
    case 1:  // Sub
      for (size_t i = bpp; i < n; ++i) row[i] = static_cast<uint8_t>(row[i] + row[i - bpp]);
      return true;
    case 2:  // Up
      for (size_t i = 0; i < n; ++i) row[i] = static_cast<uint8_t>(row[i] + prior[i]);
      return true;
    case 3:  // Average
      for (size_t i = 0; i < bpp; ++i) row[i] = static_cast<uint8_t>(row[i] + (prior[i] >> 1));
      for (size_t i = bpp; i < n; ++i) {
        row[i] = static_cast<uint8_t>(row[i] + ((row[i - bpp] + prior[i]) >> 1));
      }
      return true;
    case 4:  // Paeth
      for (size_t i = 0; i < bpp; ++i) row[i] = static_cast<uint8_t>(row[i] + prior[i]);
      for (size_t i = bpp; i < n; ++i) {
        row[i] = static_cast<uint8_t>(row[i] + Paeth(row[i - bpp], prior[i], prior[i - bpp]));
      }
      return true;
    default:
      return false;
  }
}

// cv::cvtColor's fixed-point BGR -> gray for 8 bits (OpenCV 4.6: 15-bit weights 9798, 19235,
// 3735, rounded; PngDecoderTest checks it against cvtColor).
inline uint8_t Gray(int r, int g, int b) {
  return static_cast<uint8_t>((r * 9798 + g * 19235 + b * 3735 + (1 << 14)) >> 15);
}

// Writes one unfiltered row (PNG byte order) into the output row.
void ConvertRow(const uint8_t* src, uint8_t* dst, int width, int channels, int bit_depth,
                PngOutput output) {
  if (bit_depth == 16) {  // big-endian samples -> host uint16
    uint16_t* out = reinterpret_cast<uint16_t*>(dst);
    for (int x = 0; x < width; ++x) {
      out[x] = static_cast<uint16_t>(src[2 * x] << 8 | src[2 * x + 1]);
    }
    return;
  }
  if (channels == 1) {
    std::memcpy(dst, src, static_cast<size_t>(width));
    return;
  }
  if (output == PngOutput::kGray) {
    for (int x = 0; x < width; ++x, src += channels) dst[x] = Gray(src[0], src[1], src[2]);
    return;
  }
  for (int x = 0; x < width; ++x, src += channels, dst += channels) {  // RGB(A) -> BGR(A)
    dst[0] = src[2];
    dst[1] = src[1];
    dst[2] = src[0];
    if (channels == 4) dst[3] = src[3];
  }
}

}  // namespace

cv::Mat DecodePngFast(const uint8_t* data, size_t size, PngOutput output) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (data == nullptr || size < 8 + 25 || std::memcmp(data, kSignature, 8) != 0) return {};

  // Walk the chunks: IHDR first, every chunk inside the file with a matching CRC, IDATs
  // consecutive, IEND last. Keep where the IDAT data lie.
  int width = 0, height = 0, bit_depth = 0, color_type = -1;
  std::vector<std::pair<const uint8_t*, size_t>> idat;
  size_t idat_bytes = 0;
  bool idat_done = false, seen_end = false, first = true;
  size_t pos = 8;
  while (pos < size) {
    if (size - pos < 12) return {};
    const uint8_t* chunk = data + pos;
    const uint32_t length = Be32(chunk);
    if (length > 0x7fffffffu || length > size - pos - 12) return {};
    const uint32_t crc = Be32(chunk + 8 + length);
    if (!ValidType(chunk) || libdeflate_crc32(0, chunk + 4, length + 4) != crc) return {};
    const uint8_t* body = chunk + 8;
    if (first) {
      if (!IsType(chunk, "IHDR") || length != 13) return {};
      const uint32_t w = Be32(body), h = Be32(body + 4);
      // compression 0, filter method 0, interlace 0 (Adam7 is left to OpenCV)
      if (w == 0 || h == 0 || w > 0x7fffffffu || h > 0x7fffffffu) return {};
      if (body[10] != 0 || body[11] != 0 || body[12] != 0) return {};
      width = static_cast<int>(w);
      height = static_cast<int>(h);
      bit_depth = body[8];
      color_type = body[9];
      first = false;
    } else if (IsType(chunk, "IDAT")) {
      if (idat_done) return {};  // IDAT chunks must be consecutive
      idat.emplace_back(body, length);
      idat_bytes += length;
    } else {
      if (!idat.empty()) idat_done = true;
      if (IsType(chunk, "IEND")) {
        seen_end = true;
        break;
      }
      // A tRNS chunk makes OpenCV add alpha.
      // Any other critical chunk (upper-case first letter: PLTE, a second IHDR, an unknown one)
      // is left to OpenCV too.
      if (IsType(chunk, "tRNS") || (chunk[4] & 0x20) == 0) return {};
    }
    pos += 12 + static_cast<size_t>(length);
  }
  if (first || !seen_end || idat.empty()) return {};

  int channels = 0;
  if (bit_depth == 8 && color_type == 0) {
    channels = 1;
  } else if (bit_depth == 8 && color_type == 2) {
    channels = 3;
  } else if (bit_depth == 8 && color_type == 6) {
    channels = 4;
  } else if (bit_depth == 16 && color_type == 0 && output == PngOutput::kUnchanged) {
    channels = 1;
  } else {
    return {};
  }
  const size_t bpp = static_cast<size_t>(channels) * (bit_depth / 8);
  const size_t row_bytes = static_cast<size_t>(width) * bpp;
  const size_t raw_bytes = static_cast<size_t>(height) * (row_bytes + 1);
  // Deflate expands at most ~1032x; a header announcing far more than the data can hold is
  // truncated or forged: leave it to OpenCV rather than allocate for it. And 1 GiB at most.
  if (raw_bytes > (idat_bytes + 64) * 1100 || raw_bytes > (size_t{1} << 30)) return {};

  std::vector<uint8_t> joined;
  const uint8_t* zlib = idat.front().first;
  if (idat.size() > 1) {
    joined.resize(idat_bytes);
    size_t at = 0;
    for (const auto& [p, n] : idat) {
      std::memcpy(joined.data() + at, p, n);
      at += n;
    }
    zlib = joined.data();
  }
  std::vector<uint8_t> raw(raw_bytes);
  size_t got = 0;
  const libdeflate_result r = libdeflate_zlib_decompress(ThreadDecompressor(), zlib, idat_bytes,
                                                         raw.data(), raw.size(), &got);
  if (r != LIBDEFLATE_SUCCESS || got != raw_bytes) return {};

  const int out_type = bit_depth == 16              ? CV_16UC1
                       : output == PngOutput::kGray ? CV_8UC1
                                                    : CV_MAKETYPE(CV_8U, channels);
  cv::Mat out(height, width, out_type);
  std::vector<uint8_t> zeros(row_bytes, 0);
  const uint8_t* prior = zeros.data();
  for (int y = 0; y < height; ++y) {
    uint8_t* line = raw.data() + static_cast<size_t>(y) * (row_bytes + 1);
    uint8_t* row = line + 1;
    if (!Unfilter(line[0], row, prior, row_bytes, bpp)) return {};
    ConvertRow(row, out.ptr<uint8_t>(y), width, channels, bit_depth, output);
    prior = row;
  }
  return out;
}

}  // namespace imumatch
