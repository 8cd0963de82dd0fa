#include "imumatch/features/feature_factory.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numeric>

#include "imumatch/core/error.h"
#include "imumatch/features/brief.h"
#include "imumatch/features/image_util.h"

namespace imumatch {
namespace {

constexpr const char* kValidNames = "sift, surf, orb, fast (or fast_brief), akaze, brisk";

bool ResponseGreater(const cv::KeyPoint& a, const cv::KeyPoint& b) {
  return a.response > b.response;
}

// FAST-9/16 corners + BRIEF descriptors.
class FastBrief : public cv::Feature2D {
 public:
  FastBrief(int threshold, int max_keypoints)
      : fast_(cv::FastFeatureDetector::create(threshold, true)),
        brief_(Brief::Create()),
        max_keypoints_(max_keypoints) {}

  void detectAndCompute(cv::InputArray image, cv::InputArray mask,
                        std::vector<cv::KeyPoint>& keypoints, cv::OutputArray descriptors,
                        bool useProvidedKeypoints) override {
    const cv::Mat gray = ToGray8(image.getMat(), "FastBrief");
    if (!useProvidedKeypoints) {
      fast_->detect(gray, keypoints, mask);
      // Remove the corners BRIEF cannot describe before choosing the strongest ones.
      cv::KeyPointsFilter::runByImageBorder(keypoints, gray.size(), Brief::kBorder);
      std::stable_sort(keypoints.begin(), keypoints.end(), ResponseGreater);
      if (static_cast<int>(keypoints.size()) > max_keypoints_) keypoints.resize(max_keypoints_);
    }
    if (descriptors.needed()) brief_->compute(gray, keypoints, descriptors);
  }

  int descriptorSize() const override { return brief_->descriptorSize(); }
  int descriptorType() const override { return brief_->descriptorType(); }
  int defaultNorm() const override { return brief_->defaultNorm(); }
  cv::String getDefaultName() const override { return "imumatch.FAST_BRIEF"; }

 private:
  cv::Ptr<cv::FastFeatureDetector> fast_;
  cv::Ptr<Brief> brief_;
  int max_keypoints_;
};

// cv::SIFT with options' thresholds and at most `cap` keypoints (0: no cap).
cv::Ptr<cv::Feature2D> CreateSift(const FeatureOptions& options, int cap) {
  return cv::SIFT::create(cap, 3, options.sift_contrast_threshold, options.sift_edge_threshold);
}

}  // namespace

DetectorKind ParseDetectorKind(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "sift") return DetectorKind::kSift;
  if (lower == "surf") return DetectorKind::kSurf;
  if (lower == "orb") return DetectorKind::kOrb;
  if (lower == "fast" || lower == "fast_brief") return DetectorKind::kFastBrief;
  if (lower == "akaze") return DetectorKind::kAkaze;
  if (lower == "brisk") return DetectorKind::kBrisk;
  throw InvalidArgument("unknown detector '" + std::string(name) + "'; valid: " + kValidNames);
}

std::string ToString(DetectorKind kind) {
  switch (kind) {
    case DetectorKind::kSift:
      return "sift";
    case DetectorKind::kSurf:
      return "surf";
    case DetectorKind::kOrb:
      return "orb";
    case DetectorKind::kFastBrief:
      return "fast_brief";
    case DetectorKind::kAkaze:
      return "akaze";
    case DetectorKind::kBrisk:
      return "brisk";
  }
  throw InvalidArgument("invalid DetectorKind value " + std::to_string(static_cast<int>(kind)));
}

bool IsBinaryDescriptor(DetectorKind kind) {
  switch (kind) {
    case DetectorKind::kSift:
    case DetectorKind::kSurf:
      return false;
    case DetectorKind::kOrb:
    case DetectorKind::kFastBrief:
    case DetectorKind::kAkaze:
    case DetectorKind::kBrisk:
      return true;
  }
  throw InvalidArgument("invalid DetectorKind value " + std::to_string(static_cast<int>(kind)));
}

