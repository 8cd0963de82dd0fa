#include "imumatch/io/png_decoder.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace imumatch {
namespace {

// ---- A PNG writer independent of the decoder under test: rows filtered with a chosen filter,
// stored (uncompressed) deflate blocks, CRC-32 and Adler-32 computed here. libpng (through
// cv::imdecode) decodes the result as the reference.

uint32_t Crc32(const uint8_t* p, size_t n, uint32_t crc = 0) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xff] ^ (crc >> 8);
  return ~crc;
}

void PutBe32(std::vector<uint8_t>* out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out->push_back(static_cast<uint8_t>(v >> s));
}

void PutChunk(std::vector<uint8_t>* png, const char* type, const std::vector<uint8_t>& body) {
  PutBe32(png, static_cast<uint32_t>(body.size()));
  const size_t start = png->size();
  png->insert(png->end(), type, type + 4);
  png->insert(png->end(), body.begin(), body.end());
  PutBe32(png, Crc32(png->data() + start, png->size() - start));
}

std::vector<uint8_t> ZlibStored(const std::vector<uint8_t>& raw) {
  std::vector<uint8_t> z = {0x78, 0x01};
  size_t pos = 0;
  do {
    const size_t n = std::min<size_t>(65535, raw.size() - pos);
    z.push_back(pos + n == raw.size() ? 1 : 0);  // BFINAL, BTYPE 00 (stored)
    z.push_back(static_cast<uint8_t>(n));
    z.push_back(static_cast<uint8_t>(n >> 8));
    z.push_back(static_cast<uint8_t>(~n));
    z.push_back(static_cast<uint8_t>(~n >> 8));
    z.insert(z.end(), raw.begin() + pos, raw.begin() + pos + n);
    pos += n;
  } while (pos < raw.size());
  uint32_t a = 1, b = 0;
  for (uint8_t v : raw) {
    a = (a + v) % 65521;
    b = (b + a) % 65521;
  }
  PutBe32(&z, b << 16 | a);
  return z;
}

int PaethRef(int a, int b, int c) {  // the specification's form, with branches
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  if (pb <= pc) return b;
  return c;
}

struct PngSpec {
  int width = 0, height = 0, bit_depth = 8, color_type = 0, interlace = 0;
  std::vector<uint8_t> pixels;  // rows of PNG samples (big-endian for 16 bits)
  std::vector<int> filters;     // per row; row y uses filters[y % size]
  int idat_chunks = 3;          // the zlib stream split over this many IDAT chunks
  std::vector<std::pair<std::string, std::vector<uint8_t>>> extra_chunks;  // before the IDATs
};

std::vector<uint8_t> WritePng(const PngSpec& s) {
  const int channels = s.color_type == 2 ? 3 : s.color_type == 6 ? 4 : s.color_type == 4 ? 2 : 1;
  const size_t bpp = static_cast<size_t>(channels) * s.bit_depth / 8;
  const size_t row_bytes = static_cast<size_t>(s.width) * bpp;
  std::vector<uint8_t> raw;
  std::vector<uint8_t> zero(row_bytes, 0);
  for (int y = 0; y < s.height; ++y) {
    const uint8_t* row = s.pixels.data() + y * row_bytes;
    const uint8_t* prior = y > 0 ? row - row_bytes : zero.data();
    const int f = s.filters[y % s.filters.size()];
    raw.push_back(static_cast<uint8_t>(f));
    for (size_t i = 0; i < row_bytes; ++i) {
      const int a = i >= bpp ? row[i - bpp] : 0, b = prior[i], c = i >= bpp ? prior[i - bpp] : 0;
      const int pred = f == 1   ? a
                       : f == 2 ? b
                       : f == 3 ? (a + b) / 2
                       : f == 4 ? PaethRef(a, b, c)
                                : 0;
      raw.push_back(static_cast<uint8_t>(row[i] - pred));
    }
  }
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<uint8_t> ihdr;
  PutBe32(&ihdr, static_cast<uint32_t>(s.width));
  PutBe32(&ihdr, static_cast<uint32_t>(s.height));
  ihdr.insert(ihdr.end(), {static_cast<uint8_t>(s.bit_depth), static_cast<uint8_t>(s.color_type), 0,
                           0, static_cast<uint8_t>(s.interlace)});
  PutChunk(&png, "IHDR", ihdr);
  for (const auto& [type, body] : s.extra_chunks) PutChunk(&png, type.c_str(), body);
  const std::vector<uint8_t> z = ZlibStored(raw);
  const size_t part = (z.size() + s.idat_chunks - 1) / s.idat_chunks;
  for (size_t pos = 0; pos < z.size(); pos += part) {
    PutChunk(&png, "IDAT",
             std::vector<uint8_t>(z.begin() + pos, z.begin() + std::min(z.size(), pos + part)));
  }
  PutChunk(&png, "IEND", {});
  return png;
}

