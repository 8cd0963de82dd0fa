#include "imumatch/io/image_io.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/core/error.h"
#include "imumatch/io/io_test_util.h"
#include "imumatch/testing/test_data.h"

namespace imumatch {
namespace {

using testing::DataPath;
using testing::ExpectInputError;
using testing::TempDir;

TEST(ImageIo, LoadsRealTumPairWithPlausibleDepth) {
  const RgbdImages prev = LoadRgbd(DataPath("tum_fr1_xyz_pair/img_prev.png"),
                                   DataPath("tum_fr1_xyz_pair/dep_prev.png"), ImageColor::kColor);
  EXPECT_EQ(prev.image.cols, 640);
  EXPECT_EQ(prev.image.rows, 480);
  EXPECT_EQ(prev.image.type(), CV_8UC3);
  EXPECT_EQ(prev.depth.type(), CV_16UC1);
  const cv::Mat gray = LoadImage(DataPath("tum_fr1_xyz_pair/img_curr.png"));
  EXPECT_EQ(gray.type(), CV_8UC1);
  EXPECT_EQ(gray.size(), cv::Size(640, 480));

  // fr1_xyz looks at a desk from about a metre: valid depths are mostly 0.5-3 m.
  const cv::Mat metres = DepthToMetres(prev.depth, PinholeCamera::KinectDefault().depth_scale);
  std::vector<float> valid;
  for (int r = 0; r < metres.rows; ++r) {
    for (int c = 0; c < metres.cols; ++c) {
      const float d = metres.at<float>(r, c);
      if (std::isfinite(d)) valid.push_back(d);
      if (prev.depth.at<uint16_t>(r, c) == 0) {
        EXPECT_TRUE(std::isnan(d));
      }
    }
  }
  ASSERT_GT(valid.size(), 640u * 480u / 2);
  std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
  const float median = valid[valid.size() / 2];
  EXPECT_GT(median, 0.5f);
  EXPECT_LT(median, 3.0f);
  const auto [lo, hi] = std::minmax_element(valid.begin(), valid.end());
  EXPECT_GT(*lo, 0.3f);  // the Kinect sees nothing closer than ~0.4 m
  EXPECT_LT(*hi, 10.0f);
}

TEST(ImageIo, LoadsEurocGrayFrame) {
  const cv::Mat image =
      LoadImage(DataPath("euroc_v101_excerpt/mav0/cam0/data/1403715273262142976.png"));
  EXPECT_EQ(image.size(), cv::Size(752, 480));
  EXPECT_EQ(image.type(), CV_8UC1);
  const cv::Mat color = LoadImage(
      DataPath("euroc_v101_excerpt/mav0/cam0/data/1403715273262142976.png"), ImageColor::kColor);
  EXPECT_EQ(color.type(), CV_8UC3);
}

// The datasets' own files, read through the fast PNG path (TUM: 8-bit RGB and 16-bit depth;
// EuRoC: 8-bit gray and 16-bit depth), give exactly what OpenCV reads.
TEST(ImageIo, RealFilesEqualWhatOpenCvReads) {
  const auto opencv_gray = [](const std::string& path) {
    const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
    cv::Mat gray = raw;
    if (raw.channels() == 3) cv::cvtColor(raw, gray, cv::COLOR_BGR2GRAY);
    return gray;
  };
  const auto same = [](const cv::Mat& a, const cv::Mat& b) {
    return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0.0;
  };
  for (const char* image : {"tum_fr1_xyz_pair/img_prev.png",
                            "euroc_mh05_flight/mav0/cam0/data/1403638538577829376.png"}) {
    EXPECT_TRUE(same(LoadImage(DataPath(image)), opencv_gray(DataPath(image)))) << image;
    EXPECT_TRUE(same(LoadImage(DataPath(image), ImageColor::kColor).reshape(1),
                     [&] {
                       cv::Mat c = cv::imread(DataPath(image), cv::IMREAD_COLOR);
                       return c.reshape(1);
                     }()))
        << image;
  }
  for (const char* depth : {"tum_fr1_xyz_pair/dep_prev.png",
                            "euroc_mh05_flight/mav0/depth0/data/1403638538577829376.png"}) {
    EXPECT_TRUE(same(LoadDepth(DataPath(depth)), cv::imread(DataPath(depth), cv::IMREAD_UNCHANGED)))
        << depth;
  }
}

TEST(ImageIo, MissingFile) {
  TempDir dir;
  const std::string path = dir.Path("none.png");
  ExpectInputError([&] { LoadImage(path); }, path, 0, "not found");
  ExpectInputError([&] { LoadDepth(path); }, path, 0, "not found");
}

TEST(ImageIo, EmptyAndUnreadableFiles) {
  TempDir dir;
  const std::string empty = dir.Write("empty.png", "");
  ExpectInputError([&] { LoadImage(empty); }, empty, 0, "empty");
  const std::string garbage = dir.Write("garbage.png", "this is not a PNG file at all\n");
  ExpectInputError([&] { LoadImage(garbage); }, garbage, 0, "not a PNG, JPEG, BMP or PNM");
  ExpectInputError([&] { LoadDepth(garbage); }, garbage, 0, "not a PNG, JPEG, BMP or PNM");
  // A PNG cut after its header: the size is plausible, decoding fails.
  std::vector<uchar> png;
  cv::imencode(".png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(9)), png);
  const std::string cut = dir.Write("cut.png", std::string(png.begin(), png.begin() + 40));
  ExpectInputError([&] { LoadImage(cut); }, cut, 0, "cannot decode");
}

TEST(ImageIo, RejectsEightBitDepthAndSixteenBitImage) {
  TempDir dir;
  const std::string depth8 = dir.Path("depth8.png");
  WriteImage(depth8, cv::Mat(48, 64, CV_8UC1, cv::Scalar(100)));
  ExpectInputError([&] { LoadDepth(depth8); }, depth8, 0, "16-bit");
  const std::string depth16 = dir.Path("depth16.png");
  WriteImage(depth16, cv::Mat(48, 64, CV_16UC1, cv::Scalar(5000)));
  ExpectInputError([&] { LoadImage(depth16); }, depth16, 0, "8-bit");
  const cv::Mat back = LoadDepth(depth16, cv::Size(64, 48));
  EXPECT_EQ(back.at<uint16_t>(10, 10), 5000);
  ExpectInputError([&] { LoadDepth(depth16, cv::Size(640, 480)); }, depth16, 0,
                   "64x48, expected 640x480");
}

// A 16-bit gray camera image (TUM-VI's are): scaled to 8 bits as cv::imread does for gray when
// the layout allows it (value / 257, rounded: 0 -> 0, 257 k -> k, 65535 -> 255), and equal to
// what cv::imread(IMREAD_GRAYSCALE) reads; refused by default.
TEST(ImageIo, SixteenBitCameraImagesScaleWhenTheLayoutAllows) {
  TempDir dir;
  cv::Mat raw(48, 64, CV_16UC1);
  for (int r = 0; r < raw.rows; ++r) {
    for (int c = 0; c < raw.cols; ++c)
      raw.at<uint16_t>(r, c) = static_cast<uint16_t>(r * 1301 + c * 17);
  }
  raw.at<uint16_t>(0, 0) = 0;
  raw.at<uint16_t>(0, 1) = 257 * 200;
  raw.at<uint16_t>(0, 2) = 65535;
  raw.at<uint16_t>(0, 3) = 257 * 10 + 128;  // 10.498: rounds down
  raw.at<uint16_t>(0, 4) = 257 * 10 + 129;  // 10.502: rounds up
  const std::string path = dir.Path("cam16.png");
  WriteImage(path, raw);
  ExpectInputError([&] { LoadImage(path); }, path, 0, "8-bit");
  const cv::Mat gray = LoadImage(path, ImageColor::kGray, SixteenBitImages::kScaleTo8Bit);
  ASSERT_EQ(gray.type(), CV_8UC1);
  EXPECT_EQ(gray.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(gray.at<uint8_t>(0, 1), 200);
  EXPECT_EQ(gray.at<uint8_t>(0, 2), 255);
  EXPECT_EQ(gray.at<uint8_t>(0, 3), 10);
  EXPECT_EQ(gray.at<uint8_t>(0, 4), 11);
  for (int r = 0; r < raw.rows; ++r) {
    for (int c = 5; c < raw.cols; ++c) {
      ASSERT_EQ(gray.at<uint8_t>(r, c), std::lround(raw.at<uint16_t>(r, c) / 257.0))
          << r << "," << c;
    }
  }
  // OpenCV's own reading of it, within its rounding.
  cv::Mat theirs = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(theirs.type(), CV_8UC1);
  double worst = 0.0;
  cv::minMaxLoc(cv::abs(theirs - gray), nullptr, &worst);
  EXPECT_LE(worst, 1.0);
  const cv::Mat color = LoadImage(path, ImageColor::kColor, SixteenBitImages::kScaleTo8Bit);
  EXPECT_EQ(color.type(), CV_8UC3);
  EXPECT_EQ(color.at<cv::Vec3b>(0, 1), cv::Vec3b(200, 200, 200));
  // A 16-bit colour image stays refused.
  const std::string rgb16 = dir.Path("rgb16.png");
  WriteImage(rgb16, cv::Mat(8, 8, CV_16UC3, cv::Scalar(1000, 2000, 3000)));
  ExpectInputError([&] { LoadImage(rgb16, ImageColor::kGray, SixteenBitImages::kScaleTo8Bit); },
                   rgb16, 0, "8-bit");
}

TEST(ImageIo, ImagesOfDifferentSizes) {
  TempDir dir;
  const std::string rgb = dir.Path("rgb.png");
  const std::string depth = dir.Path("depth.png");
  WriteImage(rgb, cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  WriteImage(depth, cv::Mat(40, 64, CV_16UC1, cv::Scalar(1000)));
  ExpectInputError([&] { LoadRgbd(rgb, depth); }, depth, 0, "64x40");
  WriteImage(depth, cv::Mat(48, 64, CV_16UC1, cv::Scalar(1000)));
  const RgbdImages ok = LoadRgbd(rgb, depth, ImageColor::kColor);
  EXPECT_EQ(ok.image.at<cv::Vec3b>(0, 0), cv::Vec3b(1, 2, 3));
  EXPECT_FLOAT_EQ(DepthToMetres(ok.depth, 5000.0).at<float>(3, 3), 0.2f);
}

TEST(ImageIo, WriteFailsClearly) {
  TempDir dir;
  EXPECT_THROW(WriteImage(dir.Path("no/such/folder/x.png"), cv::Mat(4, 4, CV_8UC1)), Error);
  EXPECT_THROW(WriteImage(dir.Path("x.png"), cv::Mat()), InvalidArgument);
}

}  // namespace
}  // namespace imumatch