void FeatureOptions::Check() const {
  (void)ToString(kind);  // throws for a value outside the enum
  IMUMATCH_CHECK(max_keypoints >= 1 && max_keypoints <= kMaxKeypoints,
                 "FeatureOptions.max_keypoints must be in [1, " << kMaxKeypoints << "], got "
                                                                << max_keypoints);
  IMUMATCH_CHECK(
      std::isfinite(sift_contrast_threshold) && sift_contrast_threshold > 0,
      "FeatureOptions.sift_contrast_threshold must be > 0, got " << sift_contrast_threshold);
  IMUMATCH_CHECK(std::isfinite(sift_edge_threshold) && sift_edge_threshold > 0,
                 "FeatureOptions.sift_edge_threshold must be > 0, got " << sift_edge_threshold);
  surf.Check();
  IMUMATCH_CHECK(std::isfinite(orb_scale_factor) && orb_scale_factor > 1.0,
                 "FeatureOptions.orb_scale_factor must be > 1, got " << orb_scale_factor);
  IMUMATCH_CHECK(orb_n_levels >= 1 && orb_n_levels <= 32,
                 "FeatureOptions.orb_n_levels must be in [1, 32], got " << orb_n_levels);
  IMUMATCH_CHECK(
      orb_fast_threshold >= 1 && orb_fast_threshold <= 255,
      "FeatureOptions.orb_fast_threshold must be in [1, 255], got " << orb_fast_threshold);
  IMUMATCH_CHECK(threads >= 1 && threads <= 256,
                 "FeatureOptions.threads must be in [1, 256], got " << threads);
  IMUMATCH_CHECK(fast_threshold >= 1 && fast_threshold <= 255,
                 "FeatureOptions.fast_threshold must be in [1, 255], got " << fast_threshold);
  IMUMATCH_CHECK(std::isfinite(akaze_threshold) && akaze_threshold > 0,
                 "FeatureOptions.akaze_threshold must be > 0, got " << akaze_threshold);
  IMUMATCH_CHECK(brisk_threshold >= 1 && brisk_threshold <= 255,
                 "FeatureOptions.brisk_threshold must be in [1, 255], got " << brisk_threshold);
  IMUMATCH_CHECK(brisk_octaves >= 0 && brisk_octaves <= 8,
                 "FeatureOptions.brisk_octaves must be in [0, 8], got " << brisk_octaves);
}

cv::Ptr<cv::Feature2D> CreateFeature2D(const FeatureOptions& options) {
  options.Check();
  switch (options.kind) {
    case DetectorKind::kSift:
      return CreateSift(options, options.max_keypoints);
    case DetectorKind::kSurf: {
      SurfOptions surf = options.surf;
      surf.max_keypoints = options.max_keypoints;
      return Surf::Create(surf);
    }
    case DetectorKind::kOrb:
      return cv::ORB::create(options.max_keypoints, static_cast<float>(options.orb_scale_factor),
                             options.orb_n_levels, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                             options.orb_fast_threshold);
    case DetectorKind::kFastBrief:
      return cv::makePtr<FastBrief>(options.fast_threshold, options.max_keypoints);
    case DetectorKind::kAkaze:
      return cv::AKAZE::create(cv::AKAZE::DESCRIPTOR_MLDB, 0, 3,
                               static_cast<float>(options.akaze_threshold));
    case DetectorKind::kBrisk:
      return cv::BRISK::create(options.brisk_threshold, options.brisk_octaves);
  }
  throw InvalidArgument("invalid DetectorKind");
}

