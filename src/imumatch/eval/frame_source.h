#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include <opencv2/core.hpp>

#include "imumatch/io/dataset.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch {

// The decoded images of one frame. image: 8-bit gray or BGR; depth: CV_16U raw or empty.
struct FrameImages {
  cv::Mat image;
  cv::Mat depth;
};

// Reads frame `index` of a dataset (with its depth image when with_depth is set and the frame has
// one). Throws InputError for unreadable files.
using FrameReader = std::function<FrameImages(size_t index, bool with_depth)>;

// A dataset plus the way to read its images, and whether its ground truth is exact (synthetic) or
// measured (real: motion capture + Kinect depth).
struct EvalSource {
  Dataset dataset;
  FrameReader reader;
  // The image and the depth of a frame on their own (both set by the makers below), so that a
  // pipeline can decode them on two cores. An empty depth Mat when the frame has none.
  std::function<cv::Mat(size_t index)> image_reader, depth_reader;
  // The gray image as a program written with OpenCV alone reads it (cv::imread / cv::imdecode
  // with IMREAD_GRAYSCALE, libpng's decoder and colour conversion): the end-to-end timing's
  // sequential baseline. Set by the makers below.
  std::function<cv::Mat(size_t index)> opencv_image_reader;
  bool exact_ground_truth = false;
};

// Reads FrameRecord::image_path / depth_path with io's LoadImage / LoadDepth (gray images).
FrameReader MakeDiskFrameReader(const Dataset& dataset);
// The same, one image at a time: the gray image (checked against the camera's size) and the
// depth (checked against the camera's size; empty when the frame has no depth).
std::function<cv::Mat(size_t)> MakeDiskImageReader(const Dataset& dataset);
std::function<cv::Mat(size_t)> MakeDiskDepthReader(const Dataset& dataset);
// The dataset as LoadDataset returns it, read from disk. Ground truth is exact for kSynthetic.
EvalSource MakeDiskSource(Dataset dataset);
// An in-memory synthetic sequence (no files): the frames are PNG-encoded once here so that the
// "read" stage decodes a PNG, like reading a file would. case_name names the dataset.
EvalSource MakeSyntheticSource(const SyntheticSequence& sequence, const std::string& case_name);

}  // namespace imumatch
