// DecodePngFast against libpng (cv::imdecode), in memory: whenever the fast path returns pixels,
// OpenCV must decode the same bytes to exactly the same pixels (gray: cv::cvtColor of them);
// otherwise it is a finding (trap). Refusing (an empty Mat) is always allowed: OpenCV decides.
//
// Blind mutations would almost never get past the chunk CRCs and the zlib checksum, so a custom
// mutator (structure-aware) mutates either the file and then repairs every chunk's CRC, or the
// inflated rows (filter bytes and samples) and re-deflates them into one IDAT: most inputs then
// reach the filters and the conversions.
#include <libdeflate.h>
#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/io/png_decoder.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::setNumThreads(0);
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return 0;
}

extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

namespace {

uint32_t Be32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) << 24 | static_cast<uint32_t>(p[1]) << 16 |
         static_cast<uint32_t>(p[2]) << 8 | static_cast<uint32_t>(p[3]);
}
void PutBe32(uint8_t* p, uint32_t v) {
  for (int k = 0; k < 4; ++k) p[k] = static_cast<uint8_t>(v >> (24 - 8 * k));
}

// Calls visit(pos, length) for each chunk (at byte pos, data length) that lies inside the buffer,
// in order. Returns false when a chunk runs past the end (the walk stops there).
template <typename Visit>
bool ForEachChunk(const uint8_t* data, size_t size, Visit&& visit) {
  size_t pos = 8;
  while (size >= 12 && pos <= size - 12) {
    const uint32_t length = Be32(data + pos);
    if (length > size - pos - 12) return false;
    visit(pos, static_cast<size_t>(length));
    pos += 12 + static_cast<size_t>(length);
  }
  return true;
}

bool IsIdat(const uint8_t* data, size_t pos) { return std::memcmp(data + pos + 4, "IDAT", 4) == 0; }

// Rewrites the CRC of every chunk that lies inside the buffer.
void FixCrcs(uint8_t* data, size_t size) {
  ForEachChunk(data, size, [&](size_t pos, size_t length) {
    PutBe32(data + pos + 8 + length,
            libdeflate_crc32(0, data + pos + 4, static_cast<uint32_t>(length) + 4));
  });
}

// Inflates the IDATs, mutates the rows, deflates them again into a single IDAT chunk. Returns 0
// when the input has no IDAT that inflates (the caller then mutates the file itself).
size_t MutateRows(uint8_t* data, size_t size, size_t max_size) {
  size_t first = 0, end = 0;
  std::vector<uint8_t> z;
  const bool whole = ForEachChunk(data, size, [&](size_t pos, size_t length) {
    if (!IsIdat(data, pos)) return;
    if (z.empty()) first = pos;
    z.insert(z.end(), data + pos + 8, data + pos + 8 + length);
    end = pos + 12 + length;
  });
  if (!whole || z.empty()) return 0;
  std::vector<uint8_t> raw(1 << 20);
  size_t got = 0;
  libdeflate_decompressor* d = libdeflate_alloc_decompressor();
  const libdeflate_result r =
      libdeflate_zlib_decompress(d, z.data(), z.size(), raw.data(), raw.size(), &got);
  libdeflate_free_decompressor(d);
  if (r != LIBDEFLATE_SUCCESS || got == 0) return 0;
  raw.resize(got);
  raw.resize(raw.size() + 16);
  raw.resize(LLVMFuzzerMutate(raw.data(), got, raw.size()));
  libdeflate_compressor* c = libdeflate_alloc_compressor(1);
  std::vector<uint8_t> out(libdeflate_zlib_compress_bound(c, raw.size()));
  out.resize(libdeflate_zlib_compress(c, raw.data(), raw.size(), out.data(), out.size()));
  libdeflate_free_compressor(c);
  const size_t tail = size - end;
  const size_t new_size = first + 12 + out.size() + tail;
  if (out.empty() || new_size > max_size) return 0;
  std::memmove(data + first + 12 + out.size(), data + end, tail);
  PutBe32(data + first, static_cast<uint32_t>(out.size()));
  std::memcpy(data + first + 4, "IDAT", 4);
  std::memcpy(data + first + 8, out.data(), out.size());
  FixCrcs(data, new_size);
  return new_size;
}

}  // namespace

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size,
                                          unsigned int seed) {
  if (seed % 2 == 0) {
    const size_t n = MutateRows(data, size, max_size);
    if (n > 0) return n;
  }
  const size_t n = LLVMFuzzerMutate(data, size, max_size);
  FixCrcs(data, n);
  return n;
}

namespace {

// Whether zlib (libpng's inflate) refuses the concatenated IDAT stream.
bool ZlibRefusesIdat(const uint8_t* data, size_t size) {
  std::vector<uint8_t> z;
  ForEachChunk(data, size, [&](size_t pos, size_t length) {
    if (IsIdat(data, pos)) z.insert(z.end(), data + pos + 8, data + pos + 8 + length);
  });
  std::vector<uint8_t> out(std::max<size_t>(1, z.size() * 1100));
  uLongf out_size = out.size();
  return uncompress(out.data(), &out_size, z.data(), z.size()) != Z_OK;
}

bool Same(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() &&
         cv::norm(a.reshape(1), b.reshape(1), cv::NORM_INF) == 0.0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // OpenCV decodes only what the fast path accepted: at most ~1100x the input's size (deflate's
  // largest expansion), so no huge allocation from a forged header.
  const cv::Mat fast = imumatch::DecodePngFast(data, size, imumatch::PngOutput::kUnchanged);
  const cv::Mat fast_gray = imumatch::DecodePngFast(data, size, imumatch::PngOutput::kGray);
  if (fast.empty() && fast_gray.empty()) return 0;
  cv::Mat reference;
  try {
    reference =
        cv::imdecode(cv::Mat(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data)),
                     cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    __builtin_trap();  // the fast path accepted what libpng refuses
  }
  // libdeflate remaps some invalid deflate codes instead of failing (by design: corruption is
  // the checksum's to catch), so it can accept a stream zlib refuses, with the Adler-32 matching
  // what it decoded. That is the only tolerated difference: zlib itself must refuse the stream.
  if (reference.empty() && ZlibRefusesIdat(data, size)) return 0;
  if (reference.empty()) __builtin_trap();
  if (!fast.empty() && !Same(fast, reference)) __builtin_trap();
  if (!fast_gray.empty()) {
    cv::Mat gray = reference;
    if (reference.channels() == 3) cv::cvtColor(reference, gray, cv::COLOR_BGR2GRAY);
    if (reference.channels() == 4) cv::cvtColor(reference, gray, cv::COLOR_BGRA2GRAY);
    if (!Same(fast_gray, gray)) __builtin_trap();
  }
  return 0;
}