Features ExtractFeatures(const cv::Mat& image, const FeatureOptions& options, const cv::Mat& mask) {
  options.Check();
  const cv::Mat gray = ToGray8(image, "ExtractFeatures");
  IMUMATCH_CHECK(mask.empty() || (mask.type() == CV_8UC1 && mask.size() == gray.size()),
                 "ExtractFeatures: the mask must be empty or 8-bit single-channel of the image's "
                 "size ("
                     << gray.cols << "x" << gray.rows << "), not " << mask.cols << "x" << mask.rows
                     << " of type " << mask.type());
  // cv::SIFT caps its keypoints before it applies a mask: with one, it detects without its cap
  // and the strongest are kept here, as for the kinds without a built-in cap.
  const bool sift_masked = options.kind == DetectorKind::kSift && !mask.empty();
  const bool cap_here =
      sift_masked || options.kind == DetectorKind::kAkaze || options.kind == DetectorKind::kBrisk;
  cv::Ptr<cv::Feature2D> feature2d =
      sift_masked ? CreateSift(options, 0) : CreateFeature2D(options);
  Features out;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  try {
    if (cap_here) {
      // Keep the strongest detections, then describe only those.
      feature2d->detect(gray, keypoints, mask);
      std::stable_sort(keypoints.begin(), keypoints.end(), ResponseGreater);
      if (static_cast<int>(keypoints.size()) > options.max_keypoints) {
        keypoints.resize(options.max_keypoints);
      }
      feature2d->compute(gray, keypoints, descriptors);
    } else if (options.kind == DetectorKind::kOrb && options.threads >= 2 &&
               options.orb_n_levels >= 2) {
      DetectAndComputeOrbSplit(gray, ToOrbSplitParams(options), &keypoints, &descriptors, mask);
    } else {
      feature2d->detectAndCompute(gray, mask, keypoints, descriptors);
    }
  } catch (const cv::Exception& e) {
    // OpenCV's detectors assert on some inputs (e.g. images smaller than their pyramid needs).
    throw InvalidArgument("ExtractFeatures: " + ToString(options.kind) + " failed on a " +
                          std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                          " image: " + e.what());
  }
  if (keypoints.empty() || descriptors.rows != static_cast<int>(keypoints.size())) {
    if (!keypoints.empty()) {
      throw Error("ExtractFeatures: " + ToString(options.kind) + " returned " +
                  std::to_string(descriptors.rows) + " descriptors for " +
                  std::to_string(keypoints.size()) + " keypoints");
    }
    out.descriptors = cv::Mat(0, feature2d->descriptorSize(), feature2d->descriptorType());
    return out;
  }
  return StrongestFirst(keypoints, descriptors, options.max_keypoints);
}

OrbSplitParams ToOrbSplitParams(const FeatureOptions& options) {
  OrbSplitParams p;
  p.max_keypoints = options.max_keypoints;
  p.scale_factor = static_cast<float>(options.orb_scale_factor);
  p.n_levels = options.orb_n_levels;
  p.fast_threshold = options.orb_fast_threshold;
  return p;
}

Features StrongestFirst(const std::vector<cv::KeyPoint>& keypoints, const cv::Mat& descriptors,
                        int max_keypoints) {
  IMUMATCH_CHECK(descriptors.rows == static_cast<int>(keypoints.size()),
                 descriptors.rows << " descriptors for " << keypoints.size() << " keypoints");
  IMUMATCH_CHECK(max_keypoints >= 0, "max_keypoints = " << max_keypoints);
  std::vector<int> order(keypoints.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&keypoints](int a, int b) {
    return keypoints[a].response > keypoints[b].response;
  });
  if (static_cast<int>(order.size()) > max_keypoints) order.resize(max_keypoints);
  Features out;
  out.keypoints.reserve(order.size());
  out.descriptors.create(static_cast<int>(order.size()), descriptors.cols, descriptors.type());
  for (size_t i = 0; i < order.size(); ++i) {
    out.keypoints.push_back(keypoints[order[i]]);
    descriptors.row(order[i]).copyTo(out.descriptors.row(static_cast<int>(i)));
  }
  return out;
}

}  // namespace imumatch