// Smooth gradients plus noise: every filter predicts something, no sample is constant.
std::vector<uint8_t> TestSamples(int width, int height, int samples_per_pixel, unsigned seed) {
  cv::RNG rng(seed);
  std::vector<uint8_t> v(static_cast<size_t>(width) * height * samples_per_pixel);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int k = 0; k < samples_per_pixel; ++k) {
        v[(static_cast<size_t>(y) * width + x) * samples_per_pixel + k] =
            static_cast<uint8_t>(3 * x + 5 * y + 40 * k + rng.uniform(0, 24));
      }
    }
  }
  return v;
}

cv::Mat Decode(const std::vector<uint8_t>& png, PngOutput output) {
  return DecodePngFast(png.data(), png.size(), output);
}

cv::Mat OpenCvDecode(const std::vector<uint8_t>& png) {
  return cv::imdecode(png, cv::IMREAD_UNCHANGED);
}

bool Identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() &&
         cv::norm(a.reshape(1), b.reshape(1), cv::NORM_INF) == 0.0;
}

cv::Mat ToGray(const cv::Mat& m) {
  if (m.channels() == 1) return m;
  cv::Mat g;
  cv::cvtColor(m, g, m.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return g;
}

// Every filter type (alone and mixed row by row), every handled colour type, odd sizes,
// single and split IDAT: the same pixels as libpng.
TEST(PngDecoderTest, EqualsLibpngForEveryFilterAndColourType) {
  struct Kind {
    int bit_depth, color_type, samples;
  };
  const Kind kinds[] = {{8, 0, 1}, {8, 2, 3}, {8, 6, 4}, {16, 0, 2}};
  const std::vector<std::vector<int>> filter_sets = {{0}, {1}, {2}, {3}, {4}, {4, 3, 0, 2, 1}};
  const cv::Size sizes[] = {{1, 1}, {7, 5}, {33, 17}};
  int checked = 0;
  for (const Kind& k : kinds) {
    for (const auto& filters : filter_sets) {
      for (const cv::Size& size : sizes) {
        for (int chunks : {1, 4}) {
          PngSpec s;
          s.width = size.width;
          s.height = size.height;
          s.bit_depth = k.bit_depth;
          s.color_type = k.color_type;
          s.pixels = TestSamples(size.width, size.height, k.samples, 7u + checked);
          s.filters = filters;
          s.idat_chunks = chunks;
          const std::vector<uint8_t> png = WritePng(s);
          const cv::Mat reference = OpenCvDecode(png);
          ASSERT_FALSE(reference.empty());
          const std::string what = "bit depth " + std::to_string(k.bit_depth) + ", colour type " +
                                   std::to_string(k.color_type) + ", filter " +
                                   std::to_string(filters.front()) + ", " +
                                   std::to_string(size.width) + "x" + std::to_string(size.height);
          EXPECT_TRUE(Identical(Decode(png, PngOutput::kUnchanged), reference)) << what;
          if (k.bit_depth == 8) {
            EXPECT_TRUE(Identical(Decode(png, PngOutput::kGray), ToGray(reference))) << what;
          } else {
            EXPECT_TRUE(Decode(png, PngOutput::kGray).empty()) << what;  // 16 bits -> 8: OpenCV
          }
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 4 * 6 * 3 * 2);
}

// libpng's own encoder (through cv::imencode) at several compression levels and strategies, on
// images the size of the field's datasets.
TEST(PngDecoderTest, EqualsLibpngOnImagesOpenCvEncodes) {
  cv::RNG rng(42);
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1}) {
    cv::Mat image(480, 640, type);
    rng.fill(image, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 10000 : 256);
    cv::GaussianBlur(image, image, cv::Size(5, 5), 1.5);  // smooth: adaptive filters differ
    for (int level : {0, 1, 3, 9}) {
      for (int strategy : {cv::IMWRITE_PNG_STRATEGY_DEFAULT, cv::IMWRITE_PNG_STRATEGY_FILTERED,
                           cv::IMWRITE_PNG_STRATEGY_RLE}) {
        std::vector<uint8_t> png;
        ASSERT_TRUE(
            cv::imencode(".png", image, png,
                         {cv::IMWRITE_PNG_COMPRESSION, level, cv::IMWRITE_PNG_STRATEGY, strategy}));
        const cv::Mat reference = OpenCvDecode(png);
        EXPECT_TRUE(Identical(Decode(png, PngOutput::kUnchanged), reference))
            << "type " << type << " level " << level << " strategy " << strategy;
        EXPECT_TRUE(Identical(image, reference));
        if (type != CV_16UC1) {
          EXPECT_TRUE(Identical(Decode(png, PngOutput::kGray), ToGray(reference)));
        }
      }
    }
  }
}

PngSpec SmallGray() {
  PngSpec s;
  s.width = 9;
  s.height = 4;
  s.pixels = TestSamples(9, 4, 1, 3);
  s.filters = {4, 1};
  return s;
}

TEST(PngDecoderTest, LeavesWhatItDoesNotHandleToOpenCv) {
  ASSERT_FALSE(Decode(WritePng(SmallGray()), PngOutput::kUnchanged).empty());
  {
    PngSpec s = SmallGray();  // palette
    s.color_type = 3;
    s.extra_chunks = {{"PLTE", std::vector<uint8_t>(3 * 256, 128)}};
    EXPECT_TRUE(Decode(WritePng(s), PngOutput::kUnchanged).empty());
    EXPECT_FALSE(OpenCvDecode(WritePng(s)).empty());  // a valid file, for OpenCV to decode
  }
  {
    PngSpec s = SmallGray();  // transparency: OpenCV adds an alpha channel
    s.extra_chunks = {{"tRNS", {0, 7}}};
    EXPECT_TRUE(Decode(WritePng(s), PngOutput::kUnchanged).empty());
  }
  {
    PngSpec s = SmallGray();  // gray + alpha
    s.color_type = 4;
    s.pixels = TestSamples(9, 4, 2, 3);
    EXPECT_TRUE(Decode(WritePng(s), PngOutput::kUnchanged).empty());
  }
  {
    PngSpec s = SmallGray();  // an unknown critical chunk
    s.extra_chunks = {{"QXYZ", {1, 2}}};
    EXPECT_TRUE(Decode(WritePng(s), PngOutput::kUnchanged).empty());
  }
  {
    PngSpec s = SmallGray();  // a chunk type that is not four letters (found by the fuzzer)
    s.extra_chunks = {
        {"\xb8"
         "DAT",
         {1, 2}}};
    EXPECT_TRUE(Decode(WritePng(s), PngOutput::kUnchanged).empty());
    EXPECT_TRUE(OpenCvDecode(WritePng(s)).empty());  // libpng refuses it
  }
  {
    PngSpec s = SmallGray();  // an unknown ancillary chunk is skipped
    s.extra_chunks = {{"tEXt", {'a', 0, 'b'}}};
    EXPECT_TRUE(Identical(Decode(WritePng(s), PngOutput::kUnchanged), OpenCvDecode(WritePng(s))));
  }
  cv::Mat rgb16(5, 6, CV_16UC3, cv::Scalar(1000, 2000, 3000));  // 16-bit colour
  std::vector<uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", rgb16, png));
  EXPECT_TRUE(Decode(png, PngOutput::kUnchanged).empty());
}

// Flips, truncations and lies in the header: the fast path refuses (empty), never returns pixels
// that differ from the file's.
TEST(PngDecoderTest, RefusesCorruptFiles) {
  const std::vector<uint8_t> good = WritePng(SmallGray());
  EXPECT_TRUE(Decode({}, PngOutput::kUnchanged).empty());
  for (size_t cut : {size_t{8}, size_t{30}, good.size() / 2, good.size() - 1}) {
    EXPECT_TRUE(
        Decode(std::vector<uint8_t>(good.begin(), good.begin() + cut), PngOutput::kUnchanged)
            .empty())
        << "cut at " << cut;
  }
  // Any single flipped byte after the signature breaks a CRC (or the signature itself).
  for (size_t i = 0; i < good.size(); ++i) {
    std::vector<uint8_t> bad = good;
    bad[i] ^= 0x10;
    const cv::Mat m = Decode(bad, PngOutput::kUnchanged);
    EXPECT_TRUE(m.empty()) << "byte " << i;
  }
  {
    PngSpec s = SmallGray();  // filter type 5 does not exist
    s.filters = {5};
    EXPECT_TRUE(Decode(WritePng(s), PngOutput::kUnchanged).empty());
  }
  // A header of one row more, or one row fewer, than the stream holds (the 4-row file's IDATs
  // after another file's valid IHDR).
  for (int rows : {5, 3}) {
    PngSpec other = SmallGray();
    other.height = rows;
    other.pixels.resize(static_cast<size_t>(9) * rows);
    const std::vector<uint8_t> header = WritePng(other);
    std::vector<uint8_t> forged(header.begin(), header.begin() + 8 + 25);
    forged.insert(forged.end(), good.begin() + 8 + 25, good.end());
    EXPECT_TRUE(Decode(forged, PngOutput::kUnchanged).empty()) << rows << " rows";
  }
  {
    PngSpec s = SmallGray();  // interlaced (Adam7) is OpenCV's
    s.interlace = 1;
    EXPECT_TRUE(Decode(WritePng(s), PngOutput::kUnchanged).empty());
  }
}

// A header announcing a huge image over a few bytes of data is refused before any allocation
// (deflate cannot expand that much).
TEST(PngDecoderTest, RefusesHeadersTheDataCannotFill) {
  PngSpec s = SmallGray();
  std::vector<uint8_t> png = WritePng(s);
  // IHDR body starts at byte 16: width, height. Claim 60000 x 60000 and fix the CRC.
  std::vector<uint8_t> forged = png;
  const uint8_t huge[4] = {0, 0, 0xea, 0x60};
  std::copy(huge, huge + 4, forged.begin() + 16);
  std::copy(huge, huge + 4, forged.begin() + 20);
  const uint32_t crc = Crc32(forged.data() + 12, 17);
  for (int k = 0; k < 4; ++k) forged[29 + k] = static_cast<uint8_t>(crc >> (24 - 8 * k));
  EXPECT_TRUE(Decode(forged, PngOutput::kUnchanged).empty());
}

}  // namespace
}  // namespace imumatch
