#include "imumatch/eval/frame_source.h"

#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "imumatch/core/error.h"
#include "imumatch/io/image_io.h"

namespace imumatch {

std::function<cv::Mat(size_t)> MakeDiskImageReader(const Dataset& dataset) {
  auto frames = std::make_shared<std::vector<FrameRecord>>(dataset.frames);
  const int width = dataset.camera.width, height = dataset.camera.height;
  const SixteenBitImages sixteen_bit = dataset.sixteen_bit_images;
  return [frames, width, height, sixteen_bit](size_t index) {
    IMUMATCH_CHECK(index < frames->size(), "frame index " << index);
    const FrameRecord& f = (*frames)[index];
    cv::Mat image = LoadImage(f.image_path, ImageColor::kGray, sixteen_bit);
    if (width > 0 && height > 0 && (image.cols != width || image.rows != height)) {
      throw InputError(f.image_path, "image is " + std::to_string(image.cols) + "x" +
                                         std::to_string(image.rows) + ", the camera is " +
                                         std::to_string(width) + "x" + std::to_string(height));
    }
    return image;
  };
}

std::function<cv::Mat(size_t)> MakeDiskDepthReader(const Dataset& dataset) {
  auto frames = std::make_shared<std::vector<FrameRecord>>(dataset.frames);
  const cv::Size size(dataset.camera.width, dataset.camera.height);
  return [frames, size](size_t index) {
    IMUMATCH_CHECK(index < frames->size(), "frame index " << index);
    const FrameRecord& f = (*frames)[index];
    return f.depth_path.empty() ? cv::Mat() : LoadDepth(f.depth_path, size);
  };
}

FrameReader MakeDiskFrameReader(const Dataset& dataset) {
  auto frames = std::make_shared<std::vector<FrameRecord>>(dataset.frames);
  auto image_reader = MakeDiskImageReader(dataset);
  return [frames, image_reader](size_t index, bool with_depth) {
    FrameImages out;
    out.image = image_reader(index);
    const FrameRecord& f = (*frames)[index];
    if (with_depth && !f.depth_path.empty()) out.depth = LoadDepth(f.depth_path, out.image.size());
    return out;
  };
}

EvalSource MakeDiskSource(Dataset dataset) {
  EvalSource source;
  source.reader = MakeDiskFrameReader(dataset);
  source.image_reader = MakeDiskImageReader(dataset);
  source.depth_reader = MakeDiskDepthReader(dataset);
  auto frames = std::make_shared<std::vector<FrameRecord>>(dataset.frames);
  source.opencv_image_reader = [frames](size_t index) {
    IMUMATCH_CHECK(index < frames->size(), "frame index " << index);
    return cv::imread((*frames)[index].image_path, cv::IMREAD_GRAYSCALE);
  };
  source.exact_ground_truth = dataset.kind == DatasetKind::kSynthetic;
  source.dataset = std::move(dataset);
  return source;
}

EvalSource MakeSyntheticSource(const SyntheticSequence& sequence, const std::string& case_name) {
  EvalSource source;
  Dataset& d = source.dataset;
  d.name = case_name.empty() ? sequence.motion : case_name;
  d.root = "<memory>";
  d.kind = DatasetKind::kSynthetic;
  d.camera = sequence.camera;
  d.imu_params = sequence.imu_params;
  d.cam_from_imu = sequence.cam_from_imu;
  d.imu_simulated = true;
  d.imu_source_note = "simulated IMU (in-memory synthetic sequence)";
  for (const ImuSample& s : sequence.imu) d.imu.Push(s, "synthetic imu");
  struct Encoded {
    std::string image, depth;  // PNG files' bytes
    std::string image_name, depth_name;
  };
  auto encoded = std::make_shared<std::vector<Encoded>>();
  for (size_t i = 0; i < sequence.frames.size(); ++i) {
    const SyntheticFrame& f = sequence.frames[i];
    FrameRecord r;
    r.t_ns = f.t_ns;
    r.image_path = "<memory>/rgb/" + std::to_string(i) + ".png";
    r.depth_path = "<memory>/depth/" + std::to_string(i) + ".png";
    r.world_from_cam = f.world_from_cam;
    r.imu_velocity_in_world = f.imu_velocity_in_world;
    d.frames.push_back(r);
    d.groundtruth_world_from_cam.push_back({f.t_ns, f.world_from_cam});
    Encoded e;
    std::vector<uchar> bytes;
    IMUMATCH_CHECK(cv::imencode(".png", f.rgb, bytes), "PNG encoding of frame " << i);
    e.image.assign(bytes.begin(), bytes.end());
    IMUMATCH_CHECK(cv::imencode(".png", f.depth, bytes), "PNG encoding of depth " << i);
    e.depth.assign(bytes.begin(), bytes.end());
    e.image_name = r.image_path;
    e.depth_name = r.depth_path;
    encoded->push_back(std::move(e));
  }
  // As files on disk are read (LoadImage / LoadDepth): the same decoder, the same gray.
  source.image_reader = [encoded](size_t index) {
    IMUMATCH_CHECK(index < encoded->size(), "frame index " << index);
    const Encoded& e = (*encoded)[index];
    return DecodeImage(e.image, e.image_name, ImageColor::kGray);
  };
  source.depth_reader = [encoded](size_t index) {
    IMUMATCH_CHECK(index < encoded->size(), "frame index " << index);
    const Encoded& e = (*encoded)[index];
    return DecodeDepth(e.depth, e.depth_name);
  };
  source.opencv_image_reader = [encoded](size_t index) {
    IMUMATCH_CHECK(index < encoded->size(), "frame index " << index);
    const std::string& png = (*encoded)[index].image;
    return cv::imdecode(
        cv::Mat(1, static_cast<int>(png.size()), CV_8UC1, const_cast<char*>(png.data())),
        cv::IMREAD_GRAYSCALE);
  };
  source.reader = [image_reader = source.image_reader, depth_reader = source.depth_reader](
                      size_t index, bool with_depth) {
    FrameImages out;
    out.image = image_reader(index);
    if (with_depth) out.depth = depth_reader(index);
    return out;
  };
  source.exact_ground_truth = true;
  return source;
}

}  // namespace imumatch
